//! The downloadable files of a result, with the content `wslap reconstruct` writes:
//! `summary.json`, `sources.json`, `convergence.json`, and the map files of the products.

use serde::Serialize;

use crate::products::Summary;
use crate::reconstruct::{ReconstructConfig, StageTimings};

use super::run::ReconstructionResult;
use super::{AppError, SessionResult};

/// `summary.json` of a reconstruction: the same fields, in the same order, as the CLI's.
#[derive(Debug, Serialize)]
pub struct ReconstructSummary<'a> {
    pub settings: &'a ReconstructConfig,
    pub status: String,
    pub iterations: usize,
    pub constraint_pixels: usize,
    pub systems_fitted: Vec<&'a str>,
    pub systems_excluded: Vec<String>,
    pub layers: Vec<&'a str>,
    pub c_per_layer: Vec<f64>,
    pub grid_mass_msun: f64,
    pub grid_cells: usize,
    pub field_center_arcsec: [f64; 2],
    pub field_width_arcsec: f64,
    pub theta_shift_arcsec: f64,
    pub einstein_radius_arcsec: f64,
    pub einstein_radius_z_source: f64,
    pub mass_within_arcsec: Vec<(f64, Option<f64>)>,
    pub image_plane_rms_arcsec: Option<f64>,
    pub holdout_image_plane_rms_arcsec: Option<f64>,
    pub warnings: &'a [String],
    pub maps: Summary,
    pub timings_ms: StageTimings,
}

impl ReconstructionResult {
    /// `C_l` per layer.
    pub fn layer_factors(&self) -> Vec<f64> {
        self.x
            .get(self.system.layer_columns())
            .map(<[f64]>::to_vec)
            .unwrap_or_default()
    }

    /// Total grid mass in Msun: `sum of the cell unknowns x mass unit`.
    pub fn grid_mass_msun(&self) -> f64 {
        let cells = self.x.get(self.system.cell_columns()).unwrap_or(&[]);
        cells.iter().sum::<f64>() * self.system.mass_unit_msun
    }

    /// Root mean square observed-to-predicted offset (arcsec) over the fitted (or held-out)
    /// systems; `None` when no image was matched.
    pub fn image_plane_rms_arcsec(&self, held_out: bool) -> Option<f64> {
        let offsets: Vec<f64> = self
            .sources
            .iter()
            .filter(|s| s.held_out == held_out)
            .flat_map(|s| s.observed.iter().filter_map(|i| i.offset_arcsec))
            .collect();
        let n = offsets.len() as f64;
        (!offsets.is_empty()).then(|| (offsets.iter().map(|o| o * o).sum::<f64>() / n).sqrt())
    }
}

impl SessionResult {
    /// `summary.json`: the CLI's reconstruction summary, or the map summary of a forward model
    /// or look-up (what `wslap maps` writes).
    pub fn summary_json(&self) -> Result<String, AppError> {
        let maps = self.products.summary();
        let Some(r) = &self.reconstruction else {
            return pretty(&maps);
        };
        let s = &r.system;
        let summary = ReconstructSummary {
            settings: &r.config,
            status: r.status.clone(),
            iterations: r.iterations,
            constraint_pixels: s.constraints.pixels.len(),
            systems_fitted: s
                .constraints
                .systems
                .iter()
                .map(|x| x.id.as_str())
                .collect(),
            systems_excluded: s
                .constraints
                .excluded
                .iter()
                .map(|e| format!("{} ({:?})", e.id, e.reason))
                .collect(),
            layers: s.layers.iter().map(|l| l.name.as_str()).collect(),
            c_per_layer: r.layer_factors(),
            grid_mass_msun: r.grid_mass_msun(),
            grid_cells: s.grid.cells.len(),
            field_center_arcsec: s.grid.center.to_array(),
            field_width_arcsec: s.grid.width_arcsec,
            theta_shift_arcsec: s.theta_shift_arcsec,
            einstein_radius_arcsec: maps.einstein_radius_arcsec,
            einstein_radius_z_source: maps.z_source,
            mass_within_arcsec: maps.mass_within_arcsec.clone(),
            image_plane_rms_arcsec: r.image_plane_rms_arcsec(false),
            holdout_image_plane_rms_arcsec: r.image_plane_rms_arcsec(true),
            warnings: &r.warnings,
            maps,
            timings_ms: r.timings,
        };
        pretty(&summary)
    }

    /// `sources.json` (empty list without a reconstruction).
    pub fn sources_json(&self) -> Result<String, AppError> {
        match &self.reconstruction {
            Some(r) => pretty(&r.sources),
            None => Ok("[]".to_string()),
        }
    }

    /// `convergence.json` (empty list without a reconstruction).
    pub fn convergence_json(&self) -> Result<String, AppError> {
        match &self.reconstruction {
            Some(r) => pretty(&r.convergence),
            None => Ok("[]".to_string()),
        }
    }
}

/// Pretty JSON, as the CLI writes it.
pub(super) fn pretty<T: Serialize + ?Sized>(value: &T) -> Result<String, AppError> {
    serde_json::to_string_pretty(value).map_err(|e| AppError::Run(e.to_string()))
}
