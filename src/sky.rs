//! The sky reference of the arcsec frame ([method §1]).
//!
//! Offsets from the reference `(RA0, Dec0)` are Lenstool's relative coordinates:
//! `x = -(RA - RA0) cos(Dec0) * 3600` (+x West), `y = (Dec - Dec0) * 3600` (+y North).
//! This linear relation differs from the exact gnomonic (TAN) projection of a FITS WCS by about
//! `|x| |y| tan(Dec0) / 206265` arcsec, i.e. 0.01 arcsec at 100 arcsec from the reference at
//! `|Dec0| = 10 deg`: far below a map pixel.
//!
//! [method §1]: crate::method#1-frames-and-units

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// The sky position (ICRS, degrees) of the origin of the arcsec frame.
/// In JSON (the model file's `reference`) it is `{"ra": deg, "dec": deg}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyReference {
    /// Right ascension of the frame origin in degrees, `[0, 360)`.
    #[serde(rename = "ra")]
    pub ra_deg: f64,
    /// Declination of the frame origin in degrees, `[-90, 90]`.
    #[serde(rename = "dec")]
    pub dec_deg: f64,
}

impl SkyReference {
    /// A reference; `None` unless both are finite, `|dec| < 90` (the frame is singular at a pole)
    /// and `ra` in `[-360, 360]` (it is wrapped to `[0, 360)`).
    pub fn new(ra_deg: f64, dec_deg: f64) -> Option<Self> {
        let ok = ra_deg.is_finite()
            && dec_deg.is_finite()
            && dec_deg.abs() < 90.0
            && ra_deg.abs() <= 360.0;
        ok.then(|| Self {
            ra_deg: wrap_ra(ra_deg),
            dec_deg,
        })
    }

    /// Offset in arcsec of the sky position `(ra_deg, dec_deg)`:
    /// `x = -(RA - RA0) cos(Dec0) 3600`, `y = (Dec - Dec0) 3600`, with `RA - RA0` wrapped to
    /// `[-180, 180)` degrees.
    pub fn to_offset_arcsec(&self, ra_deg: f64, dec_deg: f64) -> DVec2 {
        let d_ra = (ra_deg - self.ra_deg + 180.0).rem_euclid(360.0) - 180.0;
        DVec2::new(
            -d_ra * self.dec_deg.to_radians().cos() * 3600.0,
            (dec_deg - self.dec_deg) * 3600.0,
        )
    }

    /// Sky position `(ra_deg, dec_deg)` of the offset `p` (arcsec); the inverse of
    /// [`Self::to_offset_arcsec`], RA wrapped to `[0, 360)`.
    pub fn offset_to_radec(&self, p: DVec2) -> (f64, f64) {
        let ra = self.ra_deg - p.x / 3600.0 / self.dec_deg.to_radians().cos();
        (wrap_ra(ra), self.dec_deg + p.y / 3600.0)
    }
}

/// An RA (`is_ra`) or a Dec typed by a person: decimal degrees (`342.1833`) or sexagesimal,
/// hours for RA (`22:48:44.0`) and degrees for Dec (`-44:31:51`).
pub fn parse_sky_angle(text: &str, is_ra: bool) -> Result<f64, String> {
    let text = text.trim();
    let value = if text.contains(':') {
        crate::catalog::sexagesimal(text, if is_ra { 15.0 } else { 1.0 })?
    } else {
        text.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("'{text}' is not an angle in degrees or like 22:48:44.0"))?
    };
    let (what, limit) = if is_ra { ("RA", 360.0) } else { ("Dec", 90.0) };
    if value.abs() > limit {
        return Err(format!("{what} '{text}' is outside +-{limit} degrees"));
    }
    Ok(value)
}

/// RA in `[0, 360)` degrees: `rem_euclid` alone gives 360.0 for a tiny negative angle (found
/// by fuzzing, fuzz/regressions/fits_roundtrip/).
fn wrap_ra(ra_deg: f64) -> f64 {
    let ra = ra_deg.rem_euclid(360.0);
    if ra < 360.0 {
        ra
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_round_trip_across_ra_zero() {
        let r = SkyReference::new(0.001, -30.0).unwrap();
        let p = DVec2::new(12.5, -40.0);
        let (ra, dec) = r.offset_to_radec(p);
        assert!(ra > 359.0, "west of RA0 = 0.001 deg wraps past 360: {ra}");
        let back = r.to_offset_arcsec(ra, dec);
        assert!((back - p).length() < 1e-9, "{back}");
    }

    #[test]
    fn rejects_poles_and_non_finite() {
        assert!(SkyReference::new(10.0, 90.0).is_none());
        assert!(SkyReference::new(f64::NAN, 0.0).is_none());
        assert_eq!(SkyReference::new(-10.0, 5.0).unwrap().ra_deg, 350.0);
    }

    #[test]
    fn tiny_negative_ra_wraps_below_360() {
        for ra in [-1e-17, -9.8e-310] {
            assert_eq!(SkyReference::new(ra, 5.0).unwrap().ra_deg, 0.0, "{ra}");
        }
        let r = SkyReference::new(0.0, 0.0).unwrap();
        assert!(r.offset_to_radec(DVec2::new(1e-15, 0.0)).0 < 360.0);
    }
}
