//! A position typed or pasted by a person: RA/Dec in degrees or sexagesimal
//! (`342.1832 -44.5309`, `22:48:43.97 -44:31:51.2`, `22h48m43.97s -44d31m51.2s`,
//! `22 48 43.97 -44 31 51.2`), or x y in arcsec in the frame of the maps (`12.5" -3.2"`,
//! `12.5 -3.2 arcsec`), read into the arcsec frame ([method §1]) with the data's sky
//! reference.
//!
//! Two plain numbers carry no unit. They are read as RA/Dec in degrees when the data have a
//! sky reference and the position lies within [`SKY_MATCH_DEG`] of it (a cluster field is a
//! few arcmin wide, and arcsec offsets of the frame are never near its RA and Dec), as arcsec
//! otherwise; the answer says how it was read, and a unit (`″`, `arcsec`, `d`, `°`) settles it.
//!
//! [method §1]: crate::method#1-frames-and-units

use glam::DVec2;
use serde::Serialize;
use thiserror::Error;

use crate::sky::{parse_sky_angle, SkyReference};

/// Two plain numbers within this many degrees of the sky reference are RA/Dec (degrees).
pub const SKY_MATCH_DEG: f64 = 1.0;

/// How a typed position was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionForm {
    /// RA and Dec in decimal degrees.
    SkyDegrees,
    /// RA in hours and Dec in degrees, sexagesimal.
    SkySexagesimal,
    /// x and y in arcsec in the frame of the maps.
    FrameArcsec,
}

impl PositionForm {
    /// How the answer names it: "RA/Dec in degrees", ...
    pub fn words(self) -> &'static str {
        match self {
            PositionForm::SkyDegrees => "RA/Dec in degrees",
            PositionForm::SkySexagesimal => "RA/Dec, sexagesimal",
            PositionForm::FrameArcsec => "x y in arcsec",
        }
    }
}

/// A typed position read into the frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TypedPosition {
    /// The position in the arcsec frame.
    pub position_arcsec: DVec2,
    pub form: PositionForm,
    /// RA and Dec (degrees) when the data have a sky reference.
    pub radec_deg: Option<[f64; 2]>,
}

/// Why a typed position could not be read: the message starts with
/// "could not read 'TEXT' as a coordinate: ".
#[derive(Debug, Clone, PartialEq, Error)]
#[error("could not read '{text}' as a coordinate: {reason}")]
pub struct CoordinateError {
    pub text: String,
    pub reason: String,
}

/// The unit a token was written with.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Unit {
    None,
    Arcsec,
    Degrees,
}

/// Splits `token` into its number text and unit suffix.
fn unit_of(token: &str) -> (&str, Unit) {
    for (suffix, unit) in [
        ("arcsec", Unit::Arcsec),
        ("″", Unit::Arcsec),
        ("\"", Unit::Arcsec),
        ("deg", Unit::Degrees),
        ("°", Unit::Degrees),
        ("d", Unit::Degrees),
    ] {
        if let Some(body) = token.strip_suffix(suffix) {
            return (body, unit);
        }
    }
    (token, Unit::None)
}

/// `22h48m43.97s` or `-44d31m51.2s` (also with `'` and `"` for minutes and seconds) as
/// `22:48:43.97`, `-44:31:51.2`; `None` when the token is not of that form.
fn lettered_sexagesimal(token: &str) -> Option<String> {
    let t = token
        .replace(['h', 'd', '°', 'm', '\''], ":")
        .replace(['s', '"', '″'], "");
    let t = t.trim_end_matches(':');
    (t.matches(':').count() == 2 && t != token).then(|| t.to_string())
}

/// Reads `text` as a position (see the module doc); `reference` is the data's sky reference.
pub fn parse_position(
    text: &str,
    reference: Option<SkyReference>,
) -> Result<TypedPosition, CoordinateError> {
    let fail = |reason: String| CoordinateError {
        text: text.trim().to_string(),
        reason,
    };
    // "(12.5, -3.2)" as the read-out prints it; commas and semicolons separate as spaces do.
    let cleaned = text
        .trim()
        .trim_start_matches(['(', '['])
        .trim_end_matches([')', ']'])
        .replace([',', ';'], " ");
    let mut tokens: Vec<String> = cleaned.split_whitespace().map(str::to_string).collect();
    // "12.5 -3.2 arcsec": a unit word after both numbers applies to both.
    let mut shared = Unit::None;
    if let Some(last) = tokens.last().map(String::as_str) {
        let word = match last {
            "arcsec" | "\"" | "″" => Some(Unit::Arcsec),
            "deg" | "degrees" | "°" => Some(Unit::Degrees),
            _ => None,
        };
        if let Some(u) = word {
            shared = u;
            tokens.pop();
        }
    }
    if tokens.is_empty() {
        return Err(fail(
            "it is empty: type RA Dec (degrees or 22:48:43.97 -44:31:51.2) or x y in arcsec"
                .to_string(),
        ));
    }
    // Sexagesimal: "a:b:c" or lettered tokens, or six plain numbers "22 48 43.97 -44 31 51.2".
    let lettered: Vec<Option<String>> = tokens.iter().map(|t| lettered_sexagesimal(t)).collect();
    let sexagesimal = if tokens.len() == 2 && tokens.iter().any(|t| t.contains(':')) {
        Some([tokens[0].clone(), tokens[1].clone()])
    } else if tokens.len() == 2 && lettered.iter().all(Option::is_some) {
        Some([
            lettered[0].clone().unwrap_or_default(),
            lettered[1].clone().unwrap_or_default(),
        ])
    } else if tokens.len() == 6 && tokens.iter().all(|t| t.parse::<f64>().is_ok()) {
        Some([tokens[..3].join(":"), tokens[3..].join(":")])
    } else {
        None
    };
    if let Some([ra, dec]) = sexagesimal {
        let reference = reference.ok_or_else(|| fail(no_reference()))?;
        let ra_deg = parse_sky_angle(&ra, true).map_err(&fail)?;
        let dec_deg = parse_sky_angle(&dec, false).map_err(&fail)?;
        return Ok(sky(
            reference,
            ra_deg,
            dec_deg,
            PositionForm::SkySexagesimal,
        ));
    }
    if tokens.len() != 2 {
        return Err(fail(format!(
            "expected two values (RA Dec, or x y in arcsec), found {}",
            tokens.len()
        )));
    }
    let mut values = [0.0; 2];
    let mut units = [shared; 2];
    let mut bodies = ["", ""];
    for k in 0..2 {
        let (body, unit) = unit_of(&tokens[k]);
        bodies[k] = body;
        if unit != Unit::None {
            if shared != Unit::None && unit != shared {
                return Err(fail("the two values have different units".to_string()));
            }
            units[k] = unit;
        }
        values[k] = body
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| fail(format!("'{}' is not a number", tokens[k])))?;
    }
    let unit = match units {
        [a, b] if a == b => a,
        [Unit::None, u] | [u, Unit::None] => u,
        _ => return Err(fail("the two values have different units".to_string())),
    };
    let [a, b] = values;
    let as_sky = |reference: SkyReference| -> Result<TypedPosition, CoordinateError> {
        // The range checks, naming the value as typed.
        parse_sky_angle(bodies[0], true).map_err(&fail)?;
        parse_sky_angle(bodies[1], false).map_err(&fail)?;
        Ok(sky(reference, a, b, PositionForm::SkyDegrees))
    };
    match unit {
        Unit::Degrees => as_sky(reference.ok_or_else(|| fail(no_reference()))?),
        Unit::Arcsec => Ok(frame(reference, DVec2::new(a, b))),
        Unit::None => match reference {
            Some(r) if near(r, a, b) => as_sky(r),
            _ => Ok(frame(reference, DVec2::new(a, b))),
        },
    }
}

fn no_reference() -> String {
    "RA/Dec need the data's sky reference, and these data have none: give x y in arcsec \
     (e.g. 12.5 -3.2)"
        .to_string()
}

/// Whether `(ra, dec)` in degrees lies within [`SKY_MATCH_DEG`] of the reference.
fn near(r: SkyReference, ra: f64, dec: f64) -> bool {
    let d_ra = (ra - r.ra_deg + 180.0).rem_euclid(360.0) - 180.0;
    (dec - r.dec_deg).abs() <= SKY_MATCH_DEG
        && (d_ra * r.dec_deg.to_radians().cos()).abs() <= SKY_MATCH_DEG
}

fn sky(r: SkyReference, ra_deg: f64, dec_deg: f64, form: PositionForm) -> TypedPosition {
    TypedPosition {
        position_arcsec: r.to_offset_arcsec(ra_deg, dec_deg),
        form,
        radec_deg: Some([ra_deg.rem_euclid(360.0), dec_deg]),
    }
}

fn frame(reference: Option<SkyReference>, p: DVec2) -> TypedPosition {
    TypedPosition {
        position_arcsec: p,
        form: PositionForm::FrameArcsec,
        radec_deg: reference.map(|r| {
            let (ra, dec) = r.offset_to_radec(p);
            [ra, dec]
        }),
    }
}

/// RA (hours) and Dec (degrees) sexagesimal, as `22:48:43.97 -44:31:51.2` (RA to 0.01 s,
/// Dec to 0.1 arcsec).
pub fn sexagesimal_text(ra_deg: f64, dec_deg: f64) -> String {
    // Rounded first, so that 59.999 s never prints as 60.00.
    let ra_cs = (ra_deg.rem_euclid(360.0) / 15.0 * 360_000.0).round() as i64 % (24 * 360_000);
    let (h, m, s) = (ra_cs / 360_000, ra_cs / 6000 % 60, ra_cs % 6000);
    let sign = if dec_deg < 0.0 { '-' } else { '+' };
    let dec_ds = (dec_deg.abs() * 36_000.0).round() as i64;
    let (d, dm, ds) = (dec_ds / 36_000, dec_ds / 600 % 60, dec_ds % 600);
    format!(
        "{h:02}:{m:02}:{:02}.{:02} {sign}{d:02}:{dm:02}:{:02}.{}",
        s / 100,
        s % 100,
        ds / 10,
        ds % 10
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frame of AS1063 (the catalogue reference of the HFF data).
    fn as1063() -> Option<SkyReference> {
        SkyReference::new(342.183_208, -44.530_905)
    }

    /// Positions agree to this (arcsec): far below a map pixel.
    const TOL_ARCSEC: f64 = 1e-6;

    #[test]
    fn sky_positions_in_every_form_agree() {
        let r = as1063();
        let want = r.unwrap().to_offset_arcsec(342.1832, -44.5309);
        for text in [
            "342.1832 -44.5309",
            "342.1832d -44.5309d",
            "342.1832, -44.5309",
            "(342.1832, -44.5309)",
            "342.1832 -44.5309 deg",
        ] {
            let p = parse_position(text, r).unwrap();
            assert_eq!(p.form, PositionForm::SkyDegrees, "{text}");
            assert!(
                (p.position_arcsec - want).length() < TOL_ARCSEC,
                "{text}: {}",
                p.position_arcsec
            );
        }
        let sexa = r.unwrap().to_offset_arcsec(
            15.0 * (22.0 + 48.0 / 60.0 + 43.97 / 3600.0),
            -(44.0 + 31.0 / 60.0 + 51.2 / 3600.0),
        );
        for text in [
            "22:48:43.97 -44:31:51.2",
            "22h48m43.97s -44d31m51.2s",
            "22 48 43.97 -44 31 51.2",
            "  22:48:43.97,-44:31:51.2 ",
        ] {
            let p = parse_position(text, r).unwrap();
            assert_eq!(p.form, PositionForm::SkySexagesimal, "{text}");
            assert!(
                (p.position_arcsec - sexa).length() < TOL_ARCSEC,
                "{text}: {}",
                p.position_arcsec
            );
        }
        // The two spellings of the brief are the same point to a tenth of an arcsec.
        let a = parse_position("342.1832 -44.5309", r)
            .unwrap()
            .position_arcsec;
        let b = parse_position("22:48:43.97 -44:31:51.2", r)
            .unwrap()
            .position_arcsec;
        assert!((a - b).length() < 0.5, "{a} vs {b}");
    }

    #[test]
    fn arcsec_in_the_frame() {
        let r = as1063();
        for text in [
            "12.5\" -3.2\"",
            "12.5″ -3.2″",
            "12.5 -3.2 arcsec",
            "12.5arcsec -3.2arcsec",
            "12.5 -3.2",
        ] {
            let p = parse_position(text, r).unwrap();
            assert_eq!(p.form, PositionForm::FrameArcsec, "{text}");
            assert_eq!(p.position_arcsec, DVec2::new(12.5, -3.2), "{text}");
            let [ra, dec] = p.radec_deg.unwrap();
            let back = r.unwrap().to_offset_arcsec(ra, dec);
            assert!((back - p.position_arcsec).length() < TOL_ARCSEC);
        }
        // Without a sky reference plain numbers are arcsec, and no RA/Dec is given.
        let p = parse_position("342.1832 -44.5309", None).unwrap();
        assert_eq!(p.form, PositionForm::FrameArcsec);
        assert_eq!(p.radec_deg, None);
    }

    #[test]
    fn bad_input_says_what_is_wrong() {
        let r = as1063();
        let cases = [
            ("xyz", "could not read 'xyz' as a coordinate: expected two values (RA Dec, or x y in arcsec), found 1"),
            ("", "could not read '' as a coordinate: it is empty"),
            ("12 abc", "could not read '12 abc' as a coordinate: 'abc' is not a number"),
            ("1 2 3", "found 3"),
            ("22:61:00 -44:31:51", "'22:61:00' is not a sexagesimal angle"),
            ("25:00:00 -44:31:51", "RA '25:00:00' is outside +-360 degrees"),
            ("342.18d -95d", "Dec '-95' is outside +-90 degrees"),
            ("12\" -3d", "different units"),
        ];
        for (text, want) in cases {
            let e = parse_position(text, r).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!(
                    "could not read '{}' as a coordinate: ",
                    text.trim()
                )),
                "{e}"
            );
            assert!(e.contains(want), "{text}: {e}");
        }
        let e = parse_position("22:48:43.97 -44:31:51.2", None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("these data have none: give x y in arcsec"),
            "{e}"
        );
    }

    #[test]
    fn sexagesimal_text_round_trips() {
        assert_eq!(
            sexagesimal_text(342.183_208, -44.530_905),
            "22:48:43.97 -44:31:51.3"
        );
        assert_eq!(
            sexagesimal_text(197.872_917, -1.341_111),
            "13:11:29.50 -01:20:28.0"
        );
        assert_eq!(
            sexagesimal_text(359.999_999_9, 0.0),
            "00:00:00.00 +00:00:00.0"
        );
        let r = as1063();
        let text = sexagesimal_text(342.1832, -44.5309);
        let a = parse_position(&text, r).unwrap().position_arcsec;
        let b = parse_position("342.1832 -44.5309", r)
            .unwrap()
            .position_arcsec;
        assert!((a - b).length() < 0.15, "{text}: {a} vs {b}");
    }
}
