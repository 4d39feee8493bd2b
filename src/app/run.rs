//! Running a session: a WSLAP+ reconstruction, a forward model or a look-up of deflection
//! maps; the result keeps the maps, so curves at another source redshift need no new solve.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::curves::critical_curves;
use crate::inversion::{build_constraints, Layer, LinearSystem, ObjectiveTerms};
use crate::products::{own_map_side, ProductOptions, Products};
use crate::reconstruct::{add_external_shear, member_layers, shear_set, BcgFacts, Verdict};
use crate::reconstruct::{
    avoid_crowded_map, check_memory, cross_validate, grid_of, holdable_sources, map_geometry,
    product_options, reconstruct, reconstruct_with_choice, refit_for_second_choice, second_choice,
    second_round, strength_candidates, strength_folds, with_uncrowded_map, Candidate,
    ConvergenceRecord, CrossValidation, Dataset, DatasetError, Ensemble, EstimatedRedshifts,
    Inputs, MemoryLimit, ReconstructConfig, ReconstructError, Reconstruction, RunSize, RunStatus,
    SecondRound, SourceReport, StageTimings, StrengthCandidate, StrengthChoice, DEFAULT_FOLDS,
};
use crate::solver::{Control, Iterate};

use super::data::{DataMarks, DataViews};
use super::iterates::{IterateCache, APP_KEPT_ITERATES};
use super::{AppError, Session};

/// Map width of a forward model without a `products.size_arcsec` setting (arcsec).
const FORWARD_SIZE_ARCSEC: f64 = 200.0;

/// What a run computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunKind {
    /// WSLAP+ from the image catalogue or arcs (and members).
    Reconstruct,
    /// Maps and curves of the model file.
    Forward,
    /// Maps and curves of the deflection FITS pair.
    Lookup,
}

/// What a run made: maps (a forward model or a look-up) or a reconstruction with its maps.
#[derive(Debug)]
pub enum Outcome {
    Maps(Box<Products>),
    Reconstruction(Box<Reconstruction>),
}

/// The last result of a session.
#[derive(Debug)]
pub struct SessionResult {
    pub kind: RunKind,
    pub outcome: Outcome,
    /// What the views draw of the data the result was made from.
    pub marks: DataMarks,
    /// Wall-clock time of the run in ms.
    pub elapsed_ms: f64,
    /// The maps of the last iterate drawn (see the `iterates` module).
    pub(crate) iterate_cache: IterateCache,
    /// The ensemble run after the reconstruction (see the `ensemble` module), if any.
    pub ensemble: Option<Box<Ensemble>>,
}

impl SessionResult {
    /// The maps, curves and profile of the result.
    pub fn products(&self) -> &Products {
        match &self.outcome {
            Outcome::Maps(p) => p,
            Outcome::Reconstruction(r) => &r.products,
        }
    }

    fn products_mut(&mut self) -> &mut Products {
        match &mut self.outcome {
            Outcome::Maps(p) => p,
            Outcome::Reconstruction(r) => &mut r.products,
        }
    }

    /// The reconstruction, when the result is one.
    pub fn reconstruction(&self) -> Option<&Reconstruction> {
        match &self.outcome {
            Outcome::Maps(_) => None,
            Outcome::Reconstruction(r) => Some(r),
        }
    }

    /// Critical curves, caustics and magnification at `z_source` from the stored maps
    /// (`f = D_ls/D_s(z_source)`), without solving again.
    pub fn redraw(&mut self, z_source: f64) -> Result<(), AppError> {
        curves_at(self.products_mut(), z_source)
    }

    /// Predicted image positions of every system (arcsec) with `|mu| >=`
    /// [`crate::reconstruct::SHOWN_MIN_MAGNIFICATION`], the ones the map draws
    /// ([`crate::reconstruct::PredictedImage::is_shown`]).
    pub fn predicted(&self) -> Vec<DVec2> {
        let sources = self
            .reconstruction()
            .into_iter()
            .flat_map(|r| r.sources.iter());
        sources
            .flat_map(|s| s.predicted.iter())
            .filter(|p| p.is_shown())
            .map(|p| p.position_arcsec)
            .collect()
    }
}

/// Critical curves, caustics and magnification of `p` at `z_source` from its maps.
pub(super) fn curves_at(p: &mut Products, z_source: f64) -> Result<(), AppError> {
    let f = p
        .plane
        .distance_ratio(z_source)
        .map_err(|e| AppError::Setting(format!("z_source: {e}")))?;
    p.distance_ratio = f;
    p.magnification = p.maps.magnification(f);
    p.curves = critical_curves(&p.maps, f, z_source, None);
    // Only the stored maps are at hand here: a curve that leaves them gives a lower bound.
    p.einstein_radius_map_arcsec = own_map_side(&p.curves, p.maps.geometry());
    Ok(())
}

/// "Nothing to fit" is something missing; a file that does not read is the file's error.
fn dataset_error(e: DatasetError) -> AppError {
    match e {
        DatasetError::NoConstraints => {
            AppError::Missing("load an image catalogue or an arcs file to reconstruct".to_string())
        }
        other => AppError::File(other.to_string()),
    }
}

/// `config` keeping [`APP_KEPT_ITERATES`] iterates, for the app to step through.
fn keeping_iterates(config: &ReconstructConfig) -> ReconstructConfig {
    let mut config = config.clone();
    config.solver.keep_iterates = APP_KEPT_ITERATES;
    config
}

fn run_error(e: ReconstructError) -> AppError {
    AppError::Run(e.to_string())
}

/// The session's result of reconstruction `r` of `parsed` (its warnings after the data's).
fn reconstruction_result(mut r: Reconstruction, parsed: &Dataset) -> SessionResult {
    let mut warnings = parsed.warnings.clone();
    warnings.append(&mut r.warnings);
    r.warnings = warnings;
    SessionResult {
        kind: RunKind::Reconstruct,
        outcome: Outcome::Reconstruction(Box::new(r)),
        marks: parsed.marks(),
        elapsed_ms: 0.0,
        iterate_cache: IterateCache::default(),
        ensemble: None,
    }
}

/// What a project keeps of a reconstruction besides its data and settings
/// ([`Session::restore_reconstruction`] rebuilds the rest).
#[derive(Debug, Clone, Default)]
pub struct StoredRun {
    /// The solution vector `X`.
    pub x: Vec<f64>,
    pub iterations: usize,
    pub convergence: Vec<ConvergenceRecord>,
    pub sources: Vec<SourceReport>,
    /// The kept iterates, for the iteration slider (none: no slider).
    pub iterates: Vec<Iterate>,
    /// An "auto" strength's choice (the project's `summary.json`): it sets the grid and
    /// regulariser the run used, and the result keeps it.
    pub choice: Option<StrengthChoice>,
    /// The run's warnings (its `summary.json`), among them what its redshift estimates said,
    /// which rebuilding from `x` cannot say again; `None`: the data's, found again.
    pub warnings: Option<Vec<String>>,
}

impl Session {
    /// Runs `kind`; `progress` sees every QADP report (reconstruction only) and may cancel.
    /// The previous result is replaced only on success.
    pub fn run(
        &mut self,
        kind: RunKind,
        progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
    ) -> Result<(), AppError> {
        let t = crate::products::Clock::start();
        let mut result = match kind {
            RunKind::Reconstruct => self.run_reconstruction(progress)?,
            RunKind::Forward => self.run_forward()?,
            RunKind::Lookup => self.run_lookup()?,
        };
        result.elapsed_ms = t.ms();
        self.result = Some(result);
        Ok(())
    }

    /// Runs `f` on the reconstruction's inputs (the loaded data in one frame) and settings.
    pub(super) fn with_inputs<T>(
        &self,
        f: impl FnOnce(&Inputs<'_>, &ReconstructConfig, &Dataset) -> Result<T, AppError>,
    ) -> Result<T, AppError> {
        let mut parsed = self.parsed()?;
        let plane = self.settings.lens_plane()?;
        let mut config = self.settings.reconstruct.clone();
        // The result lists the data's warnings, this one among them.
        let unfitted = parsed.unfitted_arcs(config.constraints.mode);
        parsed.warnings.extend(unfitted);
        let inputs = parsed
            .inputs(plane, &self.settings.holdout, &mut config)
            .map_err(dataset_error)?;
        f(&inputs, &config, &parsed)
    }

    fn run_reconstruction(
        &self,
        progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
    ) -> Result<SessionResult, AppError> {
        self.with_inputs(|inputs, config, parsed| {
            let r = reconstruct(inputs, &keeping_iterates(config), progress).map_err(run_error)?;
            Ok(reconstruction_result(r, parsed))
        })
    }

    /// For an "auto" regulariser strength, the candidates and the number of folds each is
    /// cross-validated with (below 2: too few systems); `None` when the strength is a number.
    /// The app runs [`Self::strength_trial`] for the candidates in parallel workers, then
    /// [`Self::run_with_trials`].
    pub fn strength_plan(&self) -> Result<Option<(Vec<Candidate>, usize)>, AppError> {
        self.with_inputs(|inputs, config, _| {
            if config.objective.strength.value().is_some() {
                return Ok(None);
            }
            // Before the pool's workers start: each would run out of memory alone.
            check_memory(inputs, config).map_err(run_error)?;
            let folds = strength_folds(inputs, config).map_err(run_error)?;
            Ok(Some((strength_candidates(config), folds)))
        })
    }

    /// The cross-validation of one `candidate` on the loaded data and settings, as a
    /// reconstruction with "auto" runs it, with `estimates` fitted in every fold when given
    /// (a trial of a [`SecondRound`]); the session's result is not touched.
    pub fn strength_trial(
        &self,
        candidate: &Candidate,
        folds: usize,
        estimates: Option<&EstimatedRedshifts>,
        progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
    ) -> Result<StrengthCandidate, AppError> {
        self.with_inputs(|inputs, config, _| {
            let fitting = estimates.map(|e| e.fitted_by(config));
            let config = fitting.as_ref().unwrap_or(config);
            crate::reconstruct::strength_trial(inputs, config, candidate, folds, progress)
                .map_err(run_error)
        })
    }

    /// The second round the result's "auto" choice needs, if it does ([`second_round`]: it
    /// estimated redshifts after choosing): its trials are run like the first round's, with
    /// its estimates, then [`Self::choose_again_with_trials`].
    pub fn second_strength_round(&self) -> Option<SecondRound> {
        second_round(self.result.as_ref()?.reconstruction()?)
    }

    /// The result's "auto" choice made again from the `trials` of its [`SecondRound`]: the
    /// result keeps its map when the choice stands, else is the fit with the new choice (the
    /// estimated redshifts kept). Replaces the result on success.
    pub fn choose_again_with_trials(
        &mut self,
        trials: Vec<StrengthCandidate>,
        progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
    ) -> Result<(), AppError> {
        let t = crate::products::Clock::start();
        let missing = || AppError::Missing("no reconstruction to choose again for".into());
        let r = self
            .result
            .as_ref()
            .and_then(SessionResult::reconstruction)
            .ok_or_else(missing)?;
        let choice = second_choice(r, trials).ok_or_else(missing)?;
        let (choice, refit) = self.with_inputs(|inputs, _, parsed| {
            let refit = refit_for_second_choice(inputs, r, &choice, progress).map_err(run_error)?;
            // The map the choice ends with, unless it is crowded.
            let (choice, other) =
                avoid_crowded_map(inputs, refit.as_ref().unwrap_or(r), &choice, progress)
                    .map_err(run_error)?;
            let refit = other.or(refit).map(|mut m| {
                m.strength_choice = Some(choice.clone());
                reconstruction_result(m, parsed)
            });
            Ok((choice, refit))
        })?;
        let before_ms = self.result.as_ref().map_or(0.0, |x| x.elapsed_ms);
        let Some(mut result) = refit else {
            if let Some(Outcome::Reconstruction(r)) = self.result.as_mut().map(|x| &mut x.outcome) {
                r.strength_choice = Some(choice);
            }
            return Ok(());
        };
        result.elapsed_ms = before_ms + t.ms();
        // The refit's own timings start at the refit: the run in this worker is both.
        if let Outcome::Reconstruction(r) = &mut result.outcome {
            r.timings.total_ms = result.elapsed_ms;
        }
        self.result = Some(result);
        Ok(())
    }

    /// The reconstruction of an "auto" strength whose candidates were tried elsewhere
    /// (`trials`, one per candidate, over `folds` folds): the strength they choose is used
    /// and the result carries the curve. Replaces the result on success, as [`Self::run`].
    pub fn run_with_trials(
        &mut self,
        trials: Vec<StrengthCandidate>,
        folds: usize,
        progress: &mut dyn FnMut(&ConvergenceRecord) -> Control,
    ) -> Result<(), AppError> {
        let t = crate::products::Clock::start();
        let mut result = self.with_inputs(|inputs, config, parsed| {
            let choice = StrengthChoice::from_trials(config, folds, trials);
            let config = keeping_iterates(config);
            let r =
                reconstruct_with_choice(inputs, &config, choice, progress).map_err(run_error)?;
            // The map stands unless crowded, when it is the last round's.
            let r = match second_round(&r) {
                Some(_) => r,
                None => with_uncrowded_map(inputs, r, progress).map_err(run_error)?,
            };
            Ok(reconstruction_result(r, parsed))
        })?;
        result.elapsed_ms = t.ms();
        self.result = Some(result);
        Ok(())
    }

    /// The app's number of cross-validation folds: [`DEFAULT_FOLDS`], or one per source a fold
    /// can hold out when there are fewer ([`crate::reconstruct::holdable_sources`]: systems at
    /// a redshift of their own, the knots of one galaxy counted once).
    pub fn default_folds(&self) -> Result<usize, AppError> {
        self.with_inputs(|inputs, config, _| {
            let sources = holdable_sources(inputs, config).map_err(run_error)?;
            Ok(DEFAULT_FOLDS.min(sources.len()))
        })
    }

    /// K-fold cross-validation of the settings on the loaded data
    /// ([`crate::reconstruct::cross_validate`], `wslap reconstruct --folds`), with the folds'
    /// convergence on the maps a reconstruction with these settings makes; systems whose
    /// redshift the session's result estimated are fitted in every fold at it. The session's
    /// result is not touched. `progress` sees the fold (1-based) and every QADP report, and
    /// may cancel.
    pub fn cross_validate(
        &self,
        folds: usize,
        progress: &mut dyn FnMut(usize, &ConvergenceRecord) -> Control,
    ) -> Result<CrossValidation, AppError> {
        self.with_inputs(|inputs, config, parsed| {
            let geometry = map_geometry(inputs, config).map_err(run_error)?;
            // Systems whose redshift the result estimated are fitted in every fold at it, when
            // the result was made from these images.
            let observed = parsed.marks().observed;
            let mut config = config.clone();
            if let Some(r) = self
                .result()
                .ok()
                .filter(|r| r.marks.observed == observed)
                .and_then(|r| r.reconstruction())
            {
                r.fit_estimates_in(&mut config.constraints);
            }
            cross_validate(inputs, &config, folds, Some(geometry), progress).map_err(run_error)
        })
    }

    /// The verdict on the session's result once `cv`, a cross-validation of the loaded data
    /// with the current settings ([`Self::cross_validate`]), has run: its held-out images count
    /// as held out ([`Reconstruction::verdict_after`]; `None` for `cv`: the result's own
    /// verdict). `None` when the result is no reconstruction.
    pub fn verdict_after(&self, cv: Option<&CrossValidation>) -> Result<Option<Verdict>, AppError> {
        Ok(self.result()?.reconstruction().map(|r| r.verdict_after(cv)))
    }

    /// The files of `cv`'s convergence maps (`wslap reconstruct --folds` writes the same):
    /// `crossval-kappa-mean.fits`, `crossval-kappa-spread.fits` (in the loaded data's sky
    /// frame) and `crossval-kappa-spread.png`, with the result's critical curves when the
    /// result is on the same maps. Empty when `cv` has no maps.
    pub fn crossval_files(
        &self,
        cv: &CrossValidation,
    ) -> Result<Vec<(&'static str, Vec<u8>)>, AppError> {
        let Some(kappa) = &cv.kappa else {
            return Ok(Vec::new());
        };
        let curves = self
            .result()
            .ok()
            .map(|r| r.products())
            .filter(|p| p.maps.geometry() == kappa.spread.geometry)
            .map(|p| &p.curves);
        let (reference, z_lens) =
            self.with_inputs(|inputs, _, _| Ok((inputs.reference, inputs.plane.z_lens)))?;
        kappa
            .files(reference, z_lens, curves, cv.runs.len())
            .map_err(|e| AppError::Run(e.to_string()))
    }

    /// Rebuilds a reconstruction from a stored solution `x` without iterating: the same
    /// constraints, grid, layers and linear system as the run that found `x` (no grid
    /// refinements), the lens of `x` and its products; the rest of the result is `stored`'s
    /// (see [`StoredRun`]).
    pub fn restore_reconstruction(&mut self, stored: StoredRun) -> Result<(), AppError> {
        let StoredRun {
            x,
            iterations,
            convergence,
            sources,
            iterates,
            choice,
            warnings: run_warnings,
        } = stored;
        let t = crate::products::Clock::start();
        let run = |e: &dyn std::fmt::Display| AppError::Run(e.to_string());
        let parsed = self.parsed()?;
        let plane = self.settings.lens_plane()?;
        let mut config = self.settings.reconstruct.clone();
        if config.grid.refinements > 0 {
            return Err(AppError::Missing(
                "a refined grid cannot be rebuilt from X: solve again".to_string(),
            ));
        }
        let unfitted = parsed.unfitted_arcs(config.constraints.mode);
        let (source, mode) = parsed
            .constraints(config.constraints.mode)
            .map_err(dataset_error)?;
        config.constraints.mode = mode;
        // Systems whose redshift the run estimated were fitted at it, with its error.
        crate::reconstruct::fit_estimates_in(&sources, &mut config.constraints);
        // An "auto" run was made on the grid its choice took; the result says "auto" as a
        // run's does.
        let kept = config.clone();
        if let Some(c) = &choice {
            config = c.chosen_candidate().apply(&config);
        }
        let constraints = build_constraints(source, &config.constraints, &self.settings.holdout)
            .map_err(|e| run(&e))?;
        let (shear, shear_warning) = shear_set(parsed.shear.as_ref(), &config, &plane);
        let grid = grid_of(&constraints, &shear, &config).map_err(|e| run(&e))?;
        let mut warnings = parsed.warnings.clone();
        warnings.extend(shear_warning);
        warnings.extend(unfitted);
        let mut bcg = BcgFacts::default();
        let mut layers: Vec<Layer> = match &parsed.members {
            None => Vec::new(),
            Some(m) => {
                let members = member_layers(m, &config.members, &plane, &grid, &constraints)
                    .map_err(|e| run(&e))?;
                warnings.extend(members.warnings);
                bcg = members.bcg;
                members.layers
            }
        };
        add_external_shear(&mut layers, &config, &grid);
        let system = LinearSystem::build_with_shear(
            &grid,
            &layers,
            &constraints,
            &shear,
            &plane,
            &config.system,
            ObjectiveTerms::default(),
        )
        .map_err(|e| run(&e))?;
        warnings.extend(system.measurability_warnings());
        let lens = system.reconstructed_lens(&x).map_err(|e| run(&e))?;
        if let Some(w) = run_warnings {
            warnings = w;
        }
        let opts = product_options(&config, &grid);
        let products =
            Products::from_lens(&lens, plane, parsed.reference(), &opts).map_err(|e| run(&e))?;
        self.result = Some(SessionResult {
            kind: RunKind::Reconstruct,
            outcome: Outcome::Reconstruction(Box::new(Reconstruction {
                config: kept,
                system,
                x,
                status: RunStatus::Restored,
                iterations,
                convergence,
                iterates,
                lens,
                products,
                sources,
                warnings,
                timings: StageTimings::default(),
                strength_choice: choice,
                free_z: None,
                member_positions_arcsec: parsed.members_arcsec(),
                bcg,
            })),
            marks: parsed.marks(),
            elapsed_ms: t.ms(),
            iterate_cache: IterateCache::default(),
            ensemble: None,
        });
        Ok(())
    }

    fn run_forward(&self) -> Result<SessionResult, AppError> {
        let model = self
            .data
            .model_lens(&self.settings.par_options())?
            .ok_or_else(|| AppError::Missing("load a model file first".to_string()))?;
        let p = &self.settings.reconstruct.products;
        RunSize::maps(p.pixels)
            .memory(&self.settings.reconstruct)
            .check(MemoryLimit::here())
            .map_err(|e| AppError::Run(e.to_string()))?;
        let opts = ProductOptions {
            z_source: p.z_source,
            size_arcsec: p.size_arcsec.unwrap_or(FORWARD_SIZE_ARCSEC),
            pixels: p.pixels,
            ..ProductOptions::default()
        };
        let products = Products::from_lens(&model.lens, model.plane, model.reference, &opts)
            .map_err(|e| AppError::Run(e.to_string()))?;
        let parsed = self.parsed().unwrap_or_default();
        Ok(SessionResult {
            kind: RunKind::Forward,
            outcome: Outcome::Maps(Box::new(products)),
            marks: parsed.marks(),
            elapsed_ms: 0.0,
            iterate_cache: IterateCache::default(),
            ensemble: None,
        })
    }

    fn run_lookup(&self) -> Result<SessionResult, AppError> {
        let [Some(ax), Some(ay)] = &self.data.deflection else {
            return Err(AppError::Missing(
                "load both deflection maps (x and y) first".to_string(),
            ));
        };
        let plane = self.settings.lens_plane()?;
        let products = Products::from_deflection(
            ax.map.clone(),
            ay.map.clone(),
            plane,
            ax.reference,
            self.settings.reconstruct.products.z_source,
        )
        .map_err(|e| AppError::Run(format!("{} / {}: {e}", ax.name, ay.name)))?;
        Ok(SessionResult {
            kind: RunKind::Lookup,
            outcome: Outcome::Maps(Box::new(products)),
            marks: DataMarks::default(),
            elapsed_ms: 0.0,
            iterate_cache: IterateCache::default(),
            ensemble: None,
        })
    }

    /// Sets `products.z_source` and redraws the curves of the last result from its maps.
    pub fn set_z_source(&mut self, z_source: f64) -> Result<(), AppError> {
        let next = self
            .settings
            .with_field("reconstruct.products.z_source", z_source.into())?;
        if let Some(r) = &mut self.result {
            r.redraw(z_source)?;
        }
        self.settings = next;
        Ok(())
    }
}
