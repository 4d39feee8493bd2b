//! Stepping through the iterations: the solutions a reconstruction kept on the way
//! ([`Reconstruction::iterates`]), each drawn as the final one is: its kappa map, its critical
//! curves at the curves' source redshift and its predicted images, on the result's map. With
//! QADP the iteration count is the regulariser (`crate::method` §5); this shows what it does.
//!
//! One iterate's maps are made when it is first drawn and kept until another is asked for, so
//! that its hover read-outs and redraws cost nothing more. They cover the result's field with
//! half its pixels where that keeps the fast path ([`iterate_map_pixels`]); the last iterate
//! is the result and is drawn from its own maps.

use std::cell::{Ref, RefCell};

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::map::MapGeometry;
use crate::products::{ProductOptions, Products};
use crate::reconstruct::{images_on_maps, Reconstruction};
use crate::solver::Iterate;
use base64::Engine as _;

use super::data::{f32_base64, f32_values};
use super::run::curves_at;
use super::{AppError, SessionResult};

/// Iterates a reconstruction in the app keeps: the start, 39 counts spaced evenly in log and
/// the last (`crate::solver::iterate_schedule`), a step of about 22% between neighbours of a
/// run of 3000. About 41 × 8 bytes per unknown (the teaching example, 24 × 24
/// cells and 4 systems: 192 kB), 356 kB for the paper's system (1085 unknowns).
pub const APP_KEPT_ITERATES: usize = 41;

/// Most values (iterates x unknowns) a project file keeps of the iterates: 1 MiB as `f32`,
/// 1.4 MB of base64. The app's 41 iterates of the paper's system (1085 unknowns) are 44 505
/// values; a larger run keeps every other iterate (the first and the last always) until they fit.
pub const MAX_STORED_ITERATE_VALUES: usize = 1 << 18;

/// The kept iterates in a project file, for the iteration slider after a reload: their counts
/// and objectives, and their solutions as little-endian `f32` in base64 (the slider's maps do
/// not need more; the result itself is the project's full-precision `x`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredIterates {
    /// Unknowns of each iterate (the length of `X`).
    pub unknowns: usize,
    pub steps: Vec<IterateStep>,
    /// `steps.len() * unknowns` values, iterate after iterate.
    pub x_f32_base64: String,
}

impl StoredIterates {
    /// `iterates` for a project file, thinned to at most [`MAX_STORED_ITERATE_VALUES`] values;
    /// `None` when there are fewer than two (no slider) or they do not all have one length.
    pub fn from_iterates(iterates: &[Iterate]) -> Option<Self> {
        let unknowns = iterates.first()?.x.len();
        if unknowns == 0 || iterates.iter().any(|i| i.x.len() != unknowns) {
            return None;
        }
        let mut kept: Vec<&Iterate> = iterates.iter().collect();
        while kept.len() > 2 && kept.len() * unknowns > MAX_STORED_ITERATE_VALUES {
            let last = kept.len() - 1;
            kept = kept
                .iter()
                .enumerate()
                .filter(|(k, _)| k % 2 == 0 || *k == last)
                .map(|(_, i)| *i)
                .collect();
        }
        if kept.len() < 2 || kept.len() * unknowns > MAX_STORED_ITERATE_VALUES {
            return None;
        }
        Some(Self {
            unknowns,
            steps: kept
                .iter()
                .map(|i| IterateStep {
                    iteration: i.iteration,
                    objective: i.objective,
                })
                .collect(),
            x_f32_base64: f32_base64(kept.iter().flat_map(|i| i.x.iter().copied())),
        })
    }

    /// The iterates again, checked against the result's `unknowns`; the error says what does
    /// not fit.
    pub fn to_iterates(&self, unknowns: usize) -> Result<Vec<Iterate>, String> {
        if self.unknowns != unknowns {
            return Err(format!(
                "they have {} unknowns, the result {unknowns}",
                self.unknowns
            ));
        }
        let values = self.steps.len().saturating_mul(unknowns);
        if values > MAX_STORED_ITERATE_VALUES {
            return Err(format!(
                "{values} values, more than the {MAX_STORED_ITERATE_VALUES} a project keeps"
            ));
        }
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(&self.x_f32_base64)
            .map_err(|e| format!("not base64: {e}"))?;
        if bytes.len() != values * 4 {
            return Err(format!(
                "{} bytes for {} iterates of {unknowns} unknowns (want {})",
                bytes.len(),
                self.steps.len(),
                values * 4
            ));
        }
        let x = f32_values(&bytes);
        if x.iter().any(|v| !v.is_finite()) {
            return Err("a value is not a finite number".to_string());
        }
        Ok(self
            .steps
            .iter()
            .zip(x.chunks_exact(unknowns))
            .map(|(s, x)| Iterate {
                iteration: s.iteration,
                objective: s.objective,
                x: x.to_vec(),
            })
            .collect())
    }
}

/// One kept iterate as the app lists it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IterateStep {
    /// Iterations done (QADP updates; exchanges of the exact solver), counted over the whole
    /// run.
    pub iteration: usize,
    /// The objective there (the solver's, see [`crate::solver::Progress::objective`]).
    pub objective: f64,
}

/// The iterates of the last result, for the app's slider.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterateList {
    /// Iterations of the whole run (the last step's count).
    pub iterations: usize,
    /// The solver: "qadp", "exact" or "accelerated_gradient".
    pub method: String,
    pub steps: Vec<IterateStep>,
}

/// The maps, curves and predicted images of one iterate.
#[derive(Debug)]
pub(crate) struct IterateMaps {
    /// Which iterate (index into [`Reconstruction::iterates`]).
    pub index: usize,
    /// Its iteration count.
    pub iteration: usize,
    pub products: Products,
    /// Predicted images with `|mu| >=` [`super::SHOWN_MIN_MAGNIFICATION`] of every fitted
    /// system, from its source position at this iterate.
    pub predicted: Vec<DVec2>,
}

/// The last iterate drawn (see the module documentation).
#[derive(Debug, Default)]
pub(crate) struct IterateCache(RefCell<Option<IterateMaps>>);

impl SessionResult {
    /// The kept iterates of a reconstruction; `None` for other results and when none were
    /// kept (a run that kept none, a project saved before projects kept them).
    pub fn iterate_list(&self) -> Option<IterateList> {
        let r = self.reconstruction()?;
        if r.iterates.is_empty() {
            return None;
        }
        let method = serde_json::to_value(r.config.solver.method)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        Some(IterateList {
            iterations: r.iterations,
            method,
            steps: r
                .iterates
                .iter()
                .map(|i| IterateStep {
                    iteration: i.iteration,
                    objective: i.objective,
                })
                .collect(),
        })
    }

    /// The maps of iterate `index` at the curves' source redshift, made now unless they are
    /// the last ones made.
    pub(crate) fn at_iterate(&self, index: usize) -> Result<Ref<'_, IterateMaps>, AppError> {
        let final_products = self.products();
        let z_source = final_products.curves.z_source;
        let cache = &self.iterate_cache.0;
        let fresh = matches!(&*cache.borrow(), Some(m) if m.index == index
            && m.products.curves.z_source == z_source);
        if !fresh {
            let r = self.reconstruction().ok_or_else(|| {
                AppError::Missing("only a reconstruction has iterations to step through".into())
            })?;
            let maps = iterate_maps(r, final_products, index)?;
            *cache.borrow_mut() = Some(maps);
        }
        Ok(Ref::map(cache.borrow(), |m| {
            m.as_ref().expect("made above")
        }))
    }
}

/// Pixels on a side of an iterate's maps: half the result's when it has more than
/// [`ITERATE_MAP_MIN_PIXELS`] and the cells still fall on lattices of the coarser pixels (so
/// that the FFT convolution makes the maps), else the result's. Measured on the teaching
/// example (24 x 24 cells, 256 pixels): 2.5 s for 256 pixels, 0.5 s for 128 (natively, on a
/// loaded machine): the difference between a slide show and stepping through.
fn iterate_map_pixels(r: &Reconstruction, x: &[f64], geometry: MapGeometry) -> usize {
    let half = geometry.pixels / 2;
    if geometry.pixels % 2 != 0 || half < ITERATE_MAP_MIN_PIXELS {
        return geometry.pixels;
    }
    let Ok(grid) = r.system.grid_mass(x) else {
        return geometry.pixels;
    };
    let coarse = MapGeometry::centered(geometry.size_arcsec, half);
    let direct = |g: &MapGeometry| grid.map_plan(g).direct_cells;
    match direct(&coarse) <= direct(&geometry) {
        true => half,
        false => geometry.pixels,
    }
}

/// The fewest pixels on a side of an iterate's maps (see [`iterate_map_pixels`]).
pub const ITERATE_MAP_MIN_PIXELS: usize = 128;

/// Makes the maps of iterate `index` of `r` on the map of `final_products`.
fn iterate_maps(
    r: &Reconstruction,
    final_products: &Products,
    index: usize,
) -> Result<IterateMaps, AppError> {
    let run = |e: &dyn std::fmt::Display| AppError::Run(e.to_string());
    let count = r.iterates.len();
    let it = r.iterates.get(index).ok_or_else(|| {
        AppError::Setting(format!(
            "iterate {index}: this result kept {count} (0 to {})",
            count.saturating_sub(1)
        ))
    })?;
    let lens = r.system.reconstructed_lens(&it.x).map_err(|e| run(&e))?;
    let geometry = final_products.maps.geometry();
    let z_source = final_products.curves.z_source;
    let opts = ProductOptions {
        maps_only: true,
        z_source,
        size_arcsec: geometry.size_arcsec,
        pixels: iterate_map_pixels(r, &it.x, geometry),
        ..ProductOptions::default()
    };
    let mut products =
        Products::from_lens(&lens, final_products.plane, final_products.reference, &opts)
            .map_err(|e| run(&e))?;
    curves_at(&mut products, z_source)?;
    let betas = r.system.betas_arcsec(&it.x).map_err(|e| run(&e))?;
    let mut predicted = Vec::new();
    for (beta, &f) in betas.iter().zip(&r.system.distance_ratios) {
        let images = images_on_maps(&products.maps, f, *beta).map_err(|e| run(&e))?;
        predicted.extend(
            images
                .iter()
                .filter(|i| i.is_shown())
                .map(|i| i.position_arcsec),
        );
    }
    Ok(IterateMaps {
        index,
        iteration: it.iteration,
        products,
        predicted,
    })
}
