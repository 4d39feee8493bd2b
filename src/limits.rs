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

/// Line, column and reason of a `serde_json` error, the reason without the
/// `" at line L column C"` that its `Display` appends (so that a message says them once).
/// Line and column are 1-based; both are 0 when serde_json does not know them.
pub fn json_error_parts(e: &serde_json::Error) -> (usize, usize, String) {
    let (line, column) = (e.line(), e.column());
    let full = e.to_string();
    let suffix = format!(" at line {line} column {column}");
    let reason = full.strip_suffix(&suffix).unwrap_or(&full).to_string();
    (line, column, reason)
}

/// `"line L, column C: reason"` for a `serde_json` error (only the reason when serde_json
/// does not know the place).
pub fn json_error_message(e: &serde_json::Error) -> String {
    match json_error_parts(e) {
        (0, _, reason) => reason,
        (line, column, reason) => format!("line {line}, column {column}: {reason}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_place_is_said_once() {
        let e = serde_json::from_str::<serde_json::Value>("{\n  \"a\": }").unwrap_err();
        let m = json_error_message(&e);
        assert_eq!(m, "line 2, column 8: expected value");
        assert_eq!(m.matches("line").count(), 1);
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
