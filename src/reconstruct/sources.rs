//! Per-system results of a reconstruction: source position, source-plane scatter, predicted
//! images (the lens equation solved forward) and their offsets from the observed images, for
//! fitted and held-out systems alike.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::ds9::{write_marks, Mark};
use crate::image_search::{
    find_images, magnification_at, source_position, ImageError, ImageSearch, SearchGrid,
};
use crate::inversion::{
    capped_inverse_jacobian, ConstraintConfig, ConstraintSource, LinearSystem, RedshiftPrior,
};
use crate::map::{LensMaps, Map};
use crate::potential::{arrival_time_days, potential_at, potential_map};
use crate::products::Products;
use crate::profiles::{Lens, MassComponent};

use super::{Inputs, ReconstructError};

/// Predicted images solve the lens equation on the interpolated maps to this accuracy (arcsec);
/// the maps themselves are good to a fraction of their pixel.
const MAP_IMAGE_TOLERANCE_ARCSEC: f64 = 1e-3;

/// A lens given as its maps (`D_ls/D_s = 1`), bilinearly interpolated: the deflection from the
/// alpha maps, the Hessian from kappa and gamma.
#[derive(Debug)]
pub struct InterpolatedLens<'a>(pub &'a LensMaps);

impl MassComponent for InterpolatedLens<'_> {
    fn kappa(&self, p: DVec2) -> f64 {
        self.0.kappa.sample(p)
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        DVec2::new(self.0.alpha_x.sample(p), self.0.alpha_y.sample(p))
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        let (k, g1, g2) = (
            self.0.kappa.sample(p),
            self.0.gamma1.sample(p),
            self.0.gamma2.sample(p),
        );
        [k + g1, g2, k - g1]
    }
}

/// The images of a source at `beta` (arcsec) for `f = D_ls/D_s`, found on `maps` interpolated:
/// the exact lens of a reconstruction sums every cell and galaxy at each Newton step, which for
/// a 64 x 64 grid costs minutes per system.
pub fn images_on_maps(
    maps: &LensMaps,
    f: f64,
    beta: DVec2,
) -> Result<Vec<PredictedImage>, ImageError> {
    let search = ImageSearch {
        tolerance_arcsec: MAP_IMAGE_TOLERANCE_ARCSEC,
        ..ImageSearch::default()
    };
    let found = find_images(
        &InterpolatedLens(maps),
        SearchGrid::Maps(maps),
        f,
        beta,
        &search,
    )?;
    Ok(found
        .into_iter()
        .map(|i| PredictedImage {
            position_arcsec: i.position,
            magnification: i.magnification,
            delay_days: None,
        })
        .collect())
}

/// The source position `theta - f alpha(theta)` (arcsec) of the point `theta` on `maps`
/// (deflection interpolated).
pub fn source_on_maps(maps: &LensMaps, f: f64, theta: DVec2) -> DVec2 {
    source_position(&InterpolatedLens(maps), f, theta)
}

/// Most constraint pixels of one system back-projected for its scatter.
const SCATTER_SAMPLE: usize = 500;

/// One observed image and the model's prediction next to it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageReport {
    pub id: String,
    /// Observed position (arcsec): the catalogue position, or the mean of its arc pixels.
    pub position_arcsec: DVec2,
    /// Its back-projection `theta - f alpha(theta)` (arcsec).
    pub beta_arcsec: DVec2,
    /// The nearest predicted image (arcsec), if any was found.
    pub predicted_arcsec: Option<DVec2>,
    /// Distance to it in arcsec.
    pub offset_arcsec: Option<f64>,
    /// The model's signed magnification at the observed position, at the system's redshift.
    /// A large offset where `|mu|` is high usually means that the image lies near a critical
    /// curve and its source just outside the model's caustic: the pair it belongs to has
    /// merged, and the nearest predicted image is elsewhere. (Absent in results saved before
    /// it was added.)
    #[serde(default)]
    pub magnification: Option<f64>,
    /// The model's arrival time at the observed position from the system's source, in days
    /// after the system's first predicted image (negative: earlier). Absent when the lens's
    /// maps do not reach the image, and in results saved before it was added.
    #[serde(default)]
    pub delay_days: Option<f64>,
}

/// One predicted image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PredictedImage {
    pub position_arcsec: DVec2,
    /// Signed magnification at the system's redshift.
    pub magnification: f64,
    /// Arrival time in days after the system's first predicted image (0 for that one; see
    /// [`crate::arrival_time_days`]). Absent in results saved before it was added.
    #[serde(default)]
    pub delay_days: Option<f64>,
}

impl PredictedImage {
    /// Whether the map and `images.reg` show it: `|mu| >=` [`SHOWN_MIN_MAGNIFICATION`].
    pub fn is_shown(&self) -> bool {
        self.magnification.abs() >= SHOWN_MIN_MAGNIFICATION
    }
}

/// One source system (`sources.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceReport {
    pub id: String,
    pub z: f64,
    /// True when the redshift was the configured default, not measured.
    pub z_assumed: bool,
    /// For a system whose redshift was estimated (none in the catalogue, or named free), the
    /// estimate it was fitted at (`z` is the same; the `free_z` module says how); else `null`.
    #[serde(default)]
    pub z_estimate: Option<f64>,
    /// The narrowest interval holding 68% of `z_estimate`'s posterior (it contains
    /// `z_estimate`).
    #[serde(default)]
    pub z_interval: Option<[f64; 2]>,
    /// The image-plane error (arcsec) `z_interval` means for the system's images
    /// (`position_error_arcsec` of the estimate): it is fitted with it added to the position
    /// error in quadrature, so a redshift the images hardly fix weighs little in the map.
    #[serde(default)]
    pub z_position_error_arcsec: Option<f64>,
    /// True when `z_interval` reaches the top of the range searched (the setting's, or the
    /// system's own prior's): the images do not bound the redshift from above there.
    #[serde(default)]
    pub z_open_above: bool,
    /// The system's own redshift prior (`constraints.z_priors`, e.g. a `.par`'s `z_m_limit`
    /// line), if it has one: `z_estimate` was found under it, or, fixed, `z` is its value.
    #[serde(default)]
    pub z_prior: Option<RedshiftPrior>,
    /// True when the system was left out of the fit and is predicted.
    pub held_out: bool,
    /// Source position (arcsec): the solved beta of a fitted system, or for a held-out one
    /// the mean of its back-projected observed images weighted by their inverse lens Jacobians
    /// (the source whose predicted images lie closest to the observed ones, to first order).
    pub beta_arcsec: DVec2,
    /// Root mean square distance of the back-projected constraint pixels (held out: observed
    /// images) from beta, arcsec.
    pub scatter_arcsec: f64,
    pub observed: Vec<ImageReport>,
    pub predicted: Vec<PredictedImage>,
    /// Root mean square of the observed-to-predicted offsets, arcsec.
    pub image_plane_rms_arcsec: Option<f64>,
}

/// Predicted images fainter than this (`|mu|`, i.e. more than 2.5 magnitudes fainter than the
/// unlensed source) are left off the app's map and `images.reg`: they are mostly the
/// demagnified central images of the cluster core, which observations almost never show (the
/// built-in example, 8000 iterations: 129 predicted images for 90 observed, 23 of them with
/// `|mu| < 0.1`). `sources.json` and the systems table keep them all.
pub const SHOWN_MIN_MAGNIFICATION: f64 = 0.1;

/// Radius of the circles of `images.reg` (arcsec), about the size of a catalogue image.
pub const IMAGE_REGION_RADIUS_ARCSEC: f64 = 0.5;

/// `images.reg`: DS9 circles at each system's observed images (green, labelled with the image
/// id) and predicted images with `|mu| >=` [`SHOWN_MIN_MAGNIFICATION`] (magenta, dashed,
/// labelled with the system id and the signed magnification at the system's redshift), to lay over the cluster image and look for the
/// counter-images the model predicts. A predicted image that is no observed image's nearest
/// says "not observed": a candidate, or a prediction to check. Held-out systems are marked.
/// Frames as in [`crate::ds9::write_regions`] (`fk5` with the products' sky reference, else
/// pixels of their maps).
pub fn image_regions(sources: &[SourceReport], products: &Products) -> String {
    let mut marks = Vec::new();
    for s in sources {
        let held = if s.held_out { " (held out)" } else { "" };
        for o in &s.observed {
            marks.push(Mark {
                position_arcsec: o.position_arcsec,
                label: format!("{}{held}", o.id),
                color: "green",
                tag: "observed",
                dashed: false,
            });
        }
        for p in s.predicted.iter().filter(|p| p.is_shown()) {
            // An observed image's nearest predicted image is a copy of one of these.
            let matched = s
                .observed
                .iter()
                .any(|o| o.predicted_arcsec == Some(p.position_arcsec));
            let mu = p.magnification;
            let mu = if mu.abs() < 1.0 {
                format!("{mu:.2}")
            } else {
                format!("{mu:.1}")
            };
            let unmatched = if matched { "" } else { ", not observed" };
            marks.push(Mark {
                position_arcsec: p.position_arcsec,
                label: format!("{}{held}: predicted, mu={mu}{unmatched}", s.id),
                color: "magenta",
                tag: "predicted",
                dashed: true,
            });
        }
    }
    write_marks(
        &format!(
            "WSLAP+ observed images (green) and the images the model predicts (magenta, dashed)\n\
             with |mu| >= {SHOWN_MIN_MAGNIFICATION} (sources.json lists the fainter ones too);\n\
             mu: signed magnification at the system's redshift"
        ),
        &marks,
        IMAGE_REGION_RADIUS_ARCSEC,
        products.reference,
        &products.maps.geometry(),
    )
}

/// The reports of every fitted and held-out system.
pub(super) fn report(
    system: &LinearSystem,
    x: &[f64],
    lens: &Lens,
    products: &Products,
    inputs: &Inputs<'_>,
    constraints: &ConstraintConfig,
    max_stretch: f64,
) -> Result<Vec<SourceReport>, ReconstructError> {
    let betas = system.betas_arcsec(x)?;
    let times = ArrivalTimes::new(products);
    let arrival = |z: f64, beta: DVec2| {
        let times = &times;
        move |theta: DVec2| times.days(z, beta, theta)
    };
    let mut reports = Vec::new();
    for (s, sys) in system.constraints.systems.iter().enumerate() {
        let f = system.distance_ratios[s];
        let beta = betas[s];
        // The system's constraint pixels back-projected (at most SCATTER_SAMPLE of them, evenly
        // spread: a big arc would otherwise cost a full lens evaluation per pixel).
        let pixels: Vec<_> = system
            .constraints
            .pixels
            .iter()
            .filter(|p| p.system == s)
            .collect();
        let stride = pixels.len().div_ceil(SCATTER_SAMPLE).max(1);
        let d2: Vec<f64> = pixels
            .iter()
            .step_by(stride)
            .map(|p| source_position(lens, f, p.position).distance_squared(beta))
            .collect();
        let mut per_image = vec![(DVec2::ZERO, 0usize); sys.images.len()];
        for p in &pixels {
            per_image[p.image].0 += p.position;
            per_image[p.image].1 += 1;
        }
        let observed: Vec<(String, DVec2)> = sys
            .images
            .iter()
            .zip(&per_image)
            .map(|(id, &(sum, n))| {
                (
                    id.clone(),
                    observed_position(inputs, &sys.id, id, sum / n.max(1) as f64),
                )
            })
            .collect();
        let predicted = images_on_maps(&products.maps, f, beta)?;
        reports.push(finish(
            sys.id.clone(),
            sys.z,
            sys.z_assumed,
            false,
            beta,
            rms(&d2),
            observed,
            predicted,
            lens,
            f,
            &arrival(sys.z, beta),
        ));
    }
    for id in inputs.holdout {
        let Some((z, observed)) = held_out_images(inputs, id) else {
            continue;
        };
        let Some((z, z_assumed)) = constraints.given_z(id, z) else {
            continue;
        };
        let Ok(f) = inputs.plane.distance_ratio(z) else {
            continue;
        };
        // Each image back-projected, with the inverse of its lens Jacobian: the source that
        // puts the predicted images closest to the observed ones (to first order), as the
        // image-plane fit does for the fitted systems.
        let terms: Vec<(DVec2, [f64; 4])> = observed
            .iter()
            .map(|(_, p)| {
                let (alpha, h) = lens.deflection_hessian(*p);
                (*p - f * alpha, capped_inverse_jacobian(h, f, max_stretch))
            })
            .collect();
        let back: Vec<DVec2> = terms.iter().map(|(b, _)| *b).collect();
        let beta = image_plane_source(&terms);
        let d2: Vec<f64> = back.iter().map(|b| b.distance_squared(beta)).collect();
        let predicted = images_on_maps(&products.maps, f, beta)?;
        reports.push(finish(
            id.clone(),
            z,
            z_assumed,
            true,
            beta,
            rms(&d2),
            observed,
            predicted,
            lens,
            f,
            &arrival(z, beta),
        ));
    }
    Ok(reports)
}

/// The source position that minimises `sum_k |M_k (beta_k - beta)|^2` over a system's
/// images: `beta_k` an image back-projected (arcsec), `M_k` the inverse of the lens Jacobian
/// there (row-major, its stretch capped: [`capped_inverse_jacobian`]), so that `M_k (beta_k -
/// beta)` is, to first order, the image-plane offset of the image the source at `beta` makes
/// near image `k`. The weighted mean `(sum W_k)^-1 sum W_k beta_k` with `W_k = M_k^T M_k`: a
/// strongly magnified image, whose back-projection the lens pins down, weighs more than a
/// faint counter-image far from the curves. The plain mean when the weights are singular.
pub(super) fn image_plane_source(terms: &[(DVec2, [f64; 4])]) -> DVec2 {
    let w = |m: &[f64; 4]| {
        [
            m[0] * m[0] + m[2] * m[2],
            m[0] * m[1] + m[2] * m[3],
            m[1] * m[1] + m[3] * m[3],
        ]
    };
    let (mut s, mut rhs) = ([0.0; 3], DVec2::ZERO);
    for (b, m) in terms {
        let wk = w(m);
        s[0] += wk[0];
        s[1] += wk[1];
        s[2] += wk[2];
        rhs += DVec2::new(wk[0] * b.x + wk[1] * b.y, wk[1] * b.x + wk[2] * b.y);
    }
    let det = s[0] * s[2] - s[1] * s[1];
    if det.abs() > 1e-300 {
        DVec2::new(
            (s[2] * rhs.x - s[1] * rhs.y) / det,
            (s[0] * rhs.y - s[1] * rhs.x) / det,
        )
    } else {
        terms.iter().map(|(b, _)| *b).sum::<DVec2>() / terms.len().max(1) as f64
    }
}

/// `sum_k |M_k (beta_k - beta)|^2` (arcsec^2): to first order, the summed squared image-plane
/// offsets of a source at `beta` from a system's images (terms as in [`image_plane_source`]).
pub(super) fn image_plane_offsets2(terms: &[(DVec2, [f64; 4])], beta: DVec2) -> f64 {
    terms
        .iter()
        .map(|(b, m)| {
            let d = *b - beta;
            DVec2::new(m[0] * d.x + m[1] * d.y, m[2] * d.x + m[3] * d.y).length_squared()
        })
        .sum()
}

/// Arrival times on a lens's product maps: its potential map, made once.
pub struct ArrivalTimes<'a> {
    psi: Map,
    products: &'a Products,
}

impl<'a> ArrivalTimes<'a> {
    /// The potential of `products`' maps ([`potential_map`]).
    pub fn new(products: &'a Products) -> Self {
        Self {
            psi: potential_map(&products.maps),
            products,
        }
    }

    /// The arrival time in days at `theta` (arcsec) from a source at `beta` and `z`, from a
    /// fixed origin (compare images of one source only); `None` off the maps.
    pub fn days(&self, z: f64, beta: DVec2, theta: DVec2) -> Option<f64> {
        let psi = potential_at(&self.psi, &self.products.maps, theta)?;
        arrival_time_days(&self.products.plane, z, theta, beta, psi).ok()
    }

    /// Sets each image's `delay_days` from the first of them to arrive.
    pub fn set_delays(&self, z: f64, beta: DVec2, images: &mut [PredictedImage]) {
        let times: Vec<Option<f64>> = images
            .iter()
            .map(|i| self.days(z, beta, i.position_arcsec))
            .collect();
        let zero = times.iter().flatten().copied().reduce(f64::min);
        for (i, t) in images.iter_mut().zip(times) {
            i.delay_days = t.zip(zero).map(|(t, z)| t - z);
        }
    }
}

/// Observed images by id and position (arcsec).
type Observed = Vec<(String, DVec2)>;

/// The redshift (if known) and the observed images of the held-out system `id`: the image
/// catalogue's positions when it has the system, else the mean of each image's arc pixels;
/// `None` for an id that is in neither.
pub(super) fn held_out_images(inputs: &Inputs<'_>, id: &str) -> Option<(Option<f64>, Observed)> {
    if let Some(sys) = inputs
        .catalog
        .and_then(|c| c.systems.iter().find(|s| s.id == id))
    {
        let images = sys.images.iter().map(|i| (i.id.clone(), i.position));
        return Some((sys.z, images.collect()));
    }
    let ConstraintSource::Arcs(arcs) = inputs.images else {
        return None;
    };
    let sys = arcs.systems.iter().find(|s| s.id == id)?;
    let images = sys
        .image_ids()
        .into_iter()
        .zip(&sys.images)
        .filter(|(_, pixels)| !pixels.is_empty())
        .map(|(id, pixels)| {
            let mean = pixels.iter().copied().sum::<DVec2>() / pixels.len() as f64;
            (id, mean)
        });
    Some((sys.z, images.collect()))
}

/// The catalogue position of an image when there is a catalogue, else the mean of its pixels.
fn observed_position(
    inputs: &Inputs<'_>,
    system_id: &str,
    image_id: &str,
    pixel_mean: DVec2,
) -> DVec2 {
    inputs
        .catalog
        .and_then(|c| c.systems.iter().find(|s| s.id == system_id))
        .and_then(|s| s.images.iter().find(|i| i.id == image_id))
        .map_or(pixel_mean, |i| i.position)
}

fn rms(d2: &[f64]) -> f64 {
    if d2.is_empty() {
        0.0
    } else {
        (d2.iter().sum::<f64>() / d2.len() as f64).sqrt()
    }
}

#[allow(clippy::too_many_arguments)] // one report's fields, assembled in one place
fn finish(
    id: String,
    z: f64,
    z_assumed: bool,
    held_out: bool,
    beta: DVec2,
    scatter: f64,
    observed: Vec<(String, DVec2)>,
    mut predicted: Vec<PredictedImage>,
    lens: &Lens,
    f: f64,
    arrival_days: &dyn Fn(DVec2) -> Option<f64>,
) -> SourceReport {
    // Delays count from the first predicted image (from the first observed one when none was
    // predicted), so that both lists share one zero.
    let times: Vec<Option<f64>> = predicted
        .iter()
        .map(|p| arrival_days(p.position_arcsec))
        .collect();
    let observed_times: Vec<Option<f64>> = observed.iter().map(|(_, p)| arrival_days(*p)).collect();
    let first = |t: &[Option<f64>]| t.iter().flatten().copied().reduce(f64::min);
    let zero = first(&times).or_else(|| first(&observed_times));
    let since = |t: Option<f64>| Some(t? - zero?);
    for (p, t) in predicted.iter_mut().zip(&times) {
        p.delay_days = since(*t);
    }
    let observed: Vec<ImageReport> = observed
        .into_iter()
        .zip(observed_times)
        .map(|((id, position), t)| {
            let nearest = predicted.iter().map(|p| p.position_arcsec).min_by(|a, b| {
                a.distance_squared(position)
                    .total_cmp(&b.distance_squared(position))
            });
            ImageReport {
                id,
                position_arcsec: position,
                beta_arcsec: source_position(lens, f, position),
                predicted_arcsec: nearest,
                offset_arcsec: nearest.map(|p| p.distance(position)),
                magnification: Some(magnification_at(lens, f, position)),
                delay_days: since(t),
            }
        })
        .collect();
    let offsets: Vec<f64> = observed
        .iter()
        .filter_map(|o| o.offset_arcsec)
        .map(|o| o * o)
        .collect();
    SourceReport {
        id,
        z,
        z_assumed,
        z_estimate: None,
        z_interval: None,
        z_position_error_arcsec: None,
        z_open_above: false,
        z_prior: None,
        held_out,
        beta_arcsec: beta,
        scatter_arcsec: scatter,
        image_plane_rms_arcsec: (!offsets.is_empty()).then(|| rms(&offsets)),
        observed,
        predicted,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use super::image_plane_offsets2 as cost;

    #[test]
    fn the_image_plane_source_is_the_minimiser_of_the_image_plane_offsets() {
        // A tangentially stretched image (M stretches x by 8), a mildly magnified one and a
        // demagnified one with a sheared M.
        let terms = [
            (DVec2::new(1.0, 0.3), [8.0, 0.0, 0.0, 1.2]),
            (DVec2::new(1.6, -0.2), [1.5, 0.2, 0.2, 1.1]),
            (DVec2::new(0.6, 0.5), [0.4, -0.1, -0.1, 0.7]),
        ];
        let beta = image_plane_source(&terms);
        let best = cost(&terms, beta);
        // Brute force around it: no point of a fine grid does better.
        for i in -50..=50 {
            for j in -50..=50 {
                let p = beta + DVec2::new(i as f64, j as f64) * 2e-3;
                assert!(cost(&terms, p) >= best - 1e-12, "{p} beats {beta}");
            }
        }
        // The strongly stretched image pulls the source along x far more than the plain mean.
        let mean = terms.iter().map(|(b, _)| *b).sum::<DVec2>() / 3.0;
        assert!((beta.x - 1.0).abs() < 0.3 * (mean.x - 1.0).abs());
    }

    #[test]
    fn equal_weights_give_the_plain_mean() {
        let terms = [
            (DVec2::new(1.0, 2.0), [2.0, 0.0, 0.0, 2.0]),
            (DVec2::new(3.0, -2.0), [2.0, 0.0, 0.0, 2.0]),
        ];
        assert!(image_plane_source(&terms).distance(DVec2::new(2.0, 0.0)) < 1e-12);
        // Singular weights fall back to the plain mean.
        let zero = [
            (DVec2::new(1.0, 2.0), [0.0; 4]),
            (DVec2::new(3.0, 0.0), [0.0; 4]),
        ];
        assert!(image_plane_source(&zero).distance(DVec2::new(2.0, 1.0)) < 1e-12);
    }
}
