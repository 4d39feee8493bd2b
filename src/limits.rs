//! Size limits on inputs, and where a JSON error is.
//!
//! Every limit is far above any real use (the largest real catalogues are a few thousand rows,
//! HFF maps 4096 x 4096 pixels, the paper's arcs about 10^4 pixels) and well below what would
//! exhaust memory, so that a wrong or corrupt file (a 2 GB log given as a catalogue, a FITS
//! header claiming 10^6 x 10^6 pixels) is refused at once with a message naming the file, its
//! size and the limit, before it is read into memory. The command line checks a file's size
//! before reading it; the parsers, which also take texts from the browser app, check again.

use thiserror::Error;

/// Largest catalogue (Lenstool images or members) in bytes: 64 MiB, about 10^6 rows.
pub const MAX_CATALOG_BYTES: u64 = 64 << 20;
/// Most data rows in one catalogue.
pub const MAX_CATALOG_ROWS: usize = 1_000_000;
/// Largest JSON file of settings or of a parametric model in bytes: 16 MiB (a model of 10^5
/// components is about 10 MiB).
pub const MAX_JSON_BYTES: u64 = 16 << 20;
/// Largest arcs JSON file in bytes: 128 MiB (10^6 pixels written with full precision).
pub const MAX_ARCS_BYTES: u64 = 128 << 20;
/// Most arc pixels in one arcs file, all systems together: each is two rows of the linear
/// system, so 10^6 of them are already far beyond what the solver can use.
pub const MAX_ARC_PIXELS: usize = 1_000_000;
/// Most pixels in one FITS image: 10^8 (a 10000 x 10000 map).
pub const MAX_FITS_PIXELS: usize = 100_000_000;
/// Largest FITS file in bytes: 1 GiB (10^8 double-precision pixels and their headers).
pub const MAX_FITS_BYTES: u64 = 1 << 30;

/// The kinds of input file, each with its size limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// A Lenstool image or member catalogue.
    Catalog,
    /// Settings (`CONFIG.json`).
    Config,
    /// A parametric model file.
    Model,
    /// Arc pixels (JSON).
    Arcs,
    /// A FITS image.
    Fits,
}

impl InputKind {
    /// Largest accepted file in bytes.
    pub fn max_bytes(self) -> u64 {
        match self {
            Self::Catalog => MAX_CATALOG_BYTES,
            Self::Config | Self::Model => MAX_JSON_BYTES,
            Self::Arcs => MAX_ARCS_BYTES,
            Self::Fits => MAX_FITS_BYTES,
        }
    }

    /// What the file is, for messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Catalog => "a catalogue",
            Self::Config => "a settings file",
            Self::Model => "a model file",
            Self::Arcs => "an arcs file",
            Self::Fits => "a FITS file",
        }
    }
}

/// An input over one of the limits of this module.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{source_name}: {count} {unit} is more than the limit of {limit} {unit} for {what}")]
pub struct TooLarge {
    /// File name, as given by the caller.
    pub source_name: String,
    /// What was counted: `"bytes"`, `"rows"`, `"pixels"`.
    pub unit: &'static str,
    pub count: u64,
    pub limit: u64,
    /// What the limit is for, e.g. `"a catalogue"`.
    pub what: &'static str,
}

impl TooLarge {
    /// `Err` when `count > limit`.
    pub fn check(
        source_name: &str,
        unit: &'static str,
        count: u64,
        limit: u64,
        what: &'static str,
    ) -> Result<(), Self> {
        if count <= limit {
            return Ok(());
        }
        Err(Self {
            source_name: source_name.to_string(),
            unit,
            count,
            limit,
            what,
        })
    }

    /// `Err` when a file or text of `bytes` bytes is over the limit of `kind`.
    pub fn check_bytes(source_name: &str, kind: InputKind, bytes: u64) -> Result<(), Self> {
        Self::check(source_name, "bytes", bytes, kind.max_bytes(), kind.name())
    }
}

/// Line, column and reason of a `serde_json` error in `text` (the text it parsed), the reason
/// without the `" at line L column C"` that its `Display` appends (so that a message says them
/// once), and with a hint when the value there is `NaN` or `Infinity`, which JSON does not have
/// but Python's `json.dump` writes. Line and column are 1-based; both are 0 when serde_json
/// does not know them.
pub fn json_error_parts(text: &str, e: &serde_json::Error) -> (usize, usize, String) {
    let (line, column) = (e.line(), e.column());
    let full = e.to_string();
    let suffix = format!(" at line {line} column {column}");
    let mut reason = full.strip_suffix(&suffix).unwrap_or(&full).to_string();
    if let Some(word) = non_json_number(text, line, column) {
        reason.push_str(&format!(
            ": '{word}' is not a number in JSON (Python's json.dump writes NaN and Infinity \
             for such values; leave them out)"
        ));
    }
    (line, column, reason)
}

/// The word at 1-based `line` and `column` of `text` (serde_json stops on it or just after
/// its first letters) when it is a NaN or an infinity.
fn non_json_number(text: &str, line: usize, column: usize) -> Option<&str> {
    let row = text.lines().nth(line.checked_sub(1)?)?;
    let at = column.checked_sub(1)?.min(row.len());
    // serde_json counts columns in bytes; never cut a character whatever it counts.
    if !row.is_char_boundary(at) {
        return None;
    }
    let part = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '+' | '.');
    let start = row[..at]
        .char_indices()
        .rev()
        .take_while(|&(_, c)| part(c))
        .last()
        .map_or(at, |(i, _)| i);
    let end = row[start..]
        .find(|c: char| !part(c))
        .map_or(row.len(), |k| start + k);
    let word = &row[start..end];
    let bare = word.trim_start_matches(['-', '+']).to_ascii_lowercase();
    matches!(bare.as_str(), "nan" | "inf" | "infinity").then_some(word)
}

/// `"line L, column C: reason"` for a `serde_json` error in `text` (only the reason when
/// serde_json does not know the place); see [`json_error_parts`].
pub fn json_error_message(text: &str, e: &serde_json::Error) -> String {
    match json_error_parts(text, e) {
        (0, _, reason) => reason,
        (line, column, reason) => format!("line {line}, column {column}: {reason}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_place_is_said_once() {
        let text = "{\n  \"a\": }";
        let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
        let m = json_error_message(text, &e);
        assert_eq!(m, "line 2, column 8: expected value");
        assert_eq!(m.matches("line").count(), 1);
    }

    /// NaN and infinities, as Python writes them (and as people type them), are named; other
    /// words are not.
    #[test]
    fn nan_and_infinity_are_named() {
        for (text, word) in [
            ("[1, NaN]", "NaN"),
            ("[1, -Infinity]", "-Infinity"),
            ("[1, Infinity]", "Infinity"),
            ("[1,\n  nan]", "nan"),
            ("{\"a\": -inf}", "-inf"),
            ("{\"μ\": [1, NaN]}", "NaN"),
        ] {
            let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
            let m = json_error_message(text, &e);
            assert!(
                m.contains(&format!("'{word}' is not a number in JSON")),
                "{text}: {m}"
            );
        }
        for text in ["[1, none]", "[1, 2", "[1, x]", "[\"μμμ\", x]", "[\"μ\"x]"] {
            let e = serde_json::from_str::<serde_json::Value>(text).unwrap_err();
            assert!(
                !json_error_message(text, &e).contains("not a number"),
                "{text}"
            );
        }
    }

    #[test]
    fn limits_are_checked() {
        assert!(TooLarge::check_bytes("a.cat", InputKind::Catalog, MAX_CATALOG_BYTES).is_ok());
        let e =
            TooLarge::check_bytes("a.cat", InputKind::Catalog, MAX_CATALOG_BYTES + 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.cat: 67108865 bytes is more than the limit of 67108864 bytes for a catalogue"
        );
    }
}
