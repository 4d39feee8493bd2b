//! The `#REFERENCE` header of Lenstool catalogues and the change into the caller's arcsec frame.
//!
//! Lenstool's manual defines `#REFERENCE mode [ra0 dec0]`:
//! - `0`: positions are absolute (RA, Dec) in degrees (also what a file without header means);
//! - `1`: positions in arcsec relative to `(ra0, dec0)` given in sexagesimal `hh:mm:ss dd:mm:ss`;
//! - `2`: positions in pixels relative to a reference pixel: this needs the image's WCS, which
//!   the catalogue does not carry, so it is rejected;
//! - `3`: positions in arcsec relative to `(ra0, dec0)` in degrees.
//!
//! Relative positions follow [method §1]: `x = -(RA - RA0) cos(Dec0) 3600`,
//! `y = (Dec - Dec0) 3600` (see [`SkyReference::to_offset_arcsec`]).

use glam::DVec2;

use super::CatalogError;
use crate::sky::SkyReference;

/// How the position columns of a catalogue are to be read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Coords {
    /// (RA, Dec) in degrees; the header's optional `ra0 dec0` (`#REFERENCE 0 ra0 dec0`).
    AbsoluteDeg { header: Option<SkyReference> },
    /// Arcsec offsets from `reference` (`#REFERENCE 1` or `3`).
    RelativeArcsec { reference: SkyReference },
}

impl Coords {
    /// Names of the two position columns, for messages.
    pub(crate) fn column_names(&self) -> [&'static str; 2] {
        match self {
            Coords::AbsoluteDeg { .. } => ["ra", "dec"],
            Coords::RelativeArcsec { .. } => ["x", "y"],
        }
    }

    /// Checks one position as written; on failure the 0-based index of the bad coordinate
    /// (0: first, 1: second) and why. Absolute: `RA` in `[0, 360]` deg, `|Dec| < 90` deg.
    /// Relative: the implied `Dec0 + y / 3600` must also stay within `(-90, 90)` deg.
    pub(crate) fn check(&self, raw: DVec2) -> Result<(), (usize, String)> {
        match self {
            Coords::AbsoluteDeg { .. } => {
                if !(0.0..=360.0).contains(&raw.x) {
                    return Err((
                        0,
                        "is not a right ascension in [0, 360] degrees (a catalogue without \
                         header, or with '#REFERENCE 0', is in absolute degrees; relative \
                         arcsec needs '#REFERENCE 3 ra0 dec0')"
                            .into(),
                    ));
                }
                if raw.y.abs() >= 90.0 {
                    return Err((1, "is not a declination in (-90, 90) degrees".into()));
                }
            }
            Coords::RelativeArcsec { reference } => {
                let dec = reference.dec_deg + raw.y / 3600.0;
                if dec.abs() >= 90.0 {
                    return Err((
                        1,
                        format!(
                            "puts the declination at {} deg, outside (-90, 90)",
                            crate::error::number(dec)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The frame of the parsed catalogue and every position in it (arcsec).
    ///
    /// The frame is `requested` when given; otherwise the header's reference; otherwise (an
    /// absolute catalogue without `ra0 dec0`) the mean position of the rows, the RA mean taken
    /// across RA = 0 correctly. Relative positions in another frame go through (RA, Dec):
    /// `p' = to_offset(requested, offset_to_radec(file, p))`. `raw` must be non-empty and
    /// checked with [`Self::check`].
    pub(crate) fn into_frame(
        self,
        raw: &[DVec2],
        requested: Option<SkyReference>,
    ) -> (SkyReference, Vec<DVec2>) {
        match self {
            Coords::AbsoluteDeg { header } => {
                let frame = requested.or(header).unwrap_or_else(|| mean_position(raw));
                let out = raw
                    .iter()
                    .map(|p| frame.to_offset_arcsec(p.x, p.y))
                    .collect();
                (frame, out)
            }
            Coords::RelativeArcsec { reference } => {
                let frame = requested.unwrap_or(reference);
                let out = raw.iter().map(|&p| reframe(p, reference, frame)).collect();
                (frame, out)
            }
        }
    }
}

/// The offset (arcsec) in frame `to` of the offset `p` (arcsec) in frame `from`, through the
/// sky position; exactly `p` when both frames are the same.
pub(crate) fn reframe(p: DVec2, from: SkyReference, to: SkyReference) -> DVec2 {
    if from == to {
        return p;
    }
    let (ra, dec) = from.offset_to_radec(p);
    to.to_offset_arcsec(ra, dec)
}

/// A usable copy of the caller's reference (finite, `|Dec| < 90`, RA wrapped), or an error.
pub(crate) fn check_requested(
    reference: Option<SkyReference>,
    source_name: &str,
) -> Result<Option<SkyReference>, CatalogError> {
    reference
        .map(|r| {
            SkyReference::new(r.ra_deg, r.dec_deg).ok_or(CatalogError::InvalidReference {
                source_name: source_name.into(),
                ra_deg: r.ra_deg,
                dec_deg: r.dec_deg,
            })
        })
        .transpose()
}

/// Mean (RA, Dec) of absolute positions in degrees, RA averaged as offsets from the first
/// position wrapped to `[-180, 180)` so that a field across RA = 0 averages correctly.
pub(crate) fn mean_position(raw: &[DVec2]) -> SkyReference {
    let ra_first = raw[0].x;
    let n = raw.len() as f64;
    let d_ra_mean = raw
        .iter()
        .map(|p| (p.x - ra_first + 180.0).rem_euclid(360.0) - 180.0)
        .sum::<f64>()
        / n;
    let dec_mean = raw.iter().map(|p| p.y).sum::<f64>() / n;
    // Checked positions have RA in [0, 360] and |Dec| < 90, so the mean is a valid reference.
    SkyReference::new((ra_first + d_ra_mean).rem_euclid(360.0), dec_mean).unwrap_or(SkyReference {
        ra_deg: ra_first,
        dec_deg: raw[0].y,
    })
}

/// Whether a trimmed comment line is a `#REFERENCE` header (`#REFERENCE` followed by
/// whitespace or nothing; the keyword's case is ignored).
pub(crate) fn is_reference_header(trimmed: &str) -> bool {
    let key = "#REFERENCE";
    trimmed.len() >= key.len()
        && trimmed.is_char_boundary(key.len())
        && trimmed[..key.len()].eq_ignore_ascii_case(key)
        && trimmed[key.len()..]
            .chars()
            .next()
            .is_none_or(char::is_whitespace)
}

/// Reads a `#REFERENCE mode [ra0 dec0]` header (see the module documentation).
pub(crate) fn parse_reference_header(
    trimmed: &str,
    line: usize,
    source_name: &str,
) -> Result<Coords, CatalogError> {
    let bad = |reason: String| CatalogError::BadReference {
        source_name: source_name.into(),
        line,
        text: trimmed.into(),
        reason,
    };
    let fields: Vec<&str> = trimmed.split_whitespace().skip(1).collect();
    let Some((&mode, rest)) = fields.split_first() else {
        return Err(bad("no mode after #REFERENCE (0 or 3 expected)".into()));
    };
    let sky = |ra: f64, dec: f64| {
        SkyReference::new(ra, dec).ok_or_else(|| {
            bad(format!(
                "({ra}, {dec}) is not a sky position: RA must be within [-360, 360] deg and \
                 |Dec| < 90 deg"
            ))
        })
    };
    let two = |what: &str| -> Result<[&str; 2], CatalogError> {
        match rest {
            [ra, dec, ..] => Ok([ra, dec]),
            _ => Err(bad(format!("mode {mode} needs ra0 and dec0 ({what})"))),
        }
    };
    match mode {
        "0" => match rest {
            [] => Ok(Coords::AbsoluteDeg { header: None }),
            [ra, dec, ..] => {
                let (ra, dec) = (degrees(ra).map_err(&bad)?, degrees(dec).map_err(&bad)?);
                Ok(Coords::AbsoluteDeg {
                    header: Some(sky(ra, dec)?),
                })
            }
            [_] => Err(bad(
                "mode 0 takes either no reference or both ra0 and dec0".into()
            )),
        },
        "3" => {
            let [ra, dec] = two("in degrees")?;
            let (ra, dec) = (degrees(ra).map_err(&bad)?, degrees(dec).map_err(&bad)?);
            Ok(Coords::RelativeArcsec {
                reference: sky(ra, dec)?,
            })
        }
        "1" => {
            let [ra, dec] = two("as hh:mm:ss dd:mm:ss")?;
            let ra = sexagesimal(ra, 15.0).map_err(&bad)?;
            let dec = sexagesimal(dec, 1.0).map_err(&bad)?;
            Ok(Coords::RelativeArcsec {
                reference: sky(ra, dec)?,
            })
        }
        "2" => Err(CatalogError::UnsupportedReference {
            source_name: source_name.into(),
            line,
            mode: mode.into(),
            reason: "Lenstool's mode 2 gives positions in pixels relative to a reference pixel, \
                     which needs the image's WCS; convert the catalogue to '#REFERENCE 0' \
                     (degrees) or '#REFERENCE 3 ra0 dec0' (arcsec)"
                .into(),
        }),
        _ => Err(CatalogError::UnsupportedReference {
            source_name: source_name.into(),
            line,
            mode: mode.into(),
            reason: "Lenstool defines modes 0 to 3; this reader converts 0, 1 and 3".into(),
        }),
    }
}

/// A finite decimal number of degrees.
fn degrees(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{text}' is not a finite number of degrees")),
    }
}

/// `[+-]a:m:s` to degrees: `scale * sign * (a + m/60 + s/3600)`; `scale` is 15 for hours of RA
/// and 1 for degrees of Dec. Minutes and seconds must be in `[0, 60)`.
pub(crate) fn sexagesimal(text: &str, scale: f64) -> Result<f64, String> {
    let err = || format!("'{text}' is not a sexagesimal angle like 22:48:44.0 or -44:31:51");
    let (sign, body) = match text.strip_prefix('-') {
        Some(b) => (-1.0, b),
        None => (1.0, text.strip_prefix('+').unwrap_or(text)),
    };
    let parts: Vec<f64> = body
        .split(':')
        .map(|p| p.parse::<f64>().ok().filter(|v| v.is_finite() && *v >= 0.0))
        .collect::<Option<_>>()
        .ok_or_else(err)?;
    let [a, m, s] = parts[..] else {
        return Err(err());
    };
    if m >= 60.0 || s >= 60.0 {
        return Err(err());
    }
    Ok(sign * scale * (a + m / 60.0 + s / 3600.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sexagesimal_reference() {
        let c = parse_reference_header("#REFERENCE 1 22:48:44.0 -00:30:00", 1, "t").unwrap();
        let Coords::RelativeArcsec { reference } = c else {
            panic!("{c:?}")
        };
        assert!((reference.ra_deg - 342.183_333_333_333_3).abs() < 1e-9);
        assert!((reference.dec_deg + 0.5).abs() < 1e-12);
    }

    #[test]
    fn header_detection() {
        assert!(is_reference_header("#REFERENCE 3 1 2"));
        assert!(is_reference_header("#reference\t0"));
        assert!(!is_reference_header("#REFERENCES are below"));
        assert!(!is_reference_header("# reference: Smith et al."));
    }

    #[test]
    fn mean_across_ra_zero() {
        let m = mean_position(&[DVec2::new(359.9, 10.0), DVec2::new(0.1, 20.0)]);
        assert!(
            m.ra_deg.abs() < 1e-9 || (m.ra_deg - 360.0).abs() < 1e-9,
            "{m:?}"
        );
        assert!((m.dec_deg - 15.0).abs() < 1e-12);
    }
}
