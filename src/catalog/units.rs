//! Do the positions of a catalogue look like the unit its header says?
//!
//! Two mistakes are common: a catalogue of arcsec offsets without its `#REFERENCE 3` line
//! (read as absolute degrees, its rows spread over tens of degrees), and a catalogue of
//! absolute degrees under a `#REFERENCE 3 ra0 dec0` header (its "offsets" all equal `ra0`,
//! `dec0` to within a fraction of a unit). One lensing field spans well under a degree, so:
//! a row more than [`FIELD_ERROR_DEG`] from the field's centre is an error, more than
//! [`FIELD_WARN_DEG`] a warning; relative positions that all sit within
//! [`DEGREE_LOOKALIKE`] of `(ra0, dec0)` are an error (a warning for a single row).

use glam::DVec2;

use super::frame::{mean_position, Coords};
use super::rows::Row;
use super::{CatalogError, CatalogWarning};
use crate::sky::SkyReference;

/// Rows farther than this from the field's centre (degrees) get a warning: even wide-field
/// member catalogues (Subaru, HSC) reach under 1 deg from the cluster.
pub const FIELD_WARN_DEG: f64 = 1.0;
/// Rows farther than this from the field's centre (degrees) cannot be one lensing field.
pub const FIELD_ERROR_DEG: f64 = 5.0;
/// Relative positions (arcsec) all within this of the numbers `(ra0, dec0)` are degrees: as
/// arcsec they would put every image inside one arcsec at exactly the offset `(ra0, dec0)`.
pub const DEGREE_LOOKALIKE: f64 = 0.5;

/// One row's position as read (`raw`, in the header's unit) and as written.
pub(super) struct RowPosition<'a> {
    pub(super) line: usize,
    pub(super) raw: DVec2,
    pub(super) text: [&'a str; 2],
}

impl<'a> RowPosition<'a> {
    /// The position of `row` (fields 1 and 2, the layout of both Lenstool catalogues), read as
    /// `raw`.
    pub(super) fn of(row: &Row<'a>, raw: DVec2) -> Self {
        Self {
            line: row.line,
            raw,
            text: [row.fields[1], row.fields[2]],
        }
    }
}

/// Checks that the positions fit one lensing field in the unit of `coords` (module docs).
pub(super) fn check_field(
    coords: Coords,
    rows: &[RowPosition<'_>],
    source_name: &str,
    warnings: &mut Vec<CatalogWarning>,
) -> Result<(), CatalogError> {
    let names = coords.column_names();
    let Some(first) = rows.first() else {
        return Ok(());
    };
    if let Coords::RelativeArcsec { reference } = coords {
        let r = DVec2::new(reference.ra_deg, reference.dec_deg);
        let lookalike = |p: &RowPosition| {
            let ra = DVec2::new(
                (p.raw.x - r.x + 180.0).rem_euclid(360.0) - 180.0,
                p.raw.y - r.y,
            );
            ra.abs().max_element() <= DEGREE_LOOKALIKE
        };
        if rows.iter().all(lookalike) {
            let reason =
                format!(
                "(with {} '{}') looks like a position in degrees: {} within {DEGREE_LOOKALIKE} \
                 of the header's RA0 = {}, Dec0 = {}, but '#REFERENCE 1' or '3' means arcsec \
                 offsets from them; a catalogue in degrees needs '#REFERENCE 0'",
                names[1],
                first.text[1],
                if rows.len() == 1 { "the only row is" } else { "every row is" },
                r.x,
                r.y
            );
            if rows.len() > 1 {
                return Err(bad_value(source_name, first, 0, names[0], reason));
            }
            warn(warnings, source_name, first, names[0], reason);
        }
    }
    let (distance_deg, centre): (Box<dyn Fn(DVec2) -> f64>, String) = match coords {
        Coords::RelativeArcsec { .. } => (
            Box::new(|p: DVec2| p.x.hypot(p.y) / 3600.0),
            "the header's reference point (ra0, dec0)".into(),
        ),
        Coords::AbsoluteDeg { header } => {
            let (c, what) = match header {
                Some(c) => (c, "the header's reference"),
                None => {
                    let raw: Vec<DVec2> = rows.iter().map(|r| r.raw).collect();
                    (mean_position(&raw), "the mean position")
                }
            };
            (
                Box::new(move |p: DVec2| angular_distance_deg(c, p.x, p.y)),
                format!("{what} (RA {:.6}, Dec {:.6} deg)", c.ra_deg, c.dec_deg),
            )
        }
    };
    let (far, d) = rows
        .iter()
        .map(|r| (r, distance_deg(r.raw)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((first, 0.0));
    if d <= FIELD_WARN_DEG {
        return Ok(());
    }
    let hint = match coords {
        Coords::AbsoluteDeg { .. } => {
            "without a '#REFERENCE' header, or with '#REFERENCE 0', positions are absolute \
             degrees; arcsec offsets need '#REFERENCE 3 ra0 dec0'"
        }
        Coords::RelativeArcsec { .. } => "positions under '#REFERENCE 1' or '3' are arcsec",
    };
    let distance = match d < 1e6 {
        true => format!("{d:.3}"),
        false => format!("{d:.3e}"),
    };
    let reason = format!(
        "(with {} '{}') is {distance} deg from {centre}; one lensing field spans well under \
         {FIELD_WARN_DEG} deg ({hint})",
        names[1], far.text[1]
    );
    if d > FIELD_ERROR_DEG {
        return Err(bad_value(source_name, far, 0, names[0], reason));
    }
    warn(warnings, source_name, far, names[0], reason);
    Ok(())
}

/// Great-circle distance in degrees between `c` and `(ra, dec)` in degrees (haversine).
fn angular_distance_deg(c: SkyReference, ra_deg: f64, dec_deg: f64) -> f64 {
    let (d1, d2) = (c.dec_deg.to_radians(), dec_deg.to_radians());
    let h = ((d2 - d1) / 2.0).sin().powi(2)
        + d1.cos() * d2.cos() * ((ra_deg - c.ra_deg).to_radians() / 2.0).sin().powi(2);
    2.0 * h.sqrt().min(1.0).asin().to_degrees()
}

fn bad_value(
    source_name: &str,
    row: &RowPosition<'_>,
    k: usize,
    name: &'static str,
    reason: String,
) -> CatalogError {
    CatalogError::BadValue {
        source_name: source_name.into(),
        line: row.line,
        column: 2 + k,
        column_name: name,
        value: row.text[k].into(),
        reason,
    }
}

fn warn(
    warnings: &mut Vec<CatalogWarning>,
    source_name: &str,
    row: &RowPosition<'_>,
    name: &'static str,
    reason: String,
) {
    warnings.push(CatalogWarning {
        source_name: source_name.into(),
        line: row.line,
        message: format!("column 2 ({name}): '{}' {reason}", row.text[0]),
    });
}
