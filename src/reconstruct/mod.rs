//! The WSLAP+ reconstruction, end to end: constraints from the images, the cell grid and the
//! member-galaxy layers, the linear system, QADP, and the products of the solution (maps,
//! curves, per-system source positions, predicted images and their offsets, hold-out tests).
//!
//! The pipeline of the paper (Sendra et al., section 2) and [method §3] to [§6].
//!
//! [method §3]: crate::method#3-the-linear-system
//! [§6]: crate::method#6-products

mod config;
mod crossval;
mod dataset;
mod ensemble;
mod free_z;
mod memory;
mod sources;
mod summary;
mod verdict;

use glam::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use config::{ProductConfig, ReconstructConfig, SolverConfig, SolverMethod};
pub use crossval::{
    cross_validate, fitted_system_ids, fold_groups, holdable_sources, holdable_system_ids,
    CrossValidation, CrossvalTotals, FoldRun, KappaSpread, PredictedSystem, DEFAULT_FOLDS,
};
pub(crate) use dataset::arclet_unknown_z;
pub use dataset::{Dataset, DatasetError, InputText, InputTexts, PAR_GALAXY_MAX_LSTAR};
pub use ensemble::{
    check_ensemble_size, run_ensemble, Calibration, Ensemble, EnsembleMaps, EnsembleMember,
    EnsemblePlan, LeftOutImage, MemberDraw, MemberRun, CALIBRATION_MIN_IMAGES,
    CALIBRATION_MIN_PREDICTIONS, MAX_ENSEMBLE_MEMBERS,
};
pub(crate) use free_z::fit_estimates_in;
pub use free_z::{
    estimate_redshift, EstimatedRedshifts, FreeZSummary, RedshiftEstimate, FALLBACK_SIGMA_ARCSEC,
};
pub use memory::{
    layer_count, Bytes, Heap, MemoryEstimate, MemoryLimit, RunSize, TooMuchMemory,
    FALLBACK_MEMORY_LIMIT_BYTES, WASM_MEMORY_LIMIT_BYTES,
};
pub use sources::{
    image_regions, images_on_maps, source_on_maps, ArrivalTimes, ImageReport, InterpolatedLens,
    PredictedImage, SourceReport, IMAGE_REGION_RADIUS_ARCSEC, SHOWN_MIN_MAGNIFICATION,
};
pub use summary::{ReconstructSummary, Solved, WeakLensingFit};
pub use verdict::{
    members_with_own_curves, BcgFacts, Crowding, HoldoutSource, SystemCheck, Trust, Verdict,
    VerdictInputs, FAR_MORE_PREDICTED_FACTOR, FLAG_OFFSET_ARCSEC, GOOD_FIT_OFFSET_ARCSEC,
    GOOD_HOLDOUT_OFFSET_ARCSEC, LOST_IMAGE_ARCSEC, LOST_SYSTEMS_SHARE, MAIN_CURVE_MIN_SHARE,
    ON_CURVE_MAGNIFICATION, ON_CURVE_SHARE, SMALL_SCALE_OFFSET_ARCSEC, WORST_SHOWN,
};

use crate::catalog::{ArcletCatalog, ImageCatalog, Member, MemberCatalog};
use crate::cosmology::LensPlane;
use crate::image_search::ImageError;
use crate::inversion::{
    build_constraints, build_member_layers, capped_inverse_jacobian, member_layers_with,
    missing_bcg_warning, CellGrid, ConstraintError, ConstraintSet, ConstraintSource, GridError,
    GridMass, Layer, LinearSystem, MemberConfig, MembersError, ObjectiveTerms, Regulariser,
    ShearSet, Strength, SystemError,
};
use crate::map::MapGeometry;
use crate::products::{ProductOptions, Products, ProductsError};
use crate::profiles::{Lens, MassComponent};
use crate::sky::SkyReference;
use crate::solver::{
    accelerated_gradient, minimise_exact, Control, Iterate, QadpProblem, SolveOutcome, SolveStatus,
    SolverError,
};

/// What can stop a reconstruction.
#[derive(Debug, Error)]
pub enum ReconstructError {
    #[error("{source_name}: {message}")]
    Config {
        source_name: String,
        message: String,
    },
    #[error(transparent)]
    BadFieldValue(#[from] crate::error::BadFieldValue),
    #[error(transparent)]
    Constraints(#[from] ConstraintError),
    #[error(transparent)]
    Grid(#[from] GridError),
    #[error(transparent)]
    Members(#[from] MembersError),
    #[error(transparent)]
    System(#[from] SystemError),
    #[error(transparent)]
    Solver(#[from] SolverError),
    #[error(transparent)]
    Images(#[from] ImageError),
    #[error(transparent)]
    Products(#[from] ProductsError),
    #[error(transparent)]
    TooLarge(#[from] crate::limits::TooLarge),
    #[error(transparent)]
    Memory(#[from] TooMuchMemory),
    #[error("no system is left to constrain the lens ({0})")]
    NoConstraints(String),
    #[error("cancelled")]
    Cancelled,
    #[error("{}", folds_message(*folds, *systems))]
    Folds { folds: usize, systems: usize },
    #[error("an ensemble redraws the fitted systems and needs at least 2 of them, and {} fitted here: run without an ensemble", if *systems == 1 { "1 is".to_string() } else { format!("{systems} are") })]
    EnsembleSystems { systems: usize },
}

/// Why `folds` groups cannot be held out in turn from `systems` systems that can be (those
/// fitted at a redshift of their own), and what to do.
fn folds_message(folds: usize, systems: usize) -> String {
    let which = "systems with a redshift of their own, the knots of one galaxy (2.1, 2.2) \
                 counted once; a system whose redshift is estimated is never held out";
    match (folds, systems) {
        (_, 0 | 1) => format!(
            "folds = {folds}: holding systems out needs at least 2 that can be, and there {} \
             ({which}): run without folds",
            if systems == 1 { "is 1" } else { "are none" }
        ),
        (0 | 1, _) => format!(
            "folds = {folds}: cross-validation holds out at least 2 groups of systems in turn: \
             use folds from 2 to {systems} ({which})"
        ),
        _ => format!(
            "folds = {folds}: more groups than the {systems} systems that can be held out: \
             use folds from 2 to {systems} ({which})"
        ),
    }
}

/// Where the member-galaxy layers come from.
#[derive(Debug, Clone, Copy)]
pub enum LayerSource<'a> {
    /// No galaxies: the grid alone (the paper's case (i)).
    None,
    /// Layers built from a member catalogue with the `members` settings.
    Members(&'a MemberCatalog),
    /// Layers given directly (e.g. the true galaxies of a simulation).
    Given(&'a [Layer]),
}

/// The data of one reconstruction.
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    pub images: ConstraintSource<'a>,
    pub layers: LayerSource<'a>,
    pub plane: LensPlane,
    pub reference: Option<SkyReference>,
    /// Ids of systems left out of the fit and predicted afterwards.
    pub holdout: &'a [String],
    /// The image catalogue, for per-image offsets and hold-out predictions (`None` for arcs).
    pub catalog: Option<&'a ImageCatalog>,
    /// Weak-lensing galaxies (an arclet catalogue in the same frame), fitted with the `shear`
    /// settings; `None`: strong lensing alone.
    pub shear: Option<&'a ArcletCatalog>,
}

/// One report of the QADP iteration (`convergence.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvergenceRecord {
    /// Solve pass: the refinement levels (0 = the regular grid), then one per update of the
    /// image-plane weights.
    pub level: usize,
    pub iteration: usize,
    pub objective: f64,
    pub grid_mass_msun: f64,
    /// `C_l` per layer.
    pub c: Vec<f64>,
    /// Source position `beta` of each fitted system at this iteration, arcsec (frame shift
    /// removed), in the order of the constraint systems.
    pub beta_arcsec: Vec<DVec2>,
}

impl ConvergenceRecord {
    /// The record of solver state `p` of `system` in solve pass `level`.
    fn of(system: &LinearSystem, level: usize, p: &crate::solver::Progress) -> Self {
        let shift = system.theta_shift_arcsec;
        Self {
            level,
            iteration: p.iteration,
            objective: p.objective,
            grid_mass_msun: p.x[system.cell_columns()].iter().sum::<f64>() * system.mass_unit_msun,
            c: member_layers_with(&system.layers, &p.x[system.layer_columns()])
                .map(|(_, &c)| c)
                .collect(),
            beta_arcsec: system
                .beta_x_columns()
                .zip(system.beta_y_columns())
                .map(|(i, j)| DVec2::new(p.x[i] - shift, p.x[j] - shift))
                .collect(),
        }
    }
}

/// Wall-clock time of each stage in milliseconds. The first four are the final map's; an
/// "auto" strength's trials and the redshift estimates come before it, so `total_ms` is the
/// whole run's.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StageTimings {
    /// Building the final map's linear system (every pass of it).
    pub system_ms: f64,
    /// Solving it.
    pub solve_ms: f64,
    /// Its maps and curves.
    pub products_ms: f64,
    /// Its sources, predicted images and verdict inputs.
    pub sources_ms: f64,
    /// The cross-validated trials of an "auto" strength run in this process (both rounds; the
    /// app runs them in other workers, which this does not count).
    pub choice_ms: f64,
    /// The whole run in this process, from the settings' check to the result (0 for a result
    /// rebuilt from a project file).
    pub total_ms: f64,
}

/// How a reconstruction's solution came about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunStatus {
    /// Solved now; the solver's status says how its run ended.
    Solved(SolveStatus),
    /// Rebuilt from a stored solution `X` (a project file), not solved again.
    Restored,
}

impl RunStatus {
    /// The status as `summary.json` and the app write it: the solver's ("Completed",
    /// "Converged", "Cancelled", "Diverged") or "Restored".
    pub fn name(self) -> &'static str {
        match self {
            Self::Solved(s) => s.name(),
            Self::Restored => "Restored",
        }
    }
}

impl std::fmt::Display for RunStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A solved run compares equal to the solver's status it ended with.
impl PartialEq<SolveStatus> for RunStatus {
    fn eq(&self, other: &SolveStatus) -> bool {
        *self == Self::Solved(*other)
    }
}

/// The result of a reconstruction.
#[derive(Debug)]
pub struct Reconstruction {
    pub config: ReconstructConfig,
    pub system: LinearSystem,
    /// The solution `X` (cell masses in `system.mass_unit_msun`, C per layer, shifted betas).
    pub x: Vec<f64>,
    pub status: RunStatus,
    pub iterations: usize,
    pub convergence: Vec<ConvergenceRecord>,
    /// Solutions on the way to `x` (`solver.keep_iterates` of them at most; none by default
    /// or after a restore), at increasing iteration counts of the whole run, the last being
    /// `x`. All are of `system`: those of a grid refined afterwards are dropped, the passes of
    /// the image-plane weights (same unknowns) follow one another.
    pub iterates: Vec<Iterate>,
    pub lens: Lens,
    pub products: Products,
    pub sources: Vec<SourceReport>,
    pub warnings: Vec<String>,
    pub timings: StageTimings,
    /// How the regulariser's strength was chosen, when it was "auto".
    pub strength_choice: Option<StrengthChoice>,
    /// The systems whose redshift was estimated, when there were any.
    pub free_z: Option<FreeZSummary>,
    /// Positions of the member galaxies of the catalogue (arcsec; none for layers given
    /// directly), for the verdict's members with critical curves of their own.
    pub member_positions_arcsec: Vec<DVec2>,
    /// What the run found about the cluster's brightest galaxies (the warnings say it in
    /// words: `missing_bcg_warning` in the inversion, [`MemberCatalog::fitted_bcgs`]).
    pub bcg: BcgFacts,
}

/// What one candidate of an "auto" strength sets: the regulariser, its strength and the
/// grid's cells a side.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    pub regulariser: Regulariser,
    pub strength: f64,
    /// Cells a side (`None`: `grid.cells` of the settings).
    #[serde(default)]
    pub cells: Option<usize>,
}

impl Candidate {
    /// `config` with this candidate's regulariser, strength and grid.
    pub fn apply(&self, config: &ReconstructConfig) -> ReconstructConfig {
        let mut c = config.clone();
        c.objective.strength = Strength::Value(self.strength);
        c.objective.regulariser = self.regulariser;
        if let Some(cells) = self.cells {
            c.grid.cells = cells;
        }
        c
    }

    /// [`Self::apply`] for a fit whose lens alone serves (a trial of the "auto" choice): its
    /// maps at most [`CHOICE_MAP_PIXELS`] a side and no curves.
    pub fn apply_for_trial(&self, config: &ReconstructConfig) -> ReconstructConfig {
        let mut c = self.apply(config);
        c.products.pixels = c.products.pixels.min(CHOICE_MAP_PIXELS);
        c.products.maps_only = true;
        c
    }
}

/// One candidate (regulariser, strength, grid) of an "auto" strength and how well it
/// predicted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StrengthCandidate {
    #[serde(default)]
    pub regulariser: Regulariser,
    pub strength: f64,
    /// The grid's cells a side (`None` in results saved before grids were candidates: the
    /// settings' `grid.cells`).
    #[serde(default)]
    pub cells: Option<usize>,
    /// Median and rms offset of the held-out images from their predictions (arcsec) over the
    /// folds of the cross-validation (`None` when none was matched).
    pub holdout_median_arcsec: Option<f64>,
    pub holdout_rms_arcsec: Option<f64>,
    /// Held-out images with no predicted image at all.
    pub holdout_unmatched: usize,
    /// Median offset of the fitted images in the folds (arcsec).
    pub fit_median_arcsec: Option<f64>,
    /// Per held-out system, its images' offsets from their predictions (arcsec; `None` for an
    /// image with no predicted image): what an ensemble member re-scores the candidates on
    /// for the systems it drew ([`StrengthChoice::best_for`]).
    #[serde(default)]
    pub holdout_by_system: Vec<SystemOffsets>,
}

impl StrengthCandidate {
    /// What this candidate sets (its regulariser, strength and grid).
    pub fn candidate(&self) -> Candidate {
        Candidate {
            regulariser: self.regulariser,
            strength: self.strength,
            cells: self.cells,
        }
    }
}

/// The held-out images of one system and their offsets (arcsec; `None`: no predicted image).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SystemOffsets {
    pub id: String,
    pub offsets_arcsec: Vec<Option<f64>>,
}

/// The curve "auto" chose the strength from (`summary.json`'s `strength_choice`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StrengthChoice {
    pub folds: usize,
    pub candidates: Vec<StrengthCandidate>,
    /// The strength used.
    pub chosen: f64,
    /// The regulariser used with it.
    pub chosen_regulariser: Regulariser,
    /// The grid's cells a side used with it (`None`: the settings' `grid.cells`).
    #[serde(default)]
    pub chosen_cells: Option<usize>,
    /// Why it was chosen, in words.
    pub rule: String,
    /// What the systems with a redshift of their own chose before the others' redshifts were
    /// estimated on its map, when the choice was then made again with those fitted too
    /// ([`second_round`]); `None` when no redshift was estimated.
    #[serde(default)]
    pub before_estimates: Option<Candidate>,
    /// The candidates that predicted best but whose maps the verdict would distrust for
    /// crowding, in the order they were passed over ([`avoid_crowded_map`]); empty when the
    /// chosen candidate's map was the first made.
    #[serde(default)]
    pub crowded_maps: Vec<CrowdedMap>,
}

/// A candidate passed over because its map was crowded ([`avoid_crowded_map`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CrowdedMap {
    #[serde(flatten)]
    pub candidate: Candidate,
    #[serde(flatten)]
    pub crowding: Crowding,
}

impl Reconstruction {
    /// The solved system, for the quantities below and `summary.json`.
    pub fn solved(&self) -> Solved<'_> {
        Solved {
            config: &self.config,
            system: &self.system,
            x: &self.x,
            iterations: self.iterations,
            sources: &self.sources,
            warnings: &self.warnings,
            timings: self.timings,
            strength_choice: self.strength_choice.as_ref(),
            free_z: self.free_z.as_ref(),
        }
    }

    /// `C_l` per layer (the member layers', then an external shear's four).
    pub fn layer_factors(&self) -> Vec<f64> {
        self.solved().layer_factors()
    }

    /// `C_l` of the member layers alone: the factors "C" a user reads.
    pub fn member_factors(&self) -> Vec<f64> {
        self.solved().member_factors()
    }

    /// The fitted external shear, when the run has one.
    pub fn external_shear(&self) -> Option<crate::inversion::ExternalShearFit> {
        self.solved().external_shear()
    }

    /// Why no external shear was fitted where the settings ask for one; `None` when one was
    /// fitted or none was asked for (`summary.json`'s `external_shear_left_out`).
    pub fn external_shear_left_out(&self) -> Option<&'static str> {
        self.solved().external_shear_left_out()
    }

    /// Total mass of the grid cells in Msun.
    pub fn grid_mass_msun(&self) -> f64 {
        self.solved().grid_mass_msun()
    }

    /// Root mean square of the offsets between observed and predicted images, arcsec, over the
    /// fitted (not held-out) systems; `None` when no image was matched.
    pub fn image_plane_rms_arcsec(&self, held_out: bool) -> Option<f64> {
        self.solved().image_plane_rms_arcsec(held_out)
    }

    /// See [`Solved::image_offset_median_arcsec`].
    pub fn image_offset_median_arcsec(&self, held_out: bool) -> Option<f64> {
        self.solved().image_offset_median_arcsec(held_out)
    }

    /// Fits the systems whose redshift this run estimated as it did, in runs with
    /// `constraints` (a cross-validation of the same data fits them in every fold,
    /// [`cross_validate`]): at their most probable redshifts (`constraints.z_estimates`), with
    /// the image-plane error their redshifts' uncertainty adds (`constraints.z_estimate_errors`).
    pub fn fit_estimates_in(&self, constraints: &mut crate::inversion::ConstraintConfig) {
        free_z::fit_estimates_in(&self.sources, constraints);
    }

    /// The verdict on the map ([`Verdict::assess`]), with the curves at the products'
    /// source redshift.
    pub fn verdict(&self) -> Verdict {
        self.verdict_after(None)
    }

    /// [`Self::verdict`] once `cv`, a cross-validation of the same inputs and settings, has
    /// run: its held-out images count as held out (when it completed and the run holds no
    /// system out itself).
    pub fn verdict_after(&self, cv: Option<&CrossValidation>) -> Verdict {
        self.verdict_with(self.products.summary().tangential_main_area_share, cv)
    }

    fn verdict_with(&self, main_curve_share: Option<f64>, cv: Option<&CrossValidation>) -> Verdict {
        let inputs = VerdictInputs {
            curves: Some((&self.products.curves, self.products.maps.geometry())),
            main_curve_share,
            members_arcsec: &self.member_positions_arcsec,
            c_unmeasured: self.system.members_unmeasured(),
            bcg: self.bcg.clone(),
            crossval_holdout_median_arcsec: cv
                .filter(|c| c.completed())
                .and_then(|c| c.totals.holdout_image_offset_median_arcsec),
            choice_holdout_median_arcsec: self
                .strength_choice
                .as_ref()
                .and_then(StrengthChoice::chosen_holdout_median_arcsec),
        };
        Verdict::assess(&self.sources, inputs)
    }

    /// `summary.json` (what `wslap reconstruct` writes).
    pub fn summary(&self) -> ReconstructSummary<'_> {
        self.summary_after(None)
    }

    /// [`Self::summary`] once `cv`, a cross-validation of the same inputs and settings, has
    /// run (`--folds`): with its totals, and the verdict it informs
    /// ([`Self::verdict_after`]).
    pub fn summary_after(&self, cv: Option<&CrossValidation>) -> ReconstructSummary<'_> {
        let maps = self.products.summary();
        let verdict = self.verdict_with(maps.tangential_main_area_share, cv);
        let mut summary = self
            .solved()
            .summary(self.status.name().to_string(), maps, verdict);
        summary.crossval = cv.map(|c| c.totals.clone());
        summary
    }
}

/// Runs the reconstruction. `progress` sees every QADP report and may cancel; a cancelled run
/// still returns the products of the last iterate (its status says `Cancelled`). Every
/// parallel section of the run (rows, normal equations, QADP passes, maps, image search) uses
/// at most `system.threads` threads (0: all cores), and no more than a limit set around it
/// ([`crate::threads::with_limit`]).
///
/// Systems without a redshift are first left out, then have it estimated on the lens of the
/// others and are fitted at it (the `free_z` module).
pub fn reconstruct(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    reconstruct_free_z(inputs, config, true, progress)
}

/// [`reconstruct`], and with `free_z` false without estimating any redshift (the systems
/// without one stay out: cross-validation folds, which compare the fits of the same systems).
/// Either way an "auto" choice whose map is crowded gives way to the next candidates
/// ([`with_uncrowded_map`]): a fold runs the method the whole run does.
pub(crate) fn reconstruct_free_z(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    free_z: bool,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    let total = crate::products::Clock::start();
    config.validate()?;
    check_source_redshifts(inputs, config)?;
    crate::threads::with_limit(config.system.threads, || check_memory(inputs, config))?;
    let trials = crate::products::Clock::start();
    let choice = crate::threads::with_limit(config.system.threads, || {
        choose_strength(inputs, config, progress)
    })?;
    let choice_ms = trials.ms();
    let mut r = match choice {
        Some(choice) => with_choice(inputs, config, choice, free_z, progress).and_then(|r| {
            crate::threads::with_limit(config.system.threads, || {
                let r = choose_again_with_estimates(inputs, r, progress)?;
                with_uncrowded_map(inputs, r, progress)
            })
        }),
        None => crate::threads::with_limit(config.system.threads, || {
            let first = reconstruct_limited(inputs, config, progress)?;
            if !free_z {
                return Ok(first);
            }
            let r = free_z::add_free_systems(inputs, config, first, None, &[], progress)?;
            Ok(free_z::fit_consistently(inputs, config, &r, None, progress)?.unwrap_or(r))
        }),
    }?;
    with_own_priors(&mut r, config);
    r.timings.choice_ms += choice_ms;
    r.timings.total_ms = total.ms();
    Ok(r)
}

/// Marks each source that has a redshift prior of its own with it (`sources.json`).
fn with_own_priors(r: &mut Reconstruction, config: &ReconstructConfig) {
    for s in &mut r.sources {
        s.z_prior = config.constraints.z_priors.get(&s.id).copied();
    }
}

/// The estimated peak memory of [`reconstruct`] with `config` on `inputs`, checked against
/// [`MemoryLimit::here`] before any work (the `memory` module says what it counts). The
/// member layers are counted from `members.layers` and the catalogue (an upper bound), with an
/// external shear's four when one may be fitted; an
/// "auto" strength's candidates, which natively run side by side, count once per core.
pub fn check_memory(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
) -> Result<MemoryEstimate, ReconstructError> {
    let constraints = build_constraints(inputs.images, &config.constraints, inputs.holdout)?;
    let layers = match inputs.layers {
        LayerSource::None => 0,
        LayerSource::Given(layers) => layers.len(),
        LayerSource::Members(catalog) => {
            layer_count(config.members.layers, Some(catalog.members.len()))
        }
    } + if fits_external_shear(config) { 4 } else { 0 };
    let (pixels, systems) = (constraints.pixels.len(), constraints.systems.len());
    let mut estimate = RunSize::of(config, pixels, systems, layers).memory(config);
    if config.objective.strength.value().is_none() {
        let mut trial = config.clone();
        trial.products.pixels = trial.products.pixels.min(CHOICE_MAP_PIXELS);
        let mut size = RunSize::of(&trial, pixels, systems, layers);
        size.side_by_side = crate::threads::available().min(strength_candidates(config).len());
        let trials = size.memory(&trial);
        if trials.bytes > estimate.bytes {
            estimate = trials;
        }
    }
    estimate.check(MemoryLimit::here())?;
    Ok(estimate)
}

/// Whether a run with `config` may fit an external shear: the fixed regulariser's rule
/// ([`ReconstructConfig::external_shear_fitted`]), or for an "auto" strength that of any
/// candidate (an upper bound for [`check_memory`]).
fn fits_external_shear(config: &ReconstructConfig) -> bool {
    match config.objective.strength.value() {
        Some(_) => config.external_shear_fitted().is_some(),
        None => strength_candidates(config)
            .iter()
            .any(|c| c.apply(config).external_shear_fitted().is_some()),
    }
}

/// How many of `runs` independent reconstructions of `inputs` with `config` (ensemble
/// members, cross-validation folds) may run side by side here: one per thread the run may use
/// ([`crate::threads::available`] within `system.threads`), and no more than fit in the
/// memory one of them needs ([`check_memory`] of a one-thread run, against
/// [`MemoryLimit::here`]). Side by side, each run keeps one thread busy in every stage with
/// no barriers, where one run on two threads gains less than twice (BENCHMARKS.md).
pub(crate) fn side_by_side(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    runs: usize,
) -> Result<usize, ReconstructError> {
    let threads =
        crate::threads::with_limit(config.system.threads, crate::threads::available).min(runs);
    if threads <= 1 {
        return Ok(1);
    }
    let one = crate::threads::with_limit(1, || check_memory(inputs, config))?;
    let fit = MemoryLimit::here().bytes / one.bytes.max(1);
    Ok(threads.min(fit.max(1) as usize))
}

/// For an "auto" strength, the cross-validation of every candidate and the one chosen
/// ([`StrengthChoice::from_trials`]); `None` when the strength is a number. Natively the
/// candidates run side by side (each trial on one thread; their iterations are not reported),
/// elsewhere one after another with every report. The app runs [`strength_trial`] in one web
/// worker per candidate instead.
fn choose_strength(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Option<StrengthChoice>, ReconstructError> {
    if config.objective.strength.value().is_some() {
        return Ok(None);
    }
    let candidates = strength_candidates(config);
    let folds = strength_folds(inputs, config)?;
    if folds < 2 {
        return Ok(Some(StrengthChoice::from_trials(config, folds, Vec::new())));
    }
    let rows = run_trials(inputs, config, &candidates, folds, progress)?;
    Ok(Some(StrengthChoice::from_trials(config, folds, rows)))
}

/// [`strength_trial`] of each of `candidates`: natively side by side (each trial on one
/// thread; their iterations are not reported), elsewhere one after another with every report.
fn run_trials(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    candidates: &[Candidate],
    folds: usize,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Vec<StrengthCandidate>, ReconstructError> {
    if crate::threads::available() > 1 {
        crate::threads::map_items(candidates, |c| {
            strength_trial(inputs, config, c, folds, &mut |_| Control::Continue)
        })
        .into_iter()
        .collect()
    } else {
        candidates
            .iter()
            .map(|c| strength_trial(inputs, config, c, folds, progress))
            .collect()
    }
}

/// What the second round of an "auto" choice tries ([`second_round`]): every candidate of the
/// first, over as many folds, with the estimated redshifts fitted in every fold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SecondRound {
    pub candidates: Vec<Candidate>,
    pub folds: usize,
    pub estimates: EstimatedRedshifts,
}

/// The second round of `r`'s "auto" choice, when it needs one: its first round chose from
/// the systems with a redshift alone, and it then estimated the redshifts of others and
/// fitted them too. The grid and regulariser that predict best for a few systems are not
/// those for many more (MACS J0717: 10 systems with a redshift chose 16 x 16 cells, and with
/// its 41 estimated ones fitted too that grid lost an image of 11 systems, BENCHMARKS.md),
/// so the candidates are cross-validated again with the estimated systems fitted in every
/// fold, as the map is fitted, the systems with a redshift held out as before. `None` when
/// no redshift was estimated, the first round had no trials, or this is done already.
pub fn second_round(r: &Reconstruction) -> Option<SecondRound> {
    let choice = r.strength_choice.as_ref()?;
    let estimated = r.free_z.as_ref().is_some_and(|f| !f.systems.is_empty());
    let pending = choice.before_estimates.is_none() && r.status != SolveStatus::Cancelled;
    (estimated && pending && choice.was_cross_validated()).then(|| SecondRound {
        candidates: strength_candidates(&r.config),
        folds: choice.folds,
        estimates: EstimatedRedshifts::of(&r.sources),
    })
}

/// The choice of `r` made again from the second round's `trials` ([`second_round`]), with
/// what the first round chose kept in `before_estimates`. `None` without a first choice.
pub fn second_choice(r: &Reconstruction, trials: Vec<StrengthCandidate>) -> Option<StrengthChoice> {
    let first = r.strength_choice.as_ref()?;
    let estimated = r.free_z.as_ref().map_or(0, |f| f.systems.len());
    let mut choice = StrengthChoice::from_trials(&r.config, first.folds, trials);
    choice.before_estimates = Some(first.chosen_candidate());
    choice.rule = format!(
        "{}, the {estimated} system(s) whose redshift was estimated fitted at their estimates \
         in every fold (the systems with a redshift alone chose {})",
        choice.rule,
        first.describe_chosen()
    );
    Some(choice)
}

/// The fit `choice` (from [`second_choice`]) asks for instead of `r`'s map: `None` when
/// `r`'s map stands (only its `strength_choice` is to be replaced), else the fit of every
/// system with the chosen candidate, carrying `choice`. When the choice changed, the estimated
/// systems are first fitted at the redshifts estimated in the first round; then, whether it
/// changed or not, their redshifts are estimated again on that map and fitted until they
/// settle (at most `constraints.free_z_passes` times).
pub fn refit_for_second_choice(
    inputs: &Inputs<'_>,
    r: &Reconstruction,
    choice: &StrengthChoice,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Option<Reconstruction>, ReconstructError> {
    let Some(free) = &r.free_z else {
        return Ok(None);
    };
    let fixed = choice.chosen_candidate().apply(&r.config);
    let refit = match choice.before_estimates != Some(choice.chosen_candidate()) {
        true => Some(free_z::fit_at_estimates(
            inputs,
            &fixed,
            free.clone(),
            progress,
        )?),
        false => None,
    };
    let last = free_z::fit_consistently(inputs, &fixed, r, refit, progress)?;
    Ok(last.map(|mut last| {
        last.config = r.config.clone();
        last.strength_choice = Some(choice.clone());
        last
    }))
}

/// [`second_round`], [`second_choice`] and [`refit_for_second_choice`] in one, the trials run as
/// the first round's ([`run_trials`]); `r` itself when it needs no second round.
fn choose_again_with_estimates(
    inputs: &Inputs<'_>,
    r: Reconstruction,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    let Some(round) = second_round(&r) else {
        return Ok(r);
    };
    let config = round.estimates.fitted_by(&r.config);
    let clock = crate::products::Clock::start();
    let trials = run_trials(inputs, &config, &round.candidates, round.folds, progress)?;
    let trials_ms = clock.ms();
    let Some(choice) = second_choice(&r, trials) else {
        return Ok(r);
    };
    let mut r = match refit_for_second_choice(inputs, &r, &choice, progress)? {
        Some(refit) => refit,
        None => Reconstruction {
            strength_choice: Some(choice),
            ..r
        },
    };
    r.timings.choice_ms += trials_ms;
    Ok(r)
}

/// How many more candidates [`avoid_crowded_map`] fits when the chosen one's map is crowded.
pub const CROWDED_MAP_RETRIES: usize = 3;

/// What becomes of `r`, the map of an "auto" `choice`'s last round, when the verdict would
/// distrust it for crowding ([`Crowding::distrusted`]: more than a third of its systems
/// predicted far more images than observed; counted over the systems it fits,
/// [`Crowding::of_fitted`], so that held-out systems test the choice and do not make it):
/// the next candidates in the choice's order are
/// fitted in turn, at most [`CROWDED_MAP_RETRIES`] of them (the systems at an estimated
/// redshift at `r`'s estimates, made consistent with each map as before), and the first
/// map that is not crowded is kept, else the least crowded. Returns the choice `r` is to
/// carry ([`StrengthChoice::crowded_maps`] lists the candidates passed over) and the map to
/// use instead of `r`'s, if another (carrying that choice); `choice` itself and `None` when
/// `r`'s map is not crowded or `choice` was not cross-validated. `r` itself is left as it
/// was, so that an error loses nothing.
///
/// Why: the choice scores a held-out image by its nearest predicted image, and a map whose
/// critical curves wind through the images' region predicts a crowd of images, one of which
/// is always near (Jauzac et al.'s MACS J1149: 22 of 45 systems, up to 92 images for 6
/// observed; the published model 3 - 7). Ranking the candidates by their folds' crowding
/// instead did not work: the folds' maps, fitted to fewer systems, are less crowded than the
/// map of all of them (there 24% of the folds' systems against 38% and more of the map's),
/// and which maps crowd moves with the estimated redshifts (BENCHMARKS.md).
pub fn avoid_crowded_map(
    inputs: &Inputs<'_>,
    r: &Reconstruction,
    choice: &StrengthChoice,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<(StrengthChoice, Option<Reconstruction>), ReconstructError> {
    let mut next: Vec<&StrengthCandidate> = choice
        .candidates
        .iter()
        .filter(|c| !choice.is_chosen(c))
        .collect();
    next.sort_by(|p, q| predicts_better(p, q));
    let next: Vec<Candidate> = next.iter().map(|c| c.candidate()).collect();
    avoid_crowded_map_trying(inputs, r, choice, &next, progress)
}

/// [`avoid_crowded_map`] trying `next` (the candidates after the chosen one, in the order to
/// try them) when `r`'s map is crowded: an ensemble member tries them in the order its own
/// draw ranks them ([`MemberDraw::then`]).
pub(crate) fn avoid_crowded_map_trying(
    inputs: &Inputs<'_>,
    r: &Reconstruction,
    choice: &StrengthChoice,
    next: &[Candidate],
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<(StrengthChoice, Option<Reconstruction>), ReconstructError> {
    if !choice.was_cross_validated() || r.status == SolveStatus::Cancelled {
        return Ok((choice.clone(), None));
    }
    let config = &r.config;
    let free = r.free_z.as_ref().filter(|f| !f.systems.is_empty());
    let (map, used, passed) = first_uncrowded(
        Crowding::of_fitted(&r.sources),
        choice.chosen_candidate(),
        next,
        |r: &Reconstruction| Crowding::of_fitted(&r.sources),
        |candidate| {
            let fixed = candidate.apply(config);
            let mut fit = match free {
                Some(free) => {
                    let first = free_z::fit_at_estimates(inputs, &fixed, free.clone(), progress)?;
                    let last = free_z::fit_consistently(inputs, &fixed, &first, None, progress)?;
                    last.unwrap_or(first)
                }
                None => reconstruct_limited(inputs, &fixed, progress)?,
            };
            if fit.status == SolveStatus::Cancelled {
                return Ok::<_, ReconstructError>(None);
            }
            fit.config = config.clone();
            Ok(Some(fit))
        },
    )?;
    let mut choice = choice.with_chosen(used);
    choice.crowded_maps = passed.into_iter().filter(|p| p.candidate != used).collect();
    let map = map.map(|mut m| {
        m.strength_choice = Some(choice.clone());
        with_own_priors(&mut m, config);
        m
    });
    Ok((choice, map))
}

/// [`avoid_crowded_map`] of `r` with its own "auto" choice: `r` with the choice updated, or
/// the map kept instead; `r` as it is without a choice.
pub fn with_uncrowded_map(
    inputs: &Inputs<'_>,
    r: Reconstruction,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    let Some(choice) = r.strength_choice.clone() else {
        return Ok(r);
    };
    Ok(match avoid_crowded_map(inputs, &r, &choice, progress)? {
        (_, Some(map)) => map,
        (choice, None) => Reconstruction {
            strength_choice: Some(choice),
            ..r
        },
    })
}

/// The logic of [`avoid_crowded_map`] on any kind of map `M`: the first map (made with
/// `chosen`, crowded `first`) stands when it is not crowded; else the first of `next` (at
/// most [`CROWDED_MAP_RETRIES`]) whose map `fit` makes is not crowded, else the least crowded
/// of those made (the earlier on a tie). Returns the map kept (`None`: the first), its
/// candidate, and every candidate whose map was crowded, in the order fitted. `fit` returning
/// `None` (cancelled) ends the search with the maps made so far.
fn first_uncrowded<M, E>(
    first: Crowding,
    chosen: Candidate,
    next: &[Candidate],
    crowding: impl Fn(&M) -> Crowding,
    mut fit: impl FnMut(Candidate) -> Result<Option<M>, E>,
) -> Result<(Option<M>, Candidate, Vec<CrowdedMap>), E> {
    if !first.distrusted() {
        return Ok((None, chosen, Vec::new()));
    }
    let mut passed = vec![CrowdedMap {
        candidate: chosen,
        crowding: first,
    }];
    let mut least = (first, None, chosen);
    for &candidate in next.iter().take(CROWDED_MAP_RETRIES) {
        let Some(map) = fit(candidate)? else {
            break;
        };
        let c = crowding(&map);
        if !c.distrusted() {
            return Ok((Some(map), candidate, passed));
        }
        passed.push(CrowdedMap {
            candidate,
            crowding: c,
        });
        if c.less_than(&least.0) {
            least = (c, Some(map), candidate);
        }
    }
    Ok((least.1, least.2, passed))
}

/// The candidates an "auto" strength tries: every grid of `objective.auto_grid_scales`
/// (the distinct cell counts, coarsest first) with every one of `objective.auto_regularisers`
/// and every one of `objective.candidates`.
///
/// The least-mass regulariser ([`Regulariser::Density`]) fits no external shear
/// ([`ReconstructConfig::external_shear_fitted`]) and is tried beside the others, which fit
/// one: it charges the member galaxies' mass as the cells' (`LinearSystem`'s penalty), so
/// the held-out images can prefer it only for the map it draws, not for mass moved into
/// members that cost nothing (which chose it on MACS J1149 with `C` = 2.04 and an Einstein
/// radius 25% too large before, BENCHMARKS.md).
pub fn strength_candidates(config: &ReconstructConfig) -> Vec<Candidate> {
    let o = &config.objective;
    let regularisers = &o.auto_regularisers;
    let mut grids: Vec<usize> = o
        .auto_grid_scales
        .iter()
        .map(|&scale| ((scale * config.grid.cells as f64).round() as usize).max(1))
        .collect();
    grids.sort_unstable();
    grids.dedup();
    grids
        .iter()
        .flat_map(|&cells| {
            regularisers.iter().flat_map(move |&regulariser| {
                o.candidates.iter().map(move |&strength| Candidate {
                    regulariser,
                    strength,
                    cells: Some(cells),
                })
            })
        })
        .collect()
}

/// The folds an "auto" strength is cross-validated with: `objective.folds`, at most one per
/// source a fold can hold out (below 2: too few systems to hold any out). Systems fitted at
/// an estimated redshift (`constraints.z_estimates`) are fitted by every fold and count for
/// none; the knots of one galaxy count once ([`holdable_sources`]).
pub fn strength_folds(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
) -> Result<usize, ReconstructError> {
    let holdable = holdable_sources(inputs, config)?.len();
    Ok(config.objective.folds.min(holdable))
}

/// The cross-validation of one `candidate` over `folds` folds (maps of at most
/// [`CHOICE_MAP_PIXELS`] and no curves: they only serve to predict the held-out images).
pub fn strength_trial(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    candidate: &Candidate,
    folds: usize,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<StrengthCandidate, ReconstructError> {
    let trial = candidate.apply_for_trial(config);
    let mut cancelled = false;
    let cv = cross_validate(inputs, &trial, folds, None, &mut |_, record| {
        let control = progress(record);
        cancelled |= control == Control::Cancel;
        control
    })?;
    if cancelled {
        return Err(ReconstructError::Cancelled);
    }
    Ok(StrengthCandidate {
        regulariser: candidate.regulariser,
        strength: candidate.strength,
        cells: candidate.cells,
        holdout_median_arcsec: cv.totals.holdout_image_offset_median_arcsec,
        holdout_rms_arcsec: cv.totals.holdout_image_plane_rms_arcsec,
        holdout_unmatched: cv.totals.holdout_images_unmatched,
        fit_median_arcsec: cv.totals.fit_image_offset_median_arcsec,
        holdout_by_system: cv
            .systems
            .iter()
            .map(|s| SystemOffsets {
                id: s.report.id.clone(),
                offsets_arcsec: s.report.observed.iter().map(|i| i.offset_arcsec).collect(),
            })
            .collect(),
    })
}

impl StrengthChoice {
    /// Whether candidates were cross-validated (at least two folds, at least one trial): a
    /// choice without is the settings' fallback, made again by nothing.
    pub fn was_cross_validated(&self) -> bool {
        self.folds >= 2 && !self.candidates.is_empty()
    }

    /// The image-plane error (arcsec, rms over both axes) of the chosen candidate's held-out
    /// images, from their median offset, which one image near a critical curve cannot
    /// inflate: for offsets with a Gaussian error `s` per axis the median offset is
    /// `s sqrt(2 ln 2)` and the rms `s sqrt(2)`. `None` without trials.
    pub fn holdout_sigma_arcsec(&self) -> Option<f64> {
        let chosen = self.candidates.iter().find(|c| self.is_chosen(c))?;
        let median = chosen.holdout_median_arcsec?;
        Some(median * (2.0 / (2.0 * std::f64::consts::LN_2)).sqrt())
    }

    /// For each regulariser among the candidates other than the chosen one, its best
    /// candidate by the choice's own rule (the fewest unmatched, then the smallest median
    /// offset of held-out images), in the candidates' order: the other ways of drawing the
    /// map that the run tried. Held-out systems lie among the others, so they hardly tell how
    /// each regulariser extends the map beyond them (least mass lets it fall off, smoothest
    /// keeps it level); a redshift estimated out there is averaged over these maps.
    pub fn best_of_other_regularisers(&self) -> Vec<Candidate> {
        let mut best: Vec<&StrengthCandidate> = Vec::new();
        for c in &self.candidates {
            if c.regulariser == self.chosen_regulariser {
                continue;
            }
            match best.iter_mut().find(|b| b.regulariser == c.regulariser) {
                Some(b) if predicts_better(c, b).is_lt() => *b = c,
                Some(_) => {}
                None => best.push(c),
            }
        }
        best.into_iter().map(StrengthCandidate::candidate).collect()
    }

    /// The choice in words, e.g. "curvature at strength 0.1 on 24 x 24 cells, chosen by
    /// 4-fold cross-validation of 27 candidates".
    pub fn describe(&self) -> String {
        let what = self.describe_chosen();
        let again = match self.before_estimates {
            Some(first) if first == self.chosen_candidate() => {
                " (chosen again with the estimated redshifts fitted: the same)".to_string()
            }
            Some(first) => format!(
                " with the estimated redshifts fitted (before them: {})",
                describe_candidate(&first)
            ),
            None => String::new(),
        };
        let crowded = match self.crowded_maps.as_slice() {
            [] => String::new(),
            passed => format!(
                "; passed over for maps that predict far more images than observed for more \
                 than a third of the systems: {}",
                passed
                    .iter()
                    .map(|p| format!(
                        "{} ({} of {})",
                        describe_candidate(&p.candidate),
                        p.crowding.crowded_systems,
                        p.crowding.systems
                    ))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        match self.candidates.len() {
            0 => format!("{what} ({})", self.rule),
            n => format!(
                "{what}, chosen by {}-fold cross-validation of {n} candidates{again}{crowded}",
                self.folds
            ),
        }
    }

    /// The chosen candidate in words, e.g. "curvature at strength 0.1 on 24 x 24 cells".
    pub fn describe_chosen(&self) -> String {
        describe_candidate(&self.chosen_candidate())
    }

    /// Whether `c` is the chosen candidate.
    pub fn is_chosen(&self, c: &StrengthCandidate) -> bool {
        c.regulariser == self.chosen_regulariser
            && c.strength == self.chosen
            && (c.cells.is_none() || self.chosen_cells.is_none() || c.cells == self.chosen_cells)
    }

    /// The chosen candidate's held-out median offset (arcsec) over the folds of this choice,
    /// `None` when none of its held-out images was matched.
    pub fn chosen_holdout_median_arcsec(&self) -> Option<f64> {
        let chosen = self.candidates.iter().find(|c| self.is_chosen(c))?;
        chosen.holdout_median_arcsec
    }

    /// The chosen candidate: what the reconstruction uses.
    pub fn chosen_candidate(&self) -> Candidate {
        Candidate {
            regulariser: self.chosen_regulariser,
            strength: self.chosen,
            cells: self.chosen_cells,
        }
    }

    /// The candidate (regulariser, strength, grid) this choice's rule picks when the held-out
    /// systems count `weight(id)` times each (a bootstrap draw: 0 for a system not drawn, 2
    /// for one drawn twice): the first of [`Self::ranked_for`].
    ///
    /// An ensemble member re-makes the choice this way on its own draw, so that the
    /// uncertainty of the choice itself (which candidates the data cannot tell apart) enters
    /// the ensemble's spread without running the cross-validation again.
    pub fn best_for(&self, weight: impl Fn(&str) -> usize) -> Option<Candidate> {
        self.ranked_for(weight)?.into_iter().next()
    }

    /// The candidates in the order this choice's rule ranks them when the held-out systems
    /// count `weight(id)` times each: the fewest unmatched images, then the smallest median
    /// offset, both over the drawn systems' images (the candidates' order on a tie). Left
    /// out: candidates none of whose drawn systems was predicted, and those whose map of every
    /// system was passed over as crowded ([`Self::crowded_maps`]; a draw's map would be much
    /// the same). `None` without the candidates' per-system offsets (a choice made before
    /// they were kept).
    pub fn ranked_for(&self, weight: impl Fn(&str) -> usize) -> Option<Vec<Candidate>> {
        let score = |c: &StrengthCandidate| {
            let mut unmatched = 0;
            let mut offsets = Vec::new();
            for system in &c.holdout_by_system {
                let w = weight(&system.id);
                for o in &system.offsets_arcsec {
                    match o {
                        Some(o) => offsets.extend(std::iter::repeat_n(*o, w)),
                        None => unmatched += w,
                    }
                }
            }
            let median = summary::median_arcsec(offsets)?;
            Some((unmatched, median))
        };
        if self
            .candidates
            .iter()
            .any(|c| c.holdout_by_system.is_empty())
        {
            return None;
        }
        let passed_over = |c: &StrengthCandidate| {
            self.crowded_maps
                .iter()
                .any(|p| p.candidate == c.candidate())
        };
        let mut scored: Vec<((usize, f64), Candidate)> = self
            .candidates
            .iter()
            .filter(|c| !passed_over(c))
            .filter_map(|c| Some((score(c)?, c.candidate())))
            .collect();
        scored.sort_by(|(a, _), (b, _)| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        Some(scored.into_iter().map(|(_, c)| c).collect())
    }

    /// The same choice with `chosen` used instead of the chosen candidate (an ensemble
    /// member's own choice), its candidates kept.
    pub fn with_chosen(&self, chosen: Candidate) -> Self {
        Self {
            chosen: chosen.strength,
            chosen_regulariser: chosen.regulariser,
            chosen_cells: chosen.cells,
            ..self.clone()
        }
    }

    /// The choice among the `trials` of `config`'s candidates: the fewest held-out images with
    /// no predicted image, then the smallest held-out median offset. With fewer than 2 folds
    /// (no trials), or when no trial predicted any held-out image (nothing to rank them by),
    /// the middle candidate, and said so.
    pub fn from_trials(
        config: &ReconstructConfig,
        folds: usize,
        trials: Vec<StrengthCandidate>,
    ) -> Self {
        let candidates = &config.objective.candidates;
        let middle = |rule: String| Self {
            folds: 0,
            candidates: Vec::new(),
            chosen: candidates[candidates.len() / 2],
            chosen_regulariser: config.objective.regulariser,
            chosen_cells: None,
            rule,
            before_estimates: None,
            crowded_maps: Vec::new(),
        };
        if folds < 2 || trials.is_empty() {
            return middle(
                "too few fitted systems to hold any out, so the middle candidate".into(),
            );
        }
        if trials.iter().all(|t| t.holdout_median_arcsec.is_none()) {
            return middle(format!(
                "none of {} candidates predicted an image of the systems {folds} folds held \
                 out, so the middle candidate",
                trials.len()
            ));
        }
        // `trials` is not empty here, so there is a best.
        let Some(chosen) = trials
            .iter()
            .min_by(|p, q| predicts_better(p, q))
            .map(StrengthCandidate::candidate)
        else {
            return middle("no candidate to choose from, so the middle candidate".into());
        };
        Self {
            folds,
            candidates: trials,
            chosen: chosen.strength,
            chosen_regulariser: chosen.regulariser,
            chosen_cells: chosen.cells,
            rule: format!(
                "the fewest unmatched, then the smallest median offset of held-out images \
                 over {folds} folds"
            ),
            before_estimates: None,
            crowded_maps: Vec::new(),
        }
    }
}

/// A candidate in words, e.g. "curvature at strength 0.1 on 24 x 24 cells".
fn describe_candidate(c: &Candidate) -> String {
    let grid = c
        .cells
        .map_or(String::new(), |n| format!(" on {n} x {n} cells"));
    format!("{} at strength {}{grid}", c.regulariser.name(), c.strength)
}

/// The order of an "auto" choice: `Less` when `p` predicted the held-out images better than
/// `q` (fewer with no predicted image, then a smaller median offset; no median counts as an
/// infinite one).
fn predicts_better(p: &StrengthCandidate, q: &StrengthCandidate) -> std::cmp::Ordering {
    let median = |c: &StrengthCandidate| c.holdout_median_arcsec.unwrap_or(f64::INFINITY);
    p.holdout_unmatched
        .cmp(&q.holdout_unmatched)
        .then(median(p).total_cmp(&median(q)))
}

/// [`reconstruct`] with an "auto" strength already chosen (e.g. by trials run elsewhere):
/// the result carries `choice`, and its settings keep "auto".
pub fn reconstruct_with_choice(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    choice: StrengthChoice,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    let total = crate::products::Clock::start();
    let mut r = with_choice(inputs, config, choice, true, progress)?;
    with_own_priors(&mut r, config);
    r.timings.total_ms = total.ms();
    Ok(r)
}

fn with_choice(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    choice: StrengthChoice,
    free_z: bool,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    crate::threads::with_limit(config.system.threads, || {
        let fixed = choice.chosen_candidate().apply(config);
        let mut r = reconstruct_limited(inputs, &fixed, progress)?;
        if free_z {
            let sigma = choice.holdout_sigma_arcsec();
            // Only their lenses serve: the small maps of the trials, no curves.
            let others: Vec<ReconstructConfig> = choice
                .best_of_other_regularisers()
                .iter()
                .map(|c| c.apply_for_trial(config))
                .collect();
            r = free_z::add_free_systems(inputs, &fixed, r, sigma, &others, progress)?;
            // A choice made without folds (too few systems with a redshift) has no second
            // round, whose refit would make the estimates consistent with the map: here.
            if !choice.was_cross_validated() {
                r = free_z::fit_consistently(inputs, &fixed, &r, None, progress)?.unwrap_or(r);
            }
        }
        r.config = config.clone();
        r.strength_choice = Some(choice);
        Ok(r)
    })
}

/// Map side (pixels) of the trial reconstructions of an "auto" strength.
pub const CHOICE_MAP_PIXELS: usize = 256;

fn reconstruct_limited(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
    progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
) -> Result<Reconstruction, ReconstructError> {
    config.validate()?;
    check_source_redshifts(inputs, config)?;
    let constraints = build_constraints(inputs.images, &config.constraints, inputs.holdout)?;
    if constraints.systems.is_empty() {
        return Err(ReconstructError::NoConstraints(describe_excluded(
            &constraints,
        )));
    }
    let mut warnings = constraints.warnings.clone();
    warnings.extend(just_behind_lens(
        &constraints,
        config,
        &inputs.plane,
        inputs.catalog,
    ));
    let (shear, shear_warning) = shear_set(inputs.shear, config, &inputs.plane);
    warnings.extend(shear_warning);
    let mut grid = grid_of(&constraints, &shear, config)?;
    let mut bcg = BcgFacts::default();
    let mut layers: Vec<Layer> = match inputs.layers {
        LayerSource::None => Vec::new(),
        LayerSource::Given(layers) => layers.to_vec(),
        LayerSource::Members(catalog) => {
            let members =
                member_layers(catalog, &config.members, &inputs.plane, &grid, &constraints)?;
            warnings.extend(members.warnings);
            bcg = members.bcg;
            members.layers
        }
    };
    add_external_shear(&mut layers, config, &grid);
    // The system's true sizes (the layers built, the systems kept, the weak-lensing ring's
    // cells), before it is built.
    let mut size = RunSize::of(
        config,
        constraints.pixels.len(),
        constraints.systems.len(),
        layers.len(),
    );
    let ring = grid.len().saturating_sub(size.cells_per_side.pow(2));
    size.cells = size.cells.saturating_add(ring);
    size.memory(config).check(MemoryLimit::here())?;
    let mut convergence = Vec::new();
    let mut timings = StageTimings::default();
    let mut level = 0;
    let (system, outcome) = loop {
        let t = crate::products::Clock::start();
        let mut system = LinearSystem::build_with_shear(
            &grid,
            &layers,
            &constraints,
            &shear,
            &inputs.plane,
            &config.system,
            ObjectiveTerms {
                regulariser: config.objective.regulariser,
                strength: config.objective.strength.value().unwrap_or(0.0),
                ..ObjectiveTerms::default()
            },
        )?;
        if level == 0 {
            if let Some(sigma) = config.members.c_prior_sigma_unmeasured {
                hold_unmeasured_layers(&mut system, sigma);
                layers.clone_from(&system.layers);
            }
        }
        timings.system_ms += t.ms();
        let t = crate::products::Clock::start();
        let x0 = start_values(&system, &config.solver);
        let mut callback = |p: &crate::solver::Progress| {
            let record = ConvergenceRecord::of(&system, level, p);
            let control = progress(&record);
            convergence.push(record);
            control
        };
        let outcome = solve(&system, config, &x0, &mut callback)?;
        timings.solve_ms += t.ms();
        let finished = matches!(
            outcome.status,
            SolveStatus::Completed | SolveStatus::Converged
        );
        if level < config.grid.refinements && finished {
            let masses = system.cell_masses_msun(&outcome.x)?;
            grid = grid.refine(&masses, config.grid.refine_fraction)?;
            level += 1;
            continue;
        }
        break (system, outcome);
    };
    let mut iterates = outcome.iterates;
    // The image-plane weights: solve again with each pixel's residual stretched by the
    // previous solution's magnification tensor (the `regularise` module of the inversion).
    let (mut system, mut x, mut status, mut iterations) =
        (system, outcome.x, outcome.status, outcome.iterations);
    // With weak lensing, the same passes also update each galaxy's `kappa_0` (the `shear`
    // module of the inversion); passes beyond the image-plane ones keep their transforms.
    let image_passes = config.objective.image_plane_iterations;
    let shear_passes = match shear.is_empty() {
        true => 0,
        false => config.shear.iterations,
    };
    let mut shear = shear;
    for pass in 0..image_passes.max(shear_passes) {
        if status == SolveStatus::Cancelled {
            break;
        }
        let t = crate::products::Clock::start();
        let lens = system.reconstructed_lens(&x)?;
        let pixel_transforms = match pass < image_passes {
            true => system
                .constraints
                .pixels
                .iter()
                .map(|p| {
                    let f = system.distance_ratios[p.system];
                    let h = lens.hessian(p.position);
                    capped_inverse_jacobian(h, f, config.objective.max_stretch)
                })
                .collect(),
            false => system.terms.pixel_transforms.clone(),
        };
        if pass < shear_passes {
            shear = shear.with_kappa(|p| lens.kappa(p));
        }
        let terms = ObjectiveTerms {
            pixel_transforms,
            ..system.terms.clone()
        };
        // The next system replaces this one: its matrix goes first, so that two are never
        // held at once (the peak of the run, see the `memory` module).
        system.a = Vec::new();
        system = LinearSystem::build_with_shear(
            &system.grid,
            &layers,
            &constraints,
            &shear,
            &inputs.plane,
            &config.system,
            terms,
        )?;
        timings.system_ms += t.ms();
        let t = crate::products::Clock::start();
        level += 1;
        let mut callback = |p: &crate::solver::Progress| {
            let record = ConvergenceRecord::of(&system, level, p);
            let control = progress(&record);
            convergence.push(record);
            control
        };
        let outcome = solve(&system, config, &x, &mut callback)?;
        timings.solve_ms += t.ms();
        // The pass's start is `x`, the last iterate kept so far (QADP), or nothing of the
        // run's path (the exact solver starts at 0).
        iterates.extend(
            outcome
                .iterates
                .into_iter()
                .filter(|i| i.iteration > 0)
                .map(|mut i| {
                    i.iteration += iterations;
                    i
                }),
        );
        (x, status, iterations) = (outcome.x, outcome.status, iterations + outcome.iterations);
    }
    let iterates = thin_iterates(iterates, config.solver.keep_iterates);
    // First: they bear on the whole result, and the catalogues' warnings would hide them.
    // Timed with the system, whose matrix they factorise.
    let t = crate::products::Clock::start();
    warnings.splice(0..0, system.measurability_warnings());
    timings.system_ms += t.ms();
    warnings.extend(system.prior_pull_warnings(&x));
    let lens = system.reconstructed_lens(&x)?;
    let t = crate::products::Clock::start();
    let opts = product_options(config, &system.grid);
    let products = Products::from_lens(&lens, inputs.plane, inputs.reference, &opts)?;
    timings.products_ms = t.ms();
    let t = crate::products::Clock::start();
    let sources = sources::report(
        &system,
        &x,
        &lens,
        &products,
        inputs,
        &config.constraints,
        config.objective.max_stretch,
    )?;
    timings.sources_ms = t.ms();
    Ok(Reconstruction {
        config: config.clone(),
        system,
        x,
        status: RunStatus::Solved(status),
        iterations,
        convergence,
        iterates,
        lens,
        products,
        sources,
        warnings,
        timings,
        strength_choice: None,
        free_z: None,
        member_positions_arcsec: member_positions(inputs),
        bcg,
    })
}

/// The weak-lensing galaxies of `catalog` (none without one) on `plane` and the warning about
/// those left out, if any.
pub(crate) fn shear_set(
    catalog: Option<&ArcletCatalog>,
    config: &ReconstructConfig,
    plane: &LensPlane,
) -> (ShearSet, Option<String>) {
    match catalog {
        Some(catalog) => ShearSet::from_catalog(catalog, &config.shear, plane),
        None => (ShearSet::default(), None),
    }
}

/// The regular grid of `config` over the constraints, with the ring of coarser cells out to
/// the median weak-lensing galaxy when there are any (`crate::inversion::with_ring`).
///
/// Why the median and not the farthest: reduced shear cannot see a uniform mass sheet, so
/// with every galaxy on the grid a sheet over the whole grid fits the shapes as well as none,
/// and a smoothness regulariser prefers it (3.2 - 3.4 times the true mass inside 3 arcmin on
/// the synthetic cluster of `tests/data/weak_lensing`, strength 0.1). With the grid ending at the median
/// galaxy, the inner half of the galaxies map the mass and the outer half lie beyond the
/// grid, where there is no model mass and the shear they measure is that of the mass inside
/// it: a sheet would shear them, so the data weigh the grid (the weak-lensing "aperture mass"
/// argument). The model's mass beyond the median galaxy is therefore zero.
pub(crate) fn grid_of(
    constraints: &ConstraintSet,
    shear: &ShearSet,
    config: &ReconstructConfig,
) -> Result<CellGrid, GridError> {
    let positions: Vec<DVec2> = constraints.pixels.iter().map(|p| p.position).collect();
    let grid = CellGrid::from_config(&config.grid, &positions)?;
    let mut distances: Vec<f64> = shear
        .points
        .iter()
        .map(|p| (p.position - grid.center).abs().max_element())
        .collect();
    distances.sort_by(f64::total_cmp);
    let reach = match distances.is_empty() {
        true => 0.0,
        false => crate::stats::quantile(&distances, 0.5),
    };
    crate::inversion::with_ring(&grid, reach, config.shear.ring_cells_max)
}

/// The member layers of a run and what they warn about.
pub(crate) struct MemberLayers {
    pub layers: Vec<Layer>,
    /// The note of commented rows fitted as BCGs ([`MemberCatalog::fitted_bcgs`]) and a
    /// missing BCG's warning first (they matter more than the members left out one by one),
    /// then [`build_member_layers`]'s.
    pub warnings: Vec<String>,
    /// What the catalogue's members say about the brightest cluster galaxies.
    pub bcg: BcgFacts,
}

/// The layers of `catalog`'s members on `grid` ([`build_member_layers`]), checked for a missing
/// BCG near the images of `constraints` (`missing_bcg_warning` in the inversion). Shared by a
/// run and the app's rebuilding of a saved result, so both warn alike.
pub(crate) fn member_layers(
    catalog: &MemberCatalog,
    config: &MemberConfig,
    plane: &LensPlane,
    grid: &CellGrid,
    constraints: &ConstraintSet,
) -> Result<MemberLayers, MembersError> {
    let model = build_member_layers(catalog, config, plane, grid)?;
    let images = image_centres(constraints);
    let bcg = missing_bcg_warning(
        &catalog.source_name,
        catalog.par_source.as_deref(),
        &bcg_candidates(catalog, config, plane),
        &images,
        &with_luminosity(&catalog.commented, config, plane),
    );
    // Commented rows fitted as BCGs, then a missing BCG: they matter more than the members
    // left out one by one.
    let mut warnings: Vec<String> = catalog.fitted_bcgs.iter().map(|b| b.note.clone()).collect();
    let members_far = bcg.as_ref().is_some_and(|b| b.members_far);
    let facts = BcgFacts {
        missing: bcg.is_some() && !members_far,
        members_far,
        commented: bcg
            .and_then(|b| {
                warnings.push(b.warning);
                b.commented
            })
            .map(|c| c.rows)
            .unwrap_or_default(),
        fitted: catalog
            .fitted_bcgs
            .as_ref()
            .map(|b| b.rows.clone())
            .unwrap_or_default(),
    };
    warnings.extend(model.warnings);
    Ok(MemberLayers {
        layers: model.layers,
        warnings,
        bcg: facts,
    })
}

/// Each of `members` with its luminosity in `L*` ([`MemberConfig::luminosity_lstar`]).
fn with_luminosity<'a>(
    members: &'a [Member],
    config: &MemberConfig,
    plane: &LensPlane,
) -> Vec<(&'a Member, f64)> {
    let mag_star = config.mag_star_on(plane);
    members
        .iter()
        .map(|m| (m, config.luminosity_lstar(m.mag, mag_star)))
        .collect()
}

/// The members of `catalog` with their luminosity in L* as `missing_bcg_warning` weighs them:
/// a galaxy the `.par` models on its own ([`MemberCatalog::par_galaxies`]) counts as at least
/// as bright as a BCG, since the set-up chose it as one that needs its own model.
fn bcg_candidates<'a>(
    catalog: &'a MemberCatalog,
    config: &MemberConfig,
    plane: &LensPlane,
) -> Vec<(&'a Member, f64)> {
    let mut members = with_luminosity(&catalog.members, config, plane);
    for (k, (_, lstar)) in members.iter_mut().enumerate() {
        if catalog.par_galaxies.contains(&k) {
            *lstar = lstar.max(crate::inversion::BCG_MIN_LSTAR);
        }
    }
    members
}

/// The centre (mean of its pixels) of each image of the fitted systems, in arcsec.
fn image_centres(constraints: &ConstraintSet) -> Vec<DVec2> {
    let mut sums: std::collections::BTreeMap<(usize, usize), (DVec2, f64)> = Default::default();
    for p in &constraints.pixels {
        let e = sums
            .entry((p.system, p.image))
            .or_insert((DVec2::ZERO, 0.0));
        e.0 += p.position;
        e.1 += 1.0;
    }
    sums.values().map(|(sum, n)| *sum / *n).collect()
}

/// The member catalogue's positions (arcsec) of `inputs` (none for layers given directly).
fn member_positions(inputs: &Inputs<'_>) -> Vec<DVec2> {
    match inputs.layers {
        LayerSource::Members(catalog) => catalog.members.iter().map(|m| m.position).collect(),
        LayerSource::None | LayerSource::Given(_) => Vec::new(),
    }
}

/// Appends the four layers of an external shear about the grid's centre to `layers` when
/// the run fits one ([`ReconstructConfig::external_shear_fitted`],
/// [`crate::inversion::external_shear_layers`]).
pub(crate) fn add_external_shear(
    layers: &mut Vec<Layer>,
    config: &ReconstructConfig,
    grid: &CellGrid,
) {
    if let Some(sigma) = config.external_shear_fitted() {
        layers.extend(crate::inversion::external_shear_layers(grid.center, sigma));
    }
}

/// Gives every layer without a prior whose factor the data hardly measure (independent share
/// below [`crate::inversion::LAYER_SHARE_WARN`]) the prior `C = 1 +- sigma`
/// ([`crate::inversion::MemberConfig::c_prior_sigma_unmeasured`]).
fn hold_unmeasured_layers(system: &mut LinearSystem, sigma: f64) {
    let unmeasured: Vec<usize> = system
        .layer_independence()
        .iter()
        .enumerate()
        .filter(|(_, share)| share.is_some_and(|s| s < crate::inversion::LAYER_SHARE_WARN))
        .map(|(l, _)| l)
        .collect();
    for l in unmeasured {
        system.add_layer_prior(l, sigma);
    }
}

/// At most `keep` of `iterates` (the passes of the image-plane weights each keep that many),
/// evenly spread over the list; the first and the last stay.
fn thin_iterates(iterates: Vec<Iterate>, keep: usize) -> Vec<Iterate> {
    let n = iterates.len();
    if n <= keep {
        return iterates;
    }
    if keep < 2 {
        return iterates.into_iter().skip(n - keep).collect();
    }
    let chosen: Vec<usize> = (0..keep)
        .map(|k| (k as f64 * (n - 1) as f64 / (keep - 1) as f64).round() as usize)
        .collect();
    let wanted = |i: &usize| chosen.binary_search(i).is_ok();
    iterates
        .into_iter()
        .enumerate()
        .filter(|(i, _)| wanted(i))
        .map(|(_, it)| it)
        .collect()
}

/// Minimises `system`'s objective with the configured method from `x0` (the exact solver
/// needs no start).
fn solve(
    system: &LinearSystem,
    config: &ReconstructConfig,
    x0: &[f64],
    callback: &mut dyn FnMut(&crate::solver::Progress) -> Control,
) -> Result<SolveOutcome, ReconstructError> {
    let n = system.n_columns();
    let settings = config.solver_settings();
    Ok(match config.solver.method {
        SolverMethod::Exact => {
            let (steps, keep) = (config.solver.iterations, config.solver.keep_iterates);
            minimise_exact(&system.a, &system.b, n, steps, keep, callback)?
        }
        SolverMethod::Qadp => {
            QadpProblem::with_order(&system.a, &system.b, n, system.solver_order())?
                .run(x0, &settings, callback)?
        }
        SolverMethod::AcceleratedGradient => {
            accelerated_gradient(&system.a, &system.b, n, x0, &settings, callback)?
        }
    })
}

/// The map geometry of the products a reconstruction of `inputs` with `config` makes (with
/// no grid refinement; a refined grid keeps its field): the maps of `kappa.fits`.
pub fn map_geometry(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
) -> Result<MapGeometry, ReconstructError> {
    config.validate()?;
    let constraints = build_constraints(inputs.images, &config.constraints, inputs.holdout)?;
    let (shear, _) = shear_set(inputs.shear, config, &inputs.plane);
    let grid = grid_of(&constraints, &shear, config)?;
    let opts = product_options(config, &grid);
    Ok(MapGeometry::centered(opts.size_arcsec, opts.pixels))
}

/// The product maps of a reconstruction on `grid`: `products.size_arcsec` (default: the grid's
/// width, or with a weak-lensing ring the ring's) on `products.pixels`, centred on the origin. When the grid's cells would not fall on
/// lattices of the map's pixels, so that its maps would be summed cell by cell at every pixel
/// (the built-in example on 500 pixels, or 100 arcsec wide: ~10 s in a browser instead of
/// 0.4), the width is rounded to make a cell span a whole number `k` of pixels: it changes by
/// less than a factor `1 +- 1/(2k)`, and the FFT convolution makes the maps.
pub fn product_options(config: &ReconstructConfig, grid: &CellGrid) -> ProductOptions {
    let pixels = config.products.pixels;
    let requested = config.products.size_arcsec.unwrap_or(grid.extent_arcsec());
    let unit = GridMass::new(grid, vec![1.0; grid.len()]).ok();
    let direct = |size_arcsec: f64| {
        let geometry = MapGeometry {
            pixels,
            size_arcsec,
            center: DVec2::ZERO,
        };
        unit.as_ref()
            .map_or(0, |m| m.map_plan(&geometry).direct_cells)
    };
    let cell = grid.width_arcsec / grid.cells_per_side.max(1) as f64;
    let per_cell = cell * pixels as f64 / requested;
    let size_arcsec = if pixels > 0 && per_cell.is_finite() && direct(requested) > 0 {
        let snapped = pixels as f64 * cell / per_cell.round().max(1.0);
        // Kept only if it helps (a refined grid's finer levels may still be off the lattice).
        match direct(snapped) < direct(requested) {
            true => snapped,
            false => requested,
        }
    } else {
        requested
    };
    ProductOptions {
        maps_only: config.products.maps_only,
        z_source: config.products.z_source,
        size_arcsec,
        pixels,
        ..ProductOptions::default()
    }
}

/// The paper's "reasonable" start: small cell masses, small C, and each beta at the mean
/// position of its system's constraint pixels (shifted into the positive frame).
fn start_values(system: &LinearSystem, solver: &SolverConfig) -> Vec<f64> {
    let mut x = vec![0.0; system.n_columns()];
    let cell = solver.start_cell_mass_msun / system.mass_unit_msun;
    x[system.cell_columns()].iter_mut().for_each(|v| *v = cell);
    x[system.layer_columns()]
        .iter_mut()
        .for_each(|v| *v = solver.start_c);
    let ns = system.constraints.systems.len();
    let mut sum = vec![DVec2::ZERO; ns];
    let mut count = vec![0usize; ns];
    for p in &system.constraints.pixels {
        sum[p.system] += p.position;
        count[p.system] += 1;
    }
    let shift = system.theta_shift_arcsec;
    let (bx, by) = (system.beta_x_columns(), system.beta_y_columns());
    for s in 0..ns {
        let mean = sum[s] / count[s].max(1) as f64;
        x[bx.start + s] = (mean.x + shift).max(1e-3);
        x[by.start + s] = (mean.y + shift).max(1e-3);
    }
    x
}

/// Every source must lie behind the lens: the redshifts of the settings
/// ([`ReconstructConfig::check_behind_lens`]), then the first system at `z_s <= z_l`, an error
/// naming the file, the line (catalogues) or system, and the value.
fn check_source_redshifts(
    inputs: &Inputs<'_>,
    config: &ReconstructConfig,
) -> Result<(), ReconstructError> {
    let z_lens = inputs.plane.z_lens;
    let behind = |z: f64| z > z_lens;
    config.check_behind_lens(z_lens)?;
    let bad = |source_name: &str, place: String, z: f64| {
        ReconstructError::Config {
        source_name: source_name.to_string(),
        message: format!(
            "{place}: z_s = {z} is not behind the lens (z_lens = {z_lens}): a source must have z_s > z_l"
        ),
    }
    };
    match inputs.images {
        ConstraintSource::Catalog(cat) => {
            for s in &cat.systems {
                if let Some(z) = s.z.filter(|&z| !behind(z)) {
                    let line = s.images.first().map_or(0, |i| i.line);
                    return Err(bad(
                        &cat.source_name,
                        format!("line {line} (system {})", s.id),
                        z,
                    ));
                }
            }
        }
        ConstraintSource::Arcs(arcs) => {
            for s in &arcs.systems {
                if let Some(z) = s.z.filter(|&z| !behind(z)) {
                    let place = match s.line {
                        0 => format!("system {}", s.id),
                        line => format!("line {line} (system {})", s.id),
                    };
                    return Err(bad(&arcs.source_name, place, z));
                }
            }
        }
    }
    Ok(())
}

/// `D_ls/D_s` below which a system's given redshift is said to be just behind the lens.
/// A distant source has 0.5 - 0.9 behind a cluster at z_l = 0.2 - 0.5; at a tenth of that
/// the lens deflects the light a tenth as much, and multiple images are rare.
const JUST_BEHIND_RATIO: f64 = 0.1;

/// One warning per fitted system whose given redshift lies just behind the lens
/// (`D_ls/D_s` < [`JUST_BEHIND_RATIO`]): allowed, but more often a typing slip (the lens's
/// own redshift, a member's) than a real multiple image. Assumed and estimated redshifts
/// are not the catalogue's and are not said. With an image catalogue the warning names the
/// lines that give the redshift, where the user would mend it.
fn just_behind_lens(
    constraints: &ConstraintSet,
    config: &ReconstructConfig,
    plane: &LensPlane,
    catalog: Option<&ImageCatalog>,
) -> Vec<String> {
    let estimated = |id: &str| config.constraints.z_estimates.iter().any(|(e, _)| e == id);
    let Ok(at_2) = plane.distance_ratio(2.0) else {
        return Vec::new();
    };
    constraints
        .systems
        .iter()
        .filter(|s| !s.z_assumed && !estimated(&s.id))
        .filter_map(|s| {
            let ratio = plane.distance_ratio(s.z).ok()?;
            (ratio < JUST_BEHIND_RATIO).then(|| {
                format!(
                    "system {}{}: z_s = {} lies just behind the lens (z_lens = {}): D_ls/D_s = \
                     {ratio:.3} against {at_2:.2} for a source at z = 2, so the lens bends its \
                     light little and multiple images of it are rare; check that redshift",
                    s.id,
                    catalog.map_or(String::new(), |c| catalogue_lines(c, &s.id)),
                    s.z,
                    plane.z_lens
                )
            })
        })
        .collect()
}

/// " (images.cat, lines 12, 13, 14)": where system `id`'s images are in `catalog`, or
/// nothing when it holds no such system.
fn catalogue_lines(catalog: &ImageCatalog, id: &str) -> String {
    let Some(system) = catalog.systems.iter().find(|s| s.id == id) else {
        return String::new();
    };
    let noun = if system.images.len() == 1 {
        "line"
    } else {
        "lines"
    };
    let lines = crate::error::line_list(system.images.iter().map(|i| i.line));
    format!(" ({}, {noun} {lines})", catalog.source_name)
}

fn describe_excluded(constraints: &ConstraintSet) -> String {
    if constraints.excluded.is_empty() {
        return "the catalogue holds no system".to_string();
    }
    let list: Vec<String> = constraints
        .excluded
        .iter()
        .map(|e| format!("{} ({})", e.id, e.reason))
        .collect();
    format!("left out: {}", list.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate(
        kind: Regulariser,
        strength: f64,
        systems: &[(&str, &[Option<f64>])],
    ) -> StrengthCandidate {
        StrengthCandidate {
            regulariser: kind,
            strength,
            // A grid of its own per regulariser, so that the choice is seen to carry it.
            cells: Some(if kind == Regulariser::Gradient {
                24
            } else {
                32
            }),
            holdout_median_arcsec: None,
            holdout_rms_arcsec: None,
            holdout_unmatched: 0,
            fit_median_arcsec: None,
            holdout_by_system: systems
                .iter()
                .map(|(id, o)| SystemOffsets {
                    id: id.to_string(),
                    offsets_arcsec: o.to_vec(),
                })
                .collect(),
        }
    }

    fn pick(regulariser: Regulariser, strength: f64, cells: usize) -> Candidate {
        Candidate {
            regulariser,
            strength,
            cells: Some(cells),
        }
    }

    fn choice(candidates: Vec<StrengthCandidate>) -> StrengthChoice {
        StrengthChoice {
            folds: 2,
            candidates,
            chosen: 1.0,
            chosen_regulariser: Regulariser::Gradient,
            chosen_cells: None,
            rule: String::new(),
            before_estimates: None,
            crowded_maps: Vec::new(),
        }
    }

    #[test]
    fn a_draw_rescores_the_candidates_on_the_systems_it_drew() {
        let g = Regulariser::Gradient;
        let c = Regulariser::Curvature;
        let choice = choice(vec![
            candidate(
                g,
                0.01,
                &[
                    ("1", &[Some(0.1), Some(0.1)]),
                    ("2", &[Some(1.0), Some(1.0)]),
                ],
            ),
            candidate(
                c,
                0.1,
                &[
                    ("1", &[Some(0.3), Some(0.3)]),
                    ("2", &[Some(0.2), Some(0.2)]),
                ],
            ),
        ]);
        // Both once: medians 0.55 against 0.25.
        assert_eq!(choice.best_for(|_| 1), Some(pick(c, 0.1, 32)));
        // System 1 alone: 0.1 against 0.3.
        assert_eq!(
            choice.best_for(|id| usize::from(id == "1")),
            Some(pick(g, 0.01, 24))
        );
        // System 1 drawn twice, 2 once: medians 0.1 against 0.3 (a draw counts its repeats).
        assert_eq!(
            choice.best_for(|id| if id == "1" { 2 } else { 1 }),
            Some(pick(g, 0.01, 24))
        );
        // Nothing drawn that was predicted: no choice.
        assert_eq!(choice.best_for(|_| 0), None);
        assert_eq!(
            choice.ranked_for(|_| 1),
            Some(vec![pick(c, 0.1, 32), pick(g, 0.01, 24)])
        );
        // A candidate whose map of every system was passed over as crowded is no draw's.
        let mut passed = choice.clone();
        passed.crowded_maps = vec![CrowdedMap {
            candidate: pick(c, 0.1, 32),
            crowding: crowding(20),
        }];
        assert_eq!(passed.ranked_for(|_| 1), Some(vec![pick(g, 0.01, 24)]));
        assert_eq!(passed.best_for(|_| 1), Some(pick(g, 0.01, 24)));
    }

    #[test]
    fn unmatched_images_of_drawn_systems_come_first() {
        let g = Regulariser::Gradient;
        let c = Regulariser::Curvature;
        let choice = choice(vec![
            candidate(g, 0.01, &[("1", &[Some(0.1)]), ("2", &[None, Some(0.1)])]),
            candidate(
                c,
                0.1,
                &[("1", &[Some(0.5)]), ("2", &[Some(0.5), Some(0.5)])],
            ),
        ]);
        assert_eq!(choice.best_for(|_| 1), Some(pick(c, 0.1, 32)));
        assert_eq!(
            choice.best_for(|id| usize::from(id == "1")),
            Some(pick(g, 0.01, 24))
        );
    }

    /// The other regularisers' best candidates, by the choice's own rule (unmatched images
    /// first), one per regulariser in the candidates' order; the chosen one's never.
    #[test]
    fn each_other_regulariser_gives_its_best_candidate() {
        let (g, c, d) = (
            Regulariser::Gradient,
            Regulariser::Curvature,
            Regulariser::Density,
        );
        let scored = |kind, strength, median, unmatched| StrengthCandidate {
            holdout_median_arcsec: Some(median),
            holdout_unmatched: unmatched,
            ..candidate(kind, strength, &[])
        };
        let choice = choice(vec![
            scored(d, 0.01, 0.4, 1),
            scored(g, 1.0, 0.1, 0),
            scored(c, 0.1, 0.9, 0),
            scored(d, 0.1, 0.8, 0),
            scored(c, 1.0, 0.5, 0),
            scored(d, 1.0, 0.6, 0),
        ]);
        assert_eq!(
            choice.best_of_other_regularisers(),
            [pick(d, 1.0, 32), pick(c, 1.0, 32)]
        );
        let only_chosen =
            super::tests::choice(vec![scored(g, 1.0, 0.1, 0), scored(g, 0.1, 0.2, 0)]);
        assert!(only_chosen.best_of_other_regularisers().is_empty());
    }

    /// Each grid once (scales that round to the same cells give one grid), coarsest first,
    /// with every regulariser and strength.
    #[test]
    fn candidates_pair_every_grid_with_every_regulariser_and_strength() {
        let mut config = ReconstructConfig::default();
        config.grid.cells = 10;
        config.objective.auto_grid_scales = vec![1.0, 0.74, 0.75, 0.05];
        config.objective.auto_regularisers = vec![Regulariser::Curvature];
        config.objective.candidates = vec![0.1, 1.0];
        let grids: Vec<Option<usize>> = strength_candidates(&config)
            .iter()
            .map(|c| c.cells)
            .collect();
        // 0.05 of 10 is 0.5: one cell; 7.4 rounds to 7 and 7.5 to 8.
        assert_eq!(
            grids,
            [1, 1, 7, 7, 8, 8, 10, 10].map(Some).to_vec(),
            "{grids:?}"
        );
        // 7.5 and 7.6 both round to 8: one grid.
        config.objective.auto_grid_scales = vec![0.75, 0.76];
        let grids: Vec<Option<usize>> = strength_candidates(&config)
            .iter()
            .map(|c| c.cells)
            .collect();
        assert_eq!(grids, [8, 8].map(Some).to_vec());
        // The chosen candidate sets the grid of the run.
        let c = Candidate {
            regulariser: Regulariser::Curvature,
            strength: 0.1,
            cells: Some(7),
        };
        let applied = c.apply(&config);
        assert_eq!(applied.grid.cells, 7);
        assert_eq!(applied.objective.strength, Strength::Value(0.1));
        assert_eq!(applied.objective.regulariser, Regulariser::Curvature);
    }

    /// The least-mass regulariser is a candidate with or without an external shear, and its
    /// candidates fit none while the others fit the one asked for.
    #[test]
    fn the_least_mass_candidates_fit_no_shear_beside_the_others() {
        let (g, d) = (Regulariser::Gradient, Regulariser::Density);
        let mut config = ReconstructConfig::default();
        config.objective.auto_grid_scales = vec![1.0];
        config.objective.auto_regularisers = vec![d, g];
        for sigma in [Some(0.1), None] {
            config.grid.external_shear_sigma = sigma;
            let candidates = strength_candidates(&config);
            let kinds: Vec<Regulariser> = candidates.iter().map(|c| c.regulariser).collect();
            assert_eq!(kinds.iter().filter(|&&r| r == d).count(), 3);
            assert_eq!(kinds.iter().filter(|&&r| r == g).count(), 3);
            for c in &candidates {
                let fitted = c.apply(&config).external_shear_fitted();
                let expected = if c.regulariser == d { None } else { sigma };
                assert_eq!(fitted, expected, "{c:?}");
            }
        }
    }

    /// The memory estimate counts the shear's layers only when the run may fit one: not for
    /// the least-mass regulariser, fixed or the only candidate.
    #[test]
    fn the_memory_estimate_counts_a_shear_only_where_one_is_fitted() {
        let mut config = ReconstructConfig::default();
        assert!(fits_external_shear(&config));
        config.objective.auto_regularisers = vec![Regulariser::Density];
        assert!(!fits_external_shear(&config));
        config.objective.strength = Strength::Value(0.1);
        config.objective.regulariser = Regulariser::Density;
        assert!(!fits_external_shear(&config));
        config.objective.regulariser = Regulariser::Curvature;
        assert!(fits_external_shear(&config));
        config.grid.external_shear_sigma = None;
        assert!(!fits_external_shear(&config));
    }

    /// The choice in words, as the CLI prints it.
    #[test]
    fn a_choice_says_what_was_chosen_and_how() {
        let mut c = choice(vec![candidate(Regulariser::Gradient, 0.01, &[])]);
        c.chosen_regulariser = Regulariser::Curvature;
        c.chosen = 0.1;
        c.chosen_cells = Some(24);
        assert_eq!(
            c.describe(),
            "curvature at strength 0.1 on 24 x 24 cells, chosen by 2-fold cross-validation \
             of 1 candidates"
        );
        let config = ReconstructConfig::default();
        let none = StrengthChoice::from_trials(&config, 1, Vec::new());
        assert_eq!(
            none.describe(),
            "gradient at strength 0.1 (too few fitted systems to hold any out, so the middle \
             candidate)"
        );
        // Trials that predicted nothing rank nothing: not "chosen by cross-validation".
        let blind = vec![
            candidate(Regulariser::Gradient, 0.01, &[("1", &[None, None])]),
            candidate(Regulariser::Curvature, 1.0, &[("1", &[None, None])]),
        ];
        let none = StrengthChoice::from_trials(&config, 4, blind);
        assert_eq!(
            none.describe(),
            "gradient at strength 0.1 (none of 2 candidates predicted an image of the systems 4 \
             folds held out, so the middle candidate)"
        );
        assert!(!none.was_cross_validated());
        c.crowded_maps = vec![CrowdedMap {
            candidate: pick(Regulariser::Density, 0.01, 32),
            crowding: Crowding {
                crowded_systems: 22,
                systems: 45,
            },
        }];
        assert_eq!(
            c.describe(),
            "curvature at strength 0.1 on 24 x 24 cells, chosen by 2-fold cross-validation \
             of 1 candidates; passed over for maps that predict far more images than observed \
             for more than a third of the systems: density at strength 0.01 on 32 x 32 cells \
             (22 of 45)"
        );
    }

    fn crowding(crowded_systems: usize) -> Crowding {
        Crowding {
            crowded_systems,
            systems: 30,
        }
    }

    /// `first_uncrowded` with maps that are their crowding: which map is kept, which
    /// candidates are fitted and which passed over.
    fn uncrowded(first: usize, maps: &[usize]) -> (Option<usize>, f64, Vec<f64>, Vec<f64>) {
        let next: Vec<Candidate> = (1..=maps.len())
            .map(|i| pick(Regulariser::Curvature, i as f64, 16))
            .collect();
        let mut fitted = Vec::new();
        let (map, used, passed) = first_uncrowded::<Crowding, ()>(
            crowding(first),
            pick(Regulariser::Curvature, 0.0, 16),
            &next,
            |m| *m,
            |c| {
                fitted.push(c.strength);
                Ok(Some(crowding(maps[c.strength as usize - 1])))
            },
        )
        .unwrap();
        let passed = passed.iter().map(|p| p.candidate.strength).collect();
        (
            map.map(|m| m.crowded_systems),
            used.strength,
            fitted,
            passed,
        )
    }

    /// The chosen map stands unless more than a third of its systems are crowded (10 of 30
    /// is not more); then the next candidates are fitted in order until one is not, at most
    /// `CROWDED_MAP_RETRIES`, and when every one is crowded the least crowded is kept (the
    /// earlier on a tie).
    #[test]
    fn a_crowded_map_gives_way_to_the_next_candidate_that_is_not() {
        assert_eq!(uncrowded(10, &[0, 0]), (None, 0.0, vec![], vec![]));
        assert_eq!(
            uncrowded(11, &[12, 3, 0]),
            (Some(3), 2.0, vec![1.0, 2.0], vec![0.0, 1.0])
        );
        // Every one crowded: at most three more fitted, the least crowded kept, on a tie
        // the earlier.
        assert_eq!(
            uncrowded(20, &[15, 12, 12, 0]),
            (Some(12), 2.0, vec![1.0, 2.0, 3.0], vec![0.0, 1.0, 2.0, 3.0])
        );
        // The first map the least crowded: none replaces it.
        assert_eq!(
            uncrowded(11, &[15, 12]),
            (None, 0.0, vec![1.0, 2.0], vec![0.0, 1.0, 2.0])
        );
        assert_eq!(CROWDED_MAP_RETRIES, 3);
        // A cancelled fit ends the search with what was made.
        let next = [pick(Regulariser::Curvature, 1.0, 16)];
        let (map, used, passed) = first_uncrowded::<Crowding, ()>(
            crowding(11),
            pick(Regulariser::Curvature, 0.0, 16),
            &next,
            |m| *m,
            |_| Ok(None),
        )
        .unwrap();
        assert_eq!((map, used.strength, passed.len()), (None, 0.0, 1));
    }

    #[test]
    fn a_choice_without_per_system_offsets_is_not_remade() {
        let choice = choice(vec![candidate(Regulariser::Gradient, 0.01, &[])]);
        assert_eq!(choice.best_for(|_| 1), None);
    }
}
