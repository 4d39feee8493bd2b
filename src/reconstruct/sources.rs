//! Per-system results of a reconstruction: source position, source-plane scatter, predicted
//! images (the lens equation solved forward) and their offsets from the observed images, for
//! fitted and held-out systems alike.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::images::{find_images, magnification_at, source_position, ImageSearch, SearchGrid};
use crate::inversion::LinearSystem;
use crate::maps::LensMaps;
use crate::products::Products;
use crate::profiles::{Lens, MassComponent};

use super::{Inputs, ReconstructError};

/// Predicted images solve the lens equation on the interpolated maps to this accuracy (arcsec);
/// the maps themselves are good to a fraction of their pixel.
const MAP_IMAGE_TOLERANCE_ARCSEC: f64 = 1e-3;

/// The lens as its product maps, bilinearly interpolated (deflection from the alpha maps, the
/// Hessian from kappa and gamma).
#[derive(Debug)]
struct InterpolatedLens<'a>(&'a LensMaps);

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
}

/// One predicted image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PredictedImage {
    pub position_arcsec: DVec2,
    /// Signed magnification at the system's redshift.
    pub magnification: f64,
}

/// One source system (`sources.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SourceReport {
    pub id: String,
    pub z: f64,
    /// True when the redshift was the configured default, not measured.
    pub z_assumed: bool,
    /// True when the system was left out of the fit and is predicted.
    pub held_out: bool,
    /// Source position (arcsec): the solved beta of a fitted system, or the mean back-projected
    /// observed image of a held-out one.
    pub beta_arcsec: DVec2,
    /// Root mean square distance of the back-projected constraint pixels (held out: observed
    /// images) from beta, arcsec.
    pub scatter_arcsec: f64,
    pub observed: Vec<ImageReport>,
    pub predicted: Vec<PredictedImage>,
    /// Root mean square of the observed-to-predicted offsets, arcsec.
    pub image_plane_rms_arcsec: Option<f64>,
}

/// The reports of every fitted and held-out system.
pub(super) fn report(
    system: &LinearSystem,
    x: &[f64],
    lens: &Lens,
    products: &Products,
    inputs: &Inputs<'_>,
    default_z: Option<f64>,
) -> Result<Vec<SourceReport>, ReconstructError> {
    let betas = system.betas_arcsec(x)?;
    // Images are found on the product maps, interpolated: the exact lens sums every cell and
    // galaxy at each Newton step, which for a 64 x 64 grid costs minutes per system.
    let search = ImageSearch {
        tolerance_arcsec: MAP_IMAGE_TOLERANCE_ARCSEC,
        ..ImageSearch::default()
    };
    let map_lens = InterpolatedLens(&products.maps);
    let predict = |f: f64, beta: DVec2| -> Result<Vec<PredictedImage>, ReconstructError> {
        Ok(find_images(
            &map_lens,
            SearchGrid::Maps(&products.maps),
            f,
            beta,
            &search,
        )?
        .into_iter()
        .map(|i| PredictedImage {
            position_arcsec: i.position,
            magnification: i.magnification,
        })
        .collect())
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
        let predicted = predict(f, beta)?;
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
        ));
    }
    if let Some(catalog) = inputs.catalog {
        for id in inputs.holdout {
            let Some(sys) = catalog.systems.iter().find(|s| &s.id == id) else {
                continue;
            };
            let z = sys.z.or(default_z).unwrap_or(f64::NAN);
            let Ok(f) = inputs.plane.distance_ratio(z) else {
                continue;
            };
            let observed: Vec<(String, DVec2)> = sys
                .images
                .iter()
                .map(|i| (i.id.clone(), i.position))
                .collect();
            let back: Vec<DVec2> = observed
                .iter()
                .map(|(_, p)| source_position(lens, f, *p))
                .collect();
            let beta = back.iter().copied().sum::<DVec2>() / back.len().max(1) as f64;
            let d2: Vec<f64> = back.iter().map(|b| b.distance_squared(beta)).collect();
            let predicted = predict(f, beta)?;
            reports.push(finish(
                id.clone(),
                z,
                sys.z.is_none(),
                true,
                beta,
                rms(&d2),
                observed,
                predicted,
                lens,
                f,
            ));
        }
    }
    Ok(reports)
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
    predicted: Vec<PredictedImage>,
    lens: &Lens,
    f: f64,
) -> SourceReport {
    let observed: Vec<ImageReport> = observed
        .into_iter()
        .map(|(id, position)| {
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
        held_out,
        beta_arcsec: beta,
        scatter_arcsec: scatter,
        image_plane_rms_arcsec: (!offsets.is_empty()).then(|| rms(&offsets)),
        observed,
        predicted,
    }
}
