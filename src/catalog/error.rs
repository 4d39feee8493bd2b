//! What can go wrong reading a catalogue, and what is only worth a warning.
//!
//! Every message starts with the file name given by the caller and names the line, and where
//! one value is at fault its 1-based column, the column's name and the text as written.

use std::fmt;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Said of a Lenstool parameter file given where a catalogue is wanted.
const PAR_HINT: &str = "; this is a Lenstool parameter file (.par), not a catalogue: load it as \
                        the model file in the app, or give it with --par";

/// A catalogue that cannot be used as written.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CatalogError {
    /// No data rows: an empty file, or only blank and comment lines.
    #[error(
        "{source_name}: no catalogue rows in {lines} line(s) (only blank lines and # comments)"
    )]
    Empty { source_name: String, lines: usize },

    /// A member catalogue whose every row has a "no measurement" magnitude
    /// ([`crate::MAG_NO_MEASUREMENT`]): no member is left.
    #[error(
        "{source_name}: all {rows} member row(s) have a no-measurement magnitude (|mag| >= 90, \
         e.g. 99, or nan): no member to use"
    )]
    NoMeasuredMembers { source_name: String, rows: usize },

    /// A row with fewer columns than the format needs.
    #[error(
        "{source_name}: line {line}: '{row}': {found} column(s) found, at least {needed} needed \
         ({expected}){hint}",
        hint = if *lenstool_par { PAR_HINT } else { "" }
    )]
    MissingColumns {
        source_name: String,
        line: usize,
        /// The row as written (its fields joined by one space, shortened past 60 characters).
        row: String,
        found: usize,
        needed: usize,
        /// The column layout, e.g. `"id x y a b theta z [mag]"`.
        expected: &'static str,
        /// The row is a Lenstool `.par` block or keyword (`runmode`, `potentiel`, ...): the
        /// file is a parameter file given as a catalogue.
        lenstool_par: bool,
    },

    /// One field that is not a usable value: not a number, NaN/inf, out of range, a bad id.
    #[error("{source_name}: line {line}, column {column} ({column_name}): '{value}' {reason}")]
    BadValue {
        source_name: String,
        line: usize,
        /// 1-based column number.
        column: usize,
        column_name: &'static str,
        /// The field as written.
        value: String,
        /// Why it is rejected, e.g. `"is not a number"`.
        reason: String,
    },

    /// The same image id on two rows.
    #[error("{source_name}: line {line}: image id '{id}' is already used on line {first_line}")]
    DuplicateId {
        source_name: String,
        id: String,
        first_line: usize,
        line: usize,
    },

    /// A catalogue whose 7th column says it is the other kind: magnitudes in an image
    /// catalogue (its redshift column), or redshifts in a member catalogue (its magnitudes).
    #[error(
        "{source_name}: column 7 ({}) holds {} to {} on {rows} rows (line {line}: {value}), \
         which read as {}: this looks like {} ({}), not {}",
        .read_as.column(), crate::error::number(*.low), crate::error::number(*.high),
        .read_as.other_values(), .read_as.other().name(), .read_as.other().layout(),
        .read_as.name()
    )]
    OtherKind {
        source_name: String,
        /// What the file was read as.
        read_as: CatalogKind,
        /// The column's least and greatest value, and on how many rows it was read.
        low: f64,
        high: f64,
        rows: usize,
        /// The first row with such a value, and that value as written.
        line: usize,
        value: String,
    },

    /// Two images of one system whose redshifts differ by more than the agreement tolerance.
    #[error(
        "{source_name}: system '{system}': line {line_a} gives z = {z_a} but line {line_b} gives \
         z = {z_b}; images of one source must agree within {tolerance} (1 + z)"
    )]
    InconsistentRedshift {
        source_name: String,
        system: String,
        line_a: usize,
        z_a: f64,
        line_b: usize,
        z_b: f64,
        /// The relative tolerance on `Δz / (1 + z)`.
        tolerance: f64,
    },

    /// A `#REFERENCE` header that cannot be read.
    #[error("{source_name}: line {line}: bad header '{text}': {reason}")]
    BadReference {
        source_name: String,
        line: usize,
        text: String,
        reason: String,
    },

    /// A `#REFERENCE` mode this reader does not convert.
    #[error("{source_name}: line {line}: unsupported REFERENCE mode {mode}: {reason}")]
    UnsupportedReference {
        source_name: String,
        line: usize,
        mode: String,
        reason: String,
    },

    /// The sky reference asked for by the caller cannot define a frame.
    #[error(
        "{source_name}: requested sky reference (RA {ra_deg} deg, Dec {dec_deg} deg) is not \
         usable: RA and Dec must be finite and |Dec| < 90 deg"
    )]
    InvalidReference {
        source_name: String,
        ra_deg: f64,
        dec_deg: f64,
    },

    /// A catalogue without a sky reference cannot be moved to another frame.
    #[error("{source_name}: the catalogue has no sky reference, so it cannot change frame")]
    NoReference { source_name: String },

    /// A text over [`crate::limits::MAX_CATALOG_BYTES`] or with more rows than
    /// [`crate::limits::MAX_CATALOG_ROWS`].
    #[error(transparent)]
    TooLarge(#[from] crate::limits::TooLarge),

    /// A default source redshift that is not finite and positive.
    #[error("{source_name}: default source redshift {z} must be finite and > 0")]
    BadDefaultRedshift { source_name: String, z: f64 },
}

/// Something legal but worth telling the user (the caller decides what to do with it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CatalogWarning {
    /// File name, as given by the caller.
    pub source_name: String,
    /// 1-based line the warning is about (the first one, when it concerns several).
    pub line: usize,
    pub message: String,
}

impl fmt::Display for CatalogWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: line {}: {}",
            self.source_name, self.line, self.message
        )
    }
}

/// The two kinds of Lenstool catalogue, which share their first six columns and differ in
/// the 7th: a source redshift in an image catalogue, a magnitude in a member catalogue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CatalogKind {
    Images,
    Members,
}

impl CatalogKind {
    /// "an image catalogue" or "a member catalogue".
    pub fn name(self) -> &'static str {
        match self {
            Self::Images => "an image catalogue",
            Self::Members => "a member catalogue",
        }
    }

    /// The columns as Lenstool writes them.
    pub fn layout(self) -> &'static str {
        match self {
            Self::Images => "id x y a b theta z mag",
            Self::Members => "id x y a b theta mag lum",
        }
    }

    /// The name of the 7th column.
    pub fn column(self) -> &'static str {
        match self {
            Self::Images => "z",
            Self::Members => "mag",
        }
    }

    /// The other kind.
    pub fn other(self) -> Self {
        match self {
            Self::Images => Self::Members,
            Self::Members => Self::Images,
        }
    }

    /// What the 7th column holds when the file is of the other kind.
    fn other_values(self) -> &'static str {
        match self {
            Self::Images => "magnitudes, not source redshifts",
            Self::Members => "redshifts, not magnitudes",
        }
    }
}
