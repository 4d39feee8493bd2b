//! Lenstool arclet catalogues: the shapes of weakly lensed background galaxies, rows
//! `id x y a b theta z`, read with the same `#REFERENCE` rules and frame as the image and
//! member catalogues ([`super::parse_image_catalog`]).
//!
//! Each galaxy's complex ellipticity is `e = (a - b) / (a + b) exp(2 i theta)`, with `theta`
//! in degrees counter-clockwise from +x, the convention of the image catalogues' ellipses
//! ([`super::Image::theta_deg`]). Lenstool's own code agrees on the angle: its `st_opt.c`
//! (J.-P. Kneib) writes `E.theta * RTD` (degrees) and orients shapes by
//! `(cos 2 theta, sin 2 theta)` in the frame of the positions (+x West, +y North here); there
//! it measures ellipticity as `(a^2 - b^2) / (a^2 + b^2)`, whereas `(a - b) / (a + b)` is used
//! here because for a source of random orientation its expectation is the reduced shear
//! `g = gamma / (1 - kappa)` at the galaxy (for `|g| < 1`; Seitz & Schneider 1997), the
//! estimator the weak-lensing rows of the linear system need (`crate::inversion`'s `shear`
//! module).

use std::collections::HashMap;

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::frame;
use super::rows::{read_table, warn_extra_columns, warn_repeated_id, Fields};
use super::units::{check_field, RowPosition};
use super::{reframe_pair, CatalogError, CatalogWarning};
use crate::sky::SkyReference;

const ARCLET_LAYOUT: &str = "id x y a b theta z";

/// One background galaxy of an arclet catalogue.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Arclet {
    pub id: String,
    /// Position in arcsec in the catalogue's frame.
    pub position: DVec2,
    /// Semi-axes in arcsec and position angle in degrees counter-clockwise from +x.
    pub a_arcsec: f64,
    pub b_arcsec: f64,
    pub theta_deg: f64,
    /// Source redshift (> 0).
    pub z: f64,
    /// Complex ellipticity `(e1, e2)` ([`arclet_ellipticity`]).
    pub ellipticity: DVec2,
    /// 1-based line of the catalogue it came from (for messages).
    pub line: usize,
}

/// A parsed arclet catalogue.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArcletCatalog {
    /// File name, for messages.
    pub source_name: String,
    /// The frame's sky origin (as for [`super::ImageCatalog::reference`]).
    pub reference: Option<SkyReference>,
    pub arclets: Vec<Arclet>,
}

impl ArcletCatalog {
    /// The catalogue in the arcsec frame of `to` (see [`super::ImageCatalog::reframed`]).
    pub fn reframed(mut self, to: SkyReference) -> Result<Self, CatalogError> {
        let (from, to) = reframe_pair(self.reference, to, &self.source_name)?;
        for g in &mut self.arclets {
            g.position = frame::reframe(g.position, from, to);
        }
        self.reference = Some(to);
        Ok(self)
    }
}

/// The complex ellipticity `(a - b) / (a + b) * (cos 2 theta, sin 2 theta)` of an ellipse of
/// semi-axes `a`, `b` (any unit, `a + b > 0`) at position angle `theta_deg` degrees
/// counter-clockwise from +x. Dimensionless; `|e| <= 1`.
pub fn arclet_ellipticity(a: f64, b: f64, theta_deg: f64) -> DVec2 {
    let modulus = (a - b) / (a + b);
    let two_theta = 2.0 * theta_deg.to_radians();
    modulus * DVec2::new(two_theta.cos(), two_theta.sin())
}

/// Why an arclet row with `z = 0` is refused when no `.par` is given, and what to do.
const UNKNOWN_Z: &str = "is 0 (unknown): an arclet needs its redshift (> 0). Lenstool gives \
                         unknown ones the z_source of the .par's `source` block: give that \
                         .par with the catalogue (--par, or the app's model file), or write a \
                         redshift in this column (a photometric one, or the background's median)";

/// What an arclet row with `z = 0` (unknown) gets: Lenstool gives it the redshift of its
/// `.par`'s `source` block (`crate::LenstoolPar::unknown_source_z`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum ArcletUnknownZ<'a> {
    /// Refused: no `.par` says (the message says what to do).
    #[default]
    Refuse,
    /// Refused for this reason of the `.par`'s (a distribution of redshifts, a bad `z_source`).
    RefuseBecause(&'a str),
    /// Put at `z`; `origin` says where it comes from, in the reader's warning.
    Take { z: f64, origin: &'a str },
}

/// Parses a Lenstool arclet catalogue: rows `id x y a b theta z`.
///
/// Same `#REFERENCE` rules and frame as [`super::parse_image_catalog`]: positions end in the
/// arcsec frame (+x West, +y North) of `reference` when given, else of the header's. `a`, `b`
/// arcsec (>= 0, not both 0), `theta` degrees, `z` the galaxy's redshift (> 0: a weak-lensing
/// row needs its distance ratio; a row with 0, unknown, is refused here, and takes a `.par`'s
/// redshift with [`parse_arclet_catalog_with`]). Ids are free text; a repeated id is a
/// warning, and so are extra columns (ignored).
pub fn parse_arclet_catalog(
    text: &str,
    source_name: &str,
    reference: Option<SkyReference>,
) -> Result<(ArcletCatalog, Vec<CatalogWarning>), CatalogError> {
    parse_arclet_catalog_with(text, source_name, reference, ArcletUnknownZ::Refuse)
}

/// [`parse_arclet_catalog`], with rows of `z = 0` given what `unknown_z` says (one warning
/// names how many took it, and from where).
pub fn parse_arclet_catalog_with(
    text: &str,
    source_name: &str,
    reference: Option<SkyReference>,
    unknown_z: ArcletUnknownZ<'_>,
) -> Result<(ArcletCatalog, Vec<CatalogWarning>), CatalogError> {
    let requested = frame::check_requested(reference, source_name)?;
    let table = read_table(text, source_name)?;
    let [c0, c1] = table.coords.column_names();
    let names = ["id", c0, c1, "a", "b", "theta", "z", "extra"];
    let mut warnings = Vec::new();
    let mut extra_lines = Vec::new();
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let mut arclets = Vec::with_capacity(table.rows.len());
    let mut positions = Vec::with_capacity(table.rows.len());
    // The first row without a redshift, and how many there are.
    let mut unknown: Option<(usize, usize)> = None;
    for row in &table.rows {
        let f = Fields {
            row,
            names: &names,
            source_name,
        };
        f.require(ARCLET_LAYOUT, &mut extra_lines)?;
        let id = row.fields[0];
        warn_repeated_id(
            &mut seen,
            id,
            row.line,
            "arclet",
            source_name,
            &mut warnings,
        );
        let shape = f.shape(table.coords)?;
        if shape.a + shape.b <= 0.0 {
            return Err(f.bad(4, "is 0 as is a: an arclet needs a shape (a + b > 0)"));
        }
        let z = match (f.redshift(6)?, unknown_z) {
            (Some(z), _) => z,
            (None, ArcletUnknownZ::Take { z, .. }) => {
                let first = unknown.get_or_insert((row.line, 0));
                first.1 += 1;
                z
            }
            (None, ArcletUnknownZ::RefuseBecause(why)) => {
                return Err(f.bad(
                    6,
                    format!(
                        "is 0 (unknown): {why}; write each arclet's redshift in this column \
                         (a photometric one, or the background's median)"
                    ),
                ))
            }
            (None, ArcletUnknownZ::Refuse) => return Err(f.bad(6, UNKNOWN_Z)),
        };
        positions.push(RowPosition::of(row, shape.raw));
        arclets.push(Arclet {
            id: id.into(),
            position: shape.raw,
            a_arcsec: shape.a,
            b_arcsec: shape.b,
            theta_deg: shape.theta,
            z,
            ellipticity: arclet_ellipticity(shape.a, shape.b, shape.theta),
            line: row.line,
        });
    }
    warn_extra_columns(&extra_lines, source_name, &mut warnings);
    if let (Some((line, n)), ArcletUnknownZ::Take { z, origin }) = (unknown, unknown_z) {
        let rows = if n == 1 { "arclet" } else { "arclets" };
        warnings.push(CatalogWarning {
            source_name: source_name.into(),
            line,
            message: format!(
                "{n} {rows} without a redshift (z = 0) put at z = {z}, as Lenstool does: {origin}"
            ),
        });
    }
    check_field(table.coords, &positions, source_name, &mut warnings)?;
    let raw: Vec<DVec2> = arclets.iter().map(|g| g.position).collect();
    let (frame_ref, positions) = table.coords.into_frame(&raw, requested);
    for (g, p) in arclets.iter_mut().zip(positions) {
        g.position = p;
    }
    let catalog = ArcletCatalog {
        source_name: source_name.into(),
        reference: Some(frame_ref),
        arclets,
    };
    Ok((catalog, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-computed: a = 3, b = 1, theta = 30 deg gives |e| = 2/4 = 0.5 and
    /// 2 theta = 60 deg: e = 0.5 (cos 60, sin 60) = (0.25, 0.4330127).
    #[test]
    fn ellipticity_follows_the_lenstool_convention() {
        let text = "#REFERENCE 3 150.0 2.0\n\
                    # id x y a b theta z\n\
                    7 12.5 -40.0 3.0 1.0 30.0 1.2\n\
                    8 0.0 0.0 1.0 3.0 0.0 0.9\n";
        let (cat, warnings) = parse_arclet_catalog(text, "arclets.cat", None).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let g = &cat.arclets[0];
        assert_eq!((g.id.as_str(), g.line, g.z), ("7", 3, 1.2));
        assert!((g.position - DVec2::new(12.5, -40.0)).length() < 1e-9);
        assert!((g.ellipticity.x - 0.25).abs() < 1e-12);
        assert!((g.ellipticity.y - 0.75f64.sqrt() / 2.0).abs() < 1e-12);
        // b > a is the same ellipse turned by 90 degrees: e = (-0.5, 0).
        let h = cat.arclets[1].ellipticity;
        assert!((h - DVec2::new(-0.5, 0.0)).length() < 1e-12, "{h}");
    }

    #[test]
    fn bad_rows_name_file_line_column_and_value() {
        let cases = [
            (
                "1 0 0 1 0.5 10 abc\n",
                "line 2, column 7 (z): 'abc' is not a number",
            ),
            (
                "1 0 0 1 0.5 10 0\n",
                "line 2, column 7 (z): '0' is 0 (unknown): an arclet needs its redshift (> 0). \
                 Lenstool gives unknown ones the z_source of the .par's `source` block: give \
                 that .par with the catalogue",
            ),
            ("1 0 0 0 0 10 1\n", "line 2, column 5 (b): '0' is 0 as is a"),
            (
                "1 0 0 -1 0.5 10 1\n",
                "line 2, column 4 (a): '-1' is negative",
            ),
            (
                "1 0 0 1 0.5\n",
                "line 2: '1 0 0 1 0.5': 5 column(s) found, at least 7 needed",
            ),
        ];
        for (row, expected) in cases {
            let text = format!("#REFERENCE 3 150.0 2.0\n{row}");
            let err = parse_arclet_catalog(&text, "wl.cat", None).unwrap_err();
            let message = err.to_string();
            assert!(
                message.starts_with("wl.cat: ") && message.contains(expected),
                "{message}"
            );
        }
    }
}
