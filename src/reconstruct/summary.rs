//! `summary.json` of a reconstruction, shared by `wslap reconstruct` and the browser app (which
//! keeps a solved system without the rest of a [`super::Reconstruction`], e.g. one restored
//! from a project file), and the quantities it reports.

use serde::Serialize;

use crate::inversion::kappa_gamma;
use crate::profiles::MassComponent;

use super::{
    CrossvalTotals, FreeZSummary, ReconstructConfig, SourceReport, StageTimings, StrengthChoice,
    Verdict,
};
use crate::inversion::{external_shear_of, member_layers_with, ExternalShearFit, LinearSystem};
use crate::products::Summary;

/// A solved system: what the summary is made of.
#[derive(Debug, Clone, Copy)]
pub struct Solved<'a> {
    pub config: &'a ReconstructConfig,
    pub system: &'a LinearSystem,
    /// The solution `X`.
    pub x: &'a [f64],
    pub iterations: usize,
    pub sources: &'a [SourceReport],
    pub warnings: &'a [String],
    pub timings: StageTimings,
    /// How an "auto" regulariser strength was chosen.
    pub strength_choice: Option<&'a StrengthChoice>,
    /// The systems whose redshift was estimated, when there were any.
    pub free_z: Option<&'a FreeZSummary>,
}

impl<'a> Solved<'a> {
    /// `C_l` per layer (empty when `x` is too short for the system).
    pub fn layer_factors(&self) -> Vec<f64> {
        self.x
            .get(self.system.layer_columns())
            .map(<[f64]>::to_vec)
            .unwrap_or_default()
    }

    /// `C_l` of the member layers alone (not an external shear's): the factors "C" a user reads.
    pub fn member_factors(&self) -> Vec<f64> {
        member_layers_with(&self.system.layers, self.layer_factors())
            .map(|(_, c)| c)
            .collect()
    }

    /// The fitted external shear, when the run has one (`grid.external_shear_sigma`).
    pub fn external_shear(&self) -> Option<ExternalShearFit> {
        external_shear_of(&self.system.layers, &self.layer_factors())
    }

    /// Why no external shear was fitted where the settings ask for one
    /// (`grid.external_shear_sigma`), in words for the run's line and the app's caption;
    /// `None` when one was fitted or none was asked for. The one reason today: the chosen
    /// regulariser is least mass ([`ReconstructConfig::external_shear_fitted`]).
    pub fn external_shear_left_out(&self) -> Option<&'static str> {
        let asked = self.config.grid.external_shear_sigma.is_some();
        (asked && self.external_shear().is_none()).then_some("the least-mass regulariser fits none")
    }

    /// Total mass of the grid cells in Msun: the sum of the cell unknowns times the mass unit.
    pub fn grid_mass_msun(&self) -> f64 {
        let cells = self.x.get(self.system.cell_columns()).unwrap_or(&[]);
        cells.iter().sum::<f64>() * self.system.mass_unit_msun
    }

    /// The offsets (arcsec) between observed images and their nearest predicted images over the
    /// fitted (or, with `held_out`, the held-out) systems.
    fn image_offsets_arcsec(&self, held_out: bool) -> Vec<f64> {
        image_offsets_arcsec(self.sources.iter().filter(|s| s.held_out == held_out))
    }

    /// Root mean square of the offsets between observed and predicted images, arcsec, over the
    /// fitted (or, with `held_out`, the held-out) systems; `None` when no image was matched.
    pub fn image_plane_rms_arcsec(&self, held_out: bool) -> Option<f64> {
        rms_arcsec(&self.image_offsets_arcsec(held_out))
    }

    /// Median of the same offsets, arcsec (the mean of the middle two for an even count). The
    /// rms answers for the worst images: one whose source lies just outside the model's caustic
    /// has no predicted image near it, and its offset of many arcsec dominates the rms (AS1063:
    /// rms 4.1, median 0.2 arcsec). The median says how well the typical image is reproduced.
    pub fn image_offset_median_arcsec(&self, held_out: bool) -> Option<f64> {
        median_arcsec(self.image_offsets_arcsec(held_out))
    }

    /// How the map fits the weak-lensing galaxies (`None` without any).
    pub fn weak_lensing(&self) -> Option<WeakLensingFit> {
        let s = self.system;
        if s.shear.is_empty() {
            return None;
        }
        let lens = s.reconstructed_lens(self.x).ok()?;
        let chi2 = s.shear.chi2_per_galaxy(|p| kappa_gamma(lens.hessian(p)))?;
        let field = |c: &&crate::inversion::Cell| s.grid.contains(c.center, 0.0);
        let ring: Vec<_> = s.grid.cells.iter().filter(|c| !field(c)).collect();
        Some(WeakLensingFit {
            catalogue: s.shear.source_name.clone(),
            arclets: s.shear.len(),
            shape_noise: self.config.shear.shape_noise,
            chi2_per_arclet: chi2,
            ring_cells: ring.len(),
            ring_cell_arcsec: ring.first().map(|c| c.size_arcsec),
            ring_extent_arcsec: s.grid.extent_arcsec(),
        })
    }

    /// `summary.json`, with `status` as written ("Completed", "Cancelled", ...), the map
    /// summary of the products and the verdict on them.
    pub fn summary(
        self,
        status: String,
        maps: Summary,
        verdict: Verdict,
    ) -> ReconstructSummary<'a> {
        let s = self.system;
        ReconstructSummary {
            settings: self.config,
            status,
            iterations: self.iterations,
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
                .map(|e| format!("{} ({})", e.id, e.reason))
                .collect(),
            layers: member_layers_with(&s.layers, std::iter::repeat(()))
                .map(|(l, _)| l.name.as_str())
                .collect(),
            c_per_layer: self.member_factors(),
            c_independence: member_layers_with(&s.layers, s.layer_independence())
                .map(|(_, share)| *share)
                .collect(),
            external_shear: self.external_shear(),
            external_shear_left_out: self.external_shear_left_out(),
            c_unmeasured: s.members_unmeasured(),
            grid_mass_msun: self.grid_mass_msun(),
            grid_cells: s.grid.cells.len(),
            field_center_arcsec: s.grid.center.to_array(),
            field_width_arcsec: s.grid.width_arcsec,
            theta_shift_arcsec: s.theta_shift_arcsec,
            einstein_radius_arcsec: maps.einstein_radius_arcsec,
            einstein_radius_z_source: maps.z_source,
            mass_within_arcsec: maps.mass_within_arcsec.clone(),
            image_plane_rms_arcsec: self.image_plane_rms_arcsec(false),
            holdout_image_plane_rms_arcsec: self.image_plane_rms_arcsec(true),
            image_offset_median_arcsec: self.image_offset_median_arcsec(false),
            holdout_image_offset_median_arcsec: self.image_offset_median_arcsec(true),
            verdict,
            crossval: None,
            regulariser_weight: s.terms.penalty_weight,
            strength_choice: self.strength_choice,
            free_redshifts: self.free_z,
            weak_lensing: self.weak_lensing(),
            warnings: self.warnings,
            maps,
            timings_ms: self.timings,
        }
    }
}

/// `summary.json` of a reconstruction.
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
    /// Per layer, how much the data measure `C_l`: the share of the layer's deflection at the
    /// constraints that the other unknowns cannot reproduce (0 to 1; `None` when not computed,
    /// above [`crate::solver::INDEPENDENCE_MAX_UNKNOWNS`] unknowns). See
    /// [`LinearSystem::measurability_warnings`].
    pub c_independence: Vec<Option<f64>>,
    /// The tidal field of mass beyond the grid, fitted with the map
    /// ([`crate::inversion::external_shear_layers`]); `None` without one.
    pub external_shear: Option<ExternalShearFit>,
    /// Why no external shear was fitted although the settings ask for one
    /// ([`super::Reconstruction::external_shear_left_out`]); `None` otherwise.
    pub external_shear_left_out: Option<&'static str>,
    /// True when the data hardly measure `C` ([`LinearSystem::members_unmeasured`]; the
    /// warnings say why).
    pub c_unmeasured: bool,
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
    pub image_offset_median_arcsec: Option<f64>,
    pub holdout_image_offset_median_arcsec: Option<f64>,
    /// How far the map can be trusted, and why ([`Verdict::assess`]; with a cross-validation,
    /// its held-out images count as held out).
    pub verdict: Verdict,
    /// The totals of a cross-validation of the same data and settings (`--folds`; absent
    /// without one): `crossval.json` has the folds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crossval: Option<CrossvalTotals>,
    /// The regulariser's absolute weight `lambda` in the objective (0 without one).
    pub regulariser_weight: Option<f64>,
    /// The cross-validation curve an "auto" strength was chosen from (candidate, held-out
    /// median and rms), and the strength chosen.
    pub strength_choice: Option<&'a StrengthChoice>,
    /// The systems whose redshift was estimated (`sources.json` has each estimate), and the
    /// fitted median offset of the others without and with them.
    pub free_redshifts: Option<&'a FreeZSummary>,
    /// The weak-lensing fit, with an arclet catalogue (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weak_lensing: Option<WeakLensingFit>,
    pub warnings: &'a [String],
    pub maps: Summary,
    pub timings_ms: StageTimings,
}

/// How a map fits the weak-lensing galaxies (`summary.json`'s `weak_lensing`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WeakLensingFit {
    /// The arclet catalogue's file name.
    pub catalogue: String,
    /// Galaxies fitted (those behind the lens).
    pub arclets: usize,
    /// The shape noise `sigma_e` of the rows' weights.
    pub shape_noise: f64,
    /// `chi^2` of the reduced shear per galaxy, `sum |g - e|^2 / sigma_e^2 / N`
    /// ([`crate::ShearSet::chi2_per_galaxy`]): about 2 when the map fits the ellipticities to
    /// their shape noise.
    pub chi2_per_arclet: f64,
    /// Cells of the ring of coarser cells around the grid's field, their side (arcsec) and
    /// the side of the square the grid and ring cover (arcsec).
    pub ring_cells: usize,
    pub ring_cell_arcsec: Option<f64>,
    pub ring_extent_arcsec: f64,
}

/// The offsets (arcsec) of the observed images of `sources` from their nearest predicted
/// images (images without a predicted one have none).
pub(super) fn image_offsets_arcsec<'s>(
    sources: impl Iterator<Item = &'s SourceReport>,
) -> Vec<f64> {
    sources
        .flat_map(|s| s.observed.iter().filter_map(|i| i.offset_arcsec))
        .collect()
}

/// Root mean square of `offsets`; `None` when there are none.
pub(super) fn rms_arcsec(offsets: &[f64]) -> Option<f64> {
    (!offsets.is_empty())
        .then(|| (offsets.iter().map(|o| o * o).sum::<f64>() / offsets.len() as f64).sqrt())
}

/// Median of `offsets` (the mean of the middle two for an even count); `None` when there are
/// none.
pub(super) fn median_arcsec(mut offsets: Vec<f64>) -> Option<f64> {
    offsets.sort_by(f64::total_cmp);
    let n = offsets.len();
    (n > 0).then(|| 0.5 * (offsets[(n - 1) / 2] + offsets[n / 2]))
}
