//! Reading input files within the size limits of [`wslap::limits`]: a file over its limit is
//! refused from its metadata, before anything is read, with its name, size and the limit.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use wslap::{InputKind, TooLarge};

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

/// The text of `path` (UTF-8), within the limit of `kind`.
pub fn read_text(path: &Path, kind: InputKind) -> Result<String, String> {
    String::from_utf8(read_bytes(path, kind)?)
        .map_err(|e| format!("{}: not UTF-8 text: {e}", path.display()))
}
