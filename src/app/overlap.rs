//! Whether the loaded files are of one field of the sky: each file's footprint (a circle about
//! the mean sky position of what it holds) is compared with the first file's, and a file whose
//! footprint lies apart from it is named in a warning. The reconstruction puts every file in
//! one frame regardless, so files of two clusters (the HFF maps of one over the catalogues of
//! another) would otherwise mix without a word.

use glam::DVec2;

use crate::arcs::{arcs_from_regions, is_region_file};
use crate::catalog::{parse_image_catalog, parse_member_catalog};
use crate::lenstool_par::{parse_par_with, ParOptions};
use crate::model::ModelFile;
use crate::sky::SkyReference;

use super::data::{LoadedData, NamedText};

/// How far apart two footprints may be beyond touching and still count as one field (arcsec):
/// a catalogue samples its field sparsely and a model file gives only its frame's origin.
pub const FIELD_MARGIN_ARCSEC: f64 = 120.0;

/// The part of the sky a file covers: a circle.
#[derive(Debug, Clone, PartialEq)]
pub struct SkyFootprint {
    /// The file's name.
    pub name: String,
    pub center: SkyReference,
    pub radius_arcsec: f64,
}

/// Angular distance between two sky positions (arcsec), by the haversine formula.
pub fn separation_arcsec(a: SkyReference, b: SkyReference) -> f64 {
    let (d1, d2) = (a.dec_deg.to_radians(), b.dec_deg.to_radians());
    let d_dec = d2 - d1;
    let d_ra = (b.ra_deg - a.ra_deg).to_radians();
    let h = (d_dec / 2.0).sin().powi(2) + d1.cos() * d2.cos() * (d_ra / 2.0).sin().powi(2);
    2.0 * h.sqrt().min(1.0).asin().to_degrees() * 3600.0
}

/// The footprint of positions `points` (arcsec offsets from `reference`): their mean and the
/// largest distance from it. `None` without a reference or points.
fn footprint(
    name: &str,
    reference: Option<SkyReference>,
    points: &[DVec2],
) -> Option<SkyFootprint> {
    let reference = reference?;
    if points.is_empty() {
        return None;
    }
    let mean = points.iter().copied().sum::<DVec2>() / points.len() as f64;
    let radius_arcsec = points.iter().map(|p| p.distance(mean)).fold(0.0, f64::max);
    let (ra, dec) = reference.offset_to_radec(mean);
    Some(SkyFootprint {
        name: name.to_string(),
        center: SkyReference::new(ra, dec)?,
        radius_arcsec,
    })
}

/// A distance in words: arcsec, arcmin or degrees.
fn distance_words(arcsec: f64) -> String {
    if arcsec >= 3600.0 {
        format!("{:.1} degrees", arcsec / 3600.0)
    } else if arcsec >= 60.0 {
        format!("{:.1} arcmin", arcsec / 60.0)
    } else {
        format!("{arcsec:.0} arcsec")
    }
}

/// One warning per footprint of `rest` that does not overlap `first` (their circles, grown by
/// [`FIELD_MARGIN_ARCSEC`], do not touch).
pub fn apart_warnings(first: &SkyFootprint, rest: &[SkyFootprint]) -> Vec<String> {
    rest.iter()
        .filter_map(|f| {
            let d = separation_arcsec(first.center, f.center);
            (d > first.radius_arcsec + f.radius_arcsec + FIELD_MARGIN_ARCSEC).then(|| {
                format!(
                    "{} (RA {:.4}, Dec {:.4} deg) and {} (RA {:.4}, Dec {:.4} deg) are {} apart \
                     on the sky: they do not cover the same field. Are they of the same \
                     cluster? They are used together in one frame regardless.",
                    f.name,
                    f.center.ra_deg,
                    f.center.dec_deg,
                    first.name,
                    first.center.ra_deg,
                    first.center.dec_deg,
                    distance_words(d),
                )
            })
        })
        .collect()
}

impl LoadedData {
    /// The sky footprints of the loaded files that place themselves on the sky, in the order
    /// images, members, arcs (DS9 regions), deflection maps, model (its frame's origin). A
    /// file without sky positions (no `#REFERENCE`, JSON arcs, a model without `reference`)
    /// has none; a file that no longer reads is left out (its own error says why).
    pub fn sky_footprints(
        &self,
        arc_pixel_arcsec: f64,
        par_options: &ParOptions,
    ) -> Vec<SkyFootprint> {
        let mut out = Vec::new();
        if let Some(NamedText { name, text }) = &self.images {
            if let Ok((c, _)) = parse_image_catalog(text, name, None) {
                let points: Vec<DVec2> = c
                    .systems
                    .iter()
                    .flat_map(|s| s.images.iter().map(|i| i.position))
                    .collect();
                out.extend(footprint(name, c.reference, &points));
            }
        }
        if let Some(NamedText { name, text }) = &self.members {
            if let Ok((m, _)) = parse_member_catalog(text, name, None) {
                let points: Vec<DVec2> = m.members.iter().map(|m| m.position).collect();
                out.extend(footprint(name, m.reference, &points));
            }
        }
        if let Some(NamedText { name, text }) = &self.arcs {
            if is_region_file(text) {
                if let Ok(r) = arcs_from_regions(text, name, None, arc_pixel_arcsec, &|_| None) {
                    let points: Vec<DVec2> = r
                        .arcs
                        .systems
                        .iter()
                        .flat_map(|s| s.images.iter().flatten().copied())
                        .collect();
                    out.extend(footprint(name, Some(r.reference), &points));
                }
            }
        }
        for m in self.deflection.iter().flatten() {
            let g = m.map.geometry;
            let half_diagonal = g.size_arcsec / std::f64::consts::SQRT_2;
            out.extend(
                footprint(&m.name, m.reference, &[g.center]).map(|f| SkyFootprint {
                    radius_arcsec: half_diagonal,
                    ..f
                }),
            );
        }
        if let Some(NamedText { name, text }) = &self.model {
            let reference = if text.trim_start().starts_with('{') {
                ModelFile::from_json_str(text, name)
                    .ok()
                    .and_then(|m| m.reference)
            } else {
                parse_par_with(text, name, par_options)
                    .ok()
                    .and_then(|p| p.reference)
            };
            out.extend(footprint(name, reference, &[DVec2::ZERO]));
        }
        out
    }

    /// One warning per loaded file whose sky positions lie apart from the first such file's
    /// (see the module documentation); empty when they overlap or fewer than two files place
    /// themselves on the sky.
    pub fn sky_warnings(&self, arc_pixel_arcsec: f64, par_options: &ParOptions) -> Vec<String> {
        match self
            .sky_footprints(arc_pixel_arcsec, par_options)
            .split_first()
        {
            Some((first, rest)) => apart_warnings(first, rest),
            None => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::{DataRole, Session};

    /// Two systems about RA 342.18, Dec -44.53 (Abell S1063), in absolute degrees.
    const IMAGES_AS1063: &str = "1.1 342.1810 -44.5300 0.5 0.5 0 1.2 25\n\
        1.2 342.1850 -44.5330 0.5 0.5 0 1.2 25\n\
        2.1 342.1790 -44.5280 0.5 0.5 0 2.0 25\n\
        2.2 342.1870 -44.5350 0.5 0.5 0 2.0 25\n";
    /// Members about a reference near the same cluster, 30 arcsec around it.
    const MEMBERS_AS1063: &str = "#REFERENCE 3 342.1832 -44.5309\n\
        1 0 0 1 1 0 18 1\n\
        2 30 -10 1 1 0 19 1\n\
        3 -25 20 1 1 0 19 1\n";
    /// The same members about MACS J1931.8-2635.
    const MEMBERS_MACS1931: &str = "#REFERENCE 3 292.9568 -26.5758\n\
        1 0 0 1 1 0 18 1\n\
        2 30 -10 1 1 0 19 1\n\
        3 -25 20 1 1 0 19 1\n";

    /// Tolerance of the separation (arcsec) against the spherical law of cosines.
    const SEPARATION_TOL_ARCSEC: f64 = 1e-6;

    #[test]
    fn separation_is_the_great_circle_distance() {
        let a = SkyReference::new(10.0, 20.0).unwrap();
        let b = SkyReference::new(10.0, 21.0).unwrap();
        assert!((separation_arcsec(a, b) - 3600.0).abs() < SEPARATION_TOL_ARCSEC);
        // Across RA 0 and at other declinations: the law of cosines.
        let (c, d) = (
            SkyReference::new(359.5, -44.0).unwrap(),
            SkyReference::new(0.7, -43.2).unwrap(),
        );
        let (r1, r2) = (c.dec_deg.to_radians(), d.dec_deg.to_radians());
        let cos =
            r1.sin() * r2.sin() + r1.cos() * r2.cos() * (d.ra_deg - c.ra_deg).to_radians().cos();
        let want = cos.acos().to_degrees() * 3600.0;
        assert!((separation_arcsec(c, d) - want).abs() < 1e-3 * want.max(1.0));
    }

    #[test]
    fn files_of_one_cluster_say_nothing_and_of_two_are_named() {
        let mut s = Session::new();
        s.load_text(DataRole::Images, "gold.cat", IMAGES_AS1063)
            .unwrap();
        s.load_text(DataRole::Members, "as1063_members.cat", MEMBERS_AS1063)
            .unwrap();
        let par = s.settings.par_options();
        assert_eq!(s.data.sky_footprints(0.2, &par).len(), 2);
        assert!(s.sky_warnings().is_empty(), "{:?}", s.sky_warnings());
        s.load_text(DataRole::Members, "m1931.cat", MEMBERS_MACS1931)
            .unwrap();
        let w = s.sky_warnings();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("m1931.cat (RA 292.95")
                && w[0].contains("and gold.cat (RA 342.18")
                && w[0].contains("degrees apart on the sky"),
            "{}",
            w[0]
        );
        // The run lists it among the data's warnings.
        let parsed = s.parsed().unwrap();
        assert!(
            parsed.warnings.iter().any(|x| x == &w[0]),
            "{:?}",
            parsed.warnings
        );
    }

    #[test]
    fn a_file_without_sky_positions_is_not_compared() {
        let mut s = Session::new();
        s.load_text(DataRole::Images, "gold.cat", IMAGES_AS1063)
            .unwrap();
        // The teaching model has no `reference`: it places itself nowhere on the sky.
        s.load_text(DataRole::Model, "model.json", crate::TEACHING_MODEL_JSON)
            .unwrap();
        let par = s.settings.par_options();
        assert_eq!(s.data.sky_footprints(0.2, &par).len(), 1);
        assert!(s.sky_warnings().is_empty(), "{:?}", s.sky_warnings());
    }
}
