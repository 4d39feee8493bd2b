//! Rows of a Lenstool catalogue: splitting the text into rows after the `#REFERENCE` header,
//! and reading fields with errors that name the file, line, column and value.

use std::collections::HashMap;

use glam::DVec2;

use super::frame::{self, Coords};
use super::{CatalogError, CatalogWarning};
use crate::limits::{InputKind, TooLarge, MAX_CATALOG_ROWS};

/// Columns of both formats: the required ones, then one optional.
pub(super) const REQUIRED_COLUMNS: usize = 7;
pub(super) const ALL_COLUMNS: usize = 8;

/// One data row: its 1-based line and whitespace-separated fields.
pub(super) struct Row<'a> {
    pub(super) line: usize,
    pub(super) fields: Vec<&'a str>,
}

/// The rows of a catalogue and how to read their positions.
pub(super) struct Table<'a> {
    pub(super) coords: Coords,
    /// Whether the text has a `#REFERENCE` header (`coords` is then the header's).
    pub(super) has_header: bool,
    pub(super) rows: Vec<Row<'a>>,
    /// `#` lines that read as rows (an id, then numbers in the required columns): rows the
    /// author commented out, e.g. a member catalogue's BCG that the `.par` models on its own.
    pub(super) commented: Vec<Row<'a>>,
}

/// Splits the text into rows, reading the `#REFERENCE` header (which must precede the rows
/// and appear once) and skipping blank and `#` lines.
pub(super) fn read_table<'a>(text: &'a str, source_name: &str) -> Result<Table<'a>, CatalogError> {
    TooLarge::check_bytes(source_name, InputKind::Catalog, text.len() as u64)?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut header: Option<(usize, Coords)> = None;
    let mut rows: Vec<Row<'a>> = Vec::new();
    let mut commented: Vec<Row<'a>> = Vec::new();
    let mut lines = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        lines = line;
        let t = raw.trim();
        if t.is_empty() {
            continue;
        }
        if !t.starts_with('#') {
            if rows.len() == MAX_CATALOG_ROWS {
                let n = rows.len() as u64 + 1;
                let max = MAX_CATALOG_ROWS as u64;
                TooLarge::check(source_name, "rows", n, max, "a catalogue")?;
            }
            rows.push(Row {
                line,
                fields: t.split_whitespace().collect(),
            });
            continue;
        }
        if !frame::is_reference_header(t) {
            if let Some(fields) = commented_row(t) {
                if commented.len() < MAX_CATALOG_ROWS {
                    commented.push(Row { line, fields });
                }
            }
            continue;
        }
        let misplaced = |reason: String| CatalogError::BadReference {
            source_name: source_name.into(),
            line,
            text: t.into(),
            reason,
        };
        if let Some((first, _)) = header {
            return Err(misplaced(format!(
                "a second #REFERENCE header (the first is on line {first})"
            )));
        }
        if let Some(first_row) = rows.first() {
            return Err(misplaced(format!(
                "#REFERENCE must come before the first row (line {})",
                first_row.line
            )));
        }
        header = Some((line, frame::parse_reference_header(t, line, source_name)?));
    }
    if rows.is_empty() {
        return Err(CatalogError::Empty {
            source_name: source_name.into(),
            lines,
        });
    }
    let coords = header.map_or(Coords::AbsoluteDeg { header: None }, |(_, c)| c);
    Ok(Table {
        coords,
        has_header: header.is_some(),
        rows,
        commented,
    })
}

/// The fields of a `#` line that reads as a row: at least the required columns, the ones
/// after the id finite numbers (so a column header such as `#(string name) X Y ...` is not).
fn commented_row(line: &str) -> Option<Vec<&str>> {
    let fields: Vec<&str> = line.trim_start_matches('#').split_whitespace().collect();
    let numeric = |f: &&str| f.parse::<f64>().is_ok_and(f64::is_finite);
    (fields.len() >= REQUIRED_COLUMNS && fields[1..REQUIRED_COLUMNS].iter().all(numeric))
        .then_some(fields)
}

/// Characters of a short row a message quotes.
const ROW_SHOWN_CHARS: usize = 60;

/// First words of a Lenstool `.par`'s lines (block names in French and English, and the
/// keywords of its first block): a row starting so is a parameter file read as a catalogue.
const PAR_WORDS: &str = "runmode reference potentiel potential potfile limit image grille grid \
                         source champ field cosmologie cosmology fini finish";

/// Position (as written) and ellipse of one row.
pub(super) struct Shape {
    pub(super) raw: DVec2,
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) theta: f64,
}

/// Reads the fields of one row, with errors naming the file, line, column and value.
pub(super) struct Fields<'r, 'a> {
    pub(super) row: &'r Row<'a>,
    pub(super) names: &'r [&'static str; ALL_COLUMNS],
    pub(super) source_name: &'r str,
}

impl Fields<'_, '_> {
    pub(super) fn bad(&self, i: usize, reason: impl Into<String>) -> CatalogError {
        CatalogError::BadValue {
            source_name: self.source_name.into(),
            line: self.row.line,
            column: i + 1,
            column_name: self.names[i],
            value: self.row.fields[i].into(),
            reason: reason.into(),
        }
    }

    /// At least the required columns; rows with more than all columns are noted in `extra`.
    pub(super) fn require(
        &self,
        layout: &'static str,
        extra: &mut Vec<usize>,
    ) -> Result<(), CatalogError> {
        let found = self.row.fields.len();
        if found < REQUIRED_COLUMNS {
            let row = self.row.fields.join(" ");
            let row = match row.char_indices().nth(ROW_SHOWN_CHARS) {
                Some((at, _)) => format!("{}...", &row[..at]),
                None => row,
            };
            let first = self.row.fields.first().map(|f| f.to_ascii_lowercase());
            return Err(CatalogError::MissingColumns {
                source_name: self.source_name.into(),
                line: self.row.line,
                row,
                found,
                needed: REQUIRED_COLUMNS,
                expected: layout,
                lenstool_par: first.is_some_and(|f| PAR_WORDS.split(' ').any(|w| w == f)),
            });
        }
        if found > ALL_COLUMNS {
            extra.push(self.row.line);
        }
        Ok(())
    }

    /// A finite number in column `i` (0-based).
    pub(super) fn number(&self, i: usize) -> Result<f64, CatalogError> {
        match self.row.fields[i].parse::<f64>() {
            Err(_) => Err(self.bad(i, "is not a number")),
            Ok(v)
                if v.is_infinite() && !self.row.fields[i].to_ascii_lowercase().contains("inf") =>
            {
                Err(self.bad(i, "is out of range (it overflows a 64-bit float)"))
            }
            Ok(v) if !v.is_finite() => Err(self.bad(i, "is not a finite number")),
            Ok(v) => Ok(v),
        }
    }

    /// Column `i` when present, else 0.
    pub(super) fn optional(&self, i: usize) -> Result<f64, CatalogError> {
        if i < self.row.fields.len() {
            self.number(i)
        } else {
            Ok(0.0)
        }
    }

    /// Columns 2-6: position (checked for `coords`), `a >= 0`, `b >= 0` arcsec, `theta` deg.
    pub(super) fn shape(&self, coords: Coords) -> Result<Shape, CatalogError> {
        let raw = DVec2::new(self.number(1)?, self.number(2)?);
        coords
            .check(raw)
            .map_err(|(k, reason)| self.bad(1 + k, reason))?;
        let mut axes = [0.0; 2];
        for (k, axis) in axes.iter_mut().enumerate() {
            *axis = self.number(3 + k)?;
            if *axis < 0.0 {
                return Err(self.bad(3 + k, "is negative: ellipse semi-axes must be >= 0 arcsec"));
            }
        }
        let theta = self.number(5)?;
        Ok(Shape {
            raw,
            a: axes[0],
            b: axes[1],
            theta,
        })
    }

    /// Column `i` as a source redshift: 0 is unknown (`None`), otherwise it must be > 0.
    pub(super) fn redshift(&self, i: usize) -> Result<Option<f64>, CatalogError> {
        let z = self.number(i)?;
        if z == 0.0 {
            Ok(None)
        } else if z < 0.0 {
            Err(self.bad(i, "is negative: z must be > 0, or exactly 0 for unknown"))
        } else {
            Ok(Some(z))
        }
    }

    /// The system part of an image id ([`super::system_of_image`]), and whether it is the id
    /// but its last character (not the text before a `.` and a number).
    pub(super) fn system_id(&self) -> Result<(String, bool), CatalogError> {
        let id = self.row.fields[0];
        match (super::lenstool::system_and_rule(id), id.split_once('.')) {
            (Some((system, by_last)), _) => Ok((system.into(), by_last)),
            (None, Some(("", _))) => Err(self.bad(0, "has no system part before the '.'")),
            (None, Some(_)) => Err(self.bad(0, "has no image part after the '.'")),
            (None, None) => Err(self.bad(
                0,
                "is not an image id: name an image by its system and then the image, as '4.2' \
                 or '4b'",
            )),
        }
    }
}

/// Records `id` as seen on `line`; a warning when an earlier row used it (`what`: "member",
/// "arclet", the kind of row), which says that both rows are kept.
pub(super) fn warn_repeated_id<'t>(
    seen: &mut HashMap<&'t str, usize>,
    id: &'t str,
    line: usize,
    what: &str,
    source_name: &str,
    warnings: &mut Vec<CatalogWarning>,
) {
    if let Some(first_line) = seen.insert(id, line) {
        warnings.push(CatalogWarning {
            source_name: source_name.into(),
            line,
            message: format!(
                "{what} id '{id}' is already used on line {first_line}: both rows are used (ids \
                 only name rows in messages)"
            ),
        });
    }
}

/// One warning for all rows with more columns than the format has.
pub(super) fn warn_extra_columns(
    lines: &[usize],
    source_name: &str,
    warnings: &mut Vec<CatalogWarning>,
) {
    if let Some(&first) = lines.first() {
        warnings.push(CatalogWarning {
            source_name: source_name.into(),
            line: first,
            message: format!(
                "{} row(s) have more than {ALL_COLUMNS} columns; the extra columns are ignored",
                lines.len()
            ),
        });
    }
}
