//! Reading input files within the size limits of [`wslap::limits`]: a file over its limit is
//! refused from its metadata, before anything is read, with its name, size and the limit.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use wslap::{with_line_feeds, InputKind, TooLarge};

/// The bytes of `path`, refused when over the limit of `kind` (checked on the metadata first,
/// then while reading, for files that grow or report no size).
pub fn read_bytes(path: &Path, kind: InputKind) -> Result<Vec<u8>, String> {
    let name = path.display().to_string();
    let io = |e: std::io::Error| format!("{name}: {e}");
    let file = File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    TooLarge::check_bytes(&name, kind, size).map_err(|e| e.to_string())?;
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    file.take(kind.max_bytes() + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    TooLarge::check_bytes(&name, kind, bytes.len() as u64).map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Refuses an `--out` that names an existing file (not a folder) before any work, so that a run
/// of minutes does not end in "File exists".
pub fn check_out_dir(out: &Path) -> Result<(), String> {
    if out.exists() && !out.is_dir() {
        return Err(format!(
            "{}: --out names an existing file; give a folder for the results (it is created if \
             missing)",
            out.display()
        ));
    }
    Ok(())
}

/// The text of `path` (UTF-8, a leading byte-order mark dropped, as a browser drops it),
/// within the limit of `kind`. Text in another encoding is refused with the line of its first
/// byte that is not UTF-8.
pub fn read_text(path: &Path, kind: InputKind) -> Result<String, String> {
    let bytes = read_bytes(path, kind)?;
    text_of(&path.display().to_string(), bytes)
}

/// `bytes` as UTF-8 text for [`read_text`]; `name` is the file's name for the message.
fn text_of(name: &str, bytes: Vec<u8>) -> Result<String, String> {
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(format!(
            "{name}: the file is UTF-16 text; save it as UTF-8 (or plain ASCII) and load it again"
        ));
    }
    match String::from_utf8(bytes) {
        Ok(text) => {
            let text = match text.strip_prefix('\u{feff}') {
                Some(rest) => rest.to_string(),
                None => text,
            };
            Ok(with_line_feeds(&text).into_owned())
        }
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let bytes = e.as_bytes();
            let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
            Err(format!(
                "{name}: line {line}: byte 0x{:02X} is not UTF-8 text (the file is in another \
                 encoding, e.g. Latin-1, or is not text); save it as UTF-8 and load it again",
                bytes[at]
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::text_of;

    /// A byte-order mark is dropped; UTF-16 and Latin-1 are refused with the line, never with
    /// the bytes themselves.
    #[test]
    fn text_is_utf8_without_its_byte_order_mark() {
        let read = |b: &[u8]| text_of("f.par", b.to_vec());
        assert_eq!(read(b"\xEF\xBB\xBFrunmode\n").unwrap(), "runmode\n");
        assert_eq!(read(b"runmode\n").unwrap(), "runmode\n");
        // Lines ended by a carriage return alone are read as lines; CR LF stays as it is.
        assert_eq!(read(b"runmode\r\tend\r").unwrap(), "runmode\n\tend\n");
        assert_eq!(
            read(b"runmode\r\n\tend\r\n").unwrap(),
            "runmode\r\n\tend\r\n"
        );
        let e = read(b"\xFF\xFEr\0u\0").unwrap_err();
        assert!(e.starts_with("f.par: the file is UTF-16 text"), "{e}");
        let e = read(b"# ok\nname caf\xE9\n").unwrap_err();
        assert_eq!(
            e,
            "f.par: line 2: byte 0xE9 is not UTF-8 text (the file is in another encoding, e.g. \
             Latin-1, or is not text); save it as UTF-8 and load it again"
        );
    }
}
