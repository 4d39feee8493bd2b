//! The runs behind the caveats and choices of `report.md`, each at the case iteration count:
//!
//! - **Starts**: case (iii) from several starts (C0 = 0.001, the reasonable start, C0 = 1, and
//!   the bad start), each with its final C, lens-equation chi2 and grid mass in the arc region:
//!   how much the answer depends on the start, and whether a lower chi2 means a truer mass.
//! - **Best fit**: the minimiser of the same objective, approached with the accelerated
//!   projected gradient from the reasonable and the bad start, next to the chi2 of the
//!   simulated lens itself on the same rows: whether the data's best fit is the truth.
//! - **Sweep**: the defaults METHOD.md leaves open — the cell width (Gaussian sigma over the
//!   cell size), the row weights, and the member scale-radius law of a layer built from the
//!   member catalogue — and the optional prior on C (`members.c_prior_sigma`, off by default),
//!   scored by case (ii)'s median deflection error in the arc region (the realistic case:
//!   galaxy positions known, masses not).

use serde::{Deserialize, Serialize};

use super::metrics::lens_equation_chi2;
use super::{run_one, CaseReport, CaseRun, PaperConfig, PaperError, Scorer};
use crate::catalog::parse_member_catalog;
use crate::inversion::{Layer, MemberConfig, Weighting};
use crate::reconstruct::{LayerSource, Reconstruction, SolverMethod};
use crate::simulate::Simulation;

/// One run of the start study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StartRun {
    pub label: String,
    pub start_cell_mass_msun: f64,
    pub start_c: f64,
    /// Final C of the galaxy-true layer.
    pub c: f64,
    /// Final objective `phi` in f64 (comparable between starts: same system). It carries the
    /// large constant `-Theta^T W Theta / 2` of the frame shift, so compare `chi2`.
    pub objective: f64,
    /// Weighted squared residual of the lens equation, `2 phi + Theta^T W Theta`
    /// (dimensionless: weights in 1/arcsec^2).
    pub chi2: f64,
    /// `sqrt(chi2 / sum of row weights)`: the weighted rms source-plane residual, arcsec.
    pub source_rms_arcsec: f64,
    /// Root mean square of observed - predicted image positions, arcsec (None when no image
    /// was matched).
    pub image_plane_rms_arcsec: Option<f64>,
    pub grid_mass_msun: f64,
    pub grid_mass_region_msun: f64,
    pub deflection_error_median_arcsec: f64,
}

/// One run of the sweep of defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    /// "cell_sigma_factor", "weighting" or "member_r_s_law".
    pub parameter: String,
    pub value: String,
    /// The product default.
    pub is_default: bool,
    /// Lowest median deflection error of its parameter group.
    pub best: bool,
    pub c: Vec<f64>,
    pub deflection_error_median_arcsec: f64,
    pub deflection_error_p90_arcsec: f64,
    pub profile_max_rel_error: f64,
    pub einstein_radius_arcsec_z3: f64,
}

/// The data's best fit against the truth, on case (iii)'s rows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BestFit {
    /// Iterations of the accelerated projected gradient.
    pub iterations: usize,
    /// chi2 of the simulated lens itself (galaxies and soft halo, C = 1) on the same rows, with
    /// each system's best beta for it ([`super::metrics::lens_equation_chi2`]).
    pub truth_chi2: f64,
    /// `sqrt(truth_chi2 / sum of row weights)`, arcsec.
    pub truth_source_rms_arcsec: f64,
    /// The best fit from the reasonable start and from the bad start.
    pub runs: Vec<StartRun>,
}

/// The studies of `report.md` (empty when `PaperConfig::studies` is off).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Studies {
    pub starts: Vec<StartRun>,
    /// The bad start at the case iteration count (also one of `starts`).
    pub bad_start: Option<StartRun>,
    pub best_fit: Option<BestFit>,
    pub sweep: Vec<SweepRow>,
}

/// Cell widths of the sweep (Gaussian sigma over the cell size).
const CELL_SIGMA_FACTORS: [f64; 5] = [0.5, 0.75, 1.0, 1.25, 1.5];

/// The member scale-radius laws of the sweep: `(label, r_s of an M* halo in kpc, exponent)`.
const R_S_LAWS: [(&str, f64, f64); 3] = [
    ("r_s = 10 kpc (M/M*)^(1/3)", 10.0, 1.0 / 3.0),
    ("r_s = 20 kpc (M/M*)^(1/3)", 20.0, 1.0 / 3.0),
    ("r_s = 10 kpc (M/M*)^(1/2)", 10.0, 0.5),
];

/// Widths of the prior on C in the sweep (besides none, the default).
const C_PRIOR_SIGMAS: [f64; 2] = [0.3, 0.1];

/// The layers and default-run scores the studies start from.
pub(super) struct StudyInputs<'a> {
    pub layer_true: &'a Layer,
    pub layer_model: &'a Layer,
    /// The default case (ii) run, reused for the default rows of the sweep ...
    pub case_ii: &'a CaseRun,
    /// ... and case (iii), which is the reasonable start of the start study.
    pub case_iii: &'a CaseRun,
}

/// Runs the start study and the sweep.
pub(super) fn run_studies(
    config: &PaperConfig,
    simulation: &Simulation,
    scorer: &Scorer<'_>,
    inputs: &StudyInputs<'_>,
    say: &mut dyn FnMut(&str),
) -> Result<Studies, PaperError> {
    let StudyInputs {
        layer_true,
        layer_model,
        case_ii,
        case_iii,
    } = *inputs;
    let field = simulation.config.field_arcsec;
    let soft_per_cell = simulation.soft_mass_msun / (config.grid_cells * config.grid_cells) as f64;
    let reasonable_mass = config.reasonable_start_cell_mass_msun;
    let starts_spec = [
        ("C0 = 0.001", reasonable_mass, 0.001),
        ("reasonable", reasonable_mass, config.reasonable_start_c),
        ("C0 = 1", reasonable_mass, 1.0),
        (
            "bad",
            config.bad_start_cell_factor * soft_per_cell,
            config.bad_start_c,
        ),
    ];
    let mut starts = Vec::new();
    for (label, mass, c0) in starts_spec {
        let owned;
        let (rec, r) = if label == "reasonable" {
            // The same settings as case (iii): its run is reused.
            (&case_iii.reconstruction, case_iii.report.clone())
        } else {
            let mut rc = config.reconstruct_config(field, config.iterations);
            rc.solver.start_cell_mass_msun = mass;
            rc.solver.start_c = c0;
            owned = run_one(
                simulation,
                LayerSource::Given(std::slice::from_ref(layer_true)),
                &rc,
                "start study",
            )?;
            (&owned, scorer.score(&owned, "start study")?.report)
        };
        let run = start_run(label, mass, c0, rec, &r);
        say(&format!(
            "start study, {label}: C {:.3}, chi2 {:.4e} (source-plane rms {:.3}\"), grid mass in the arc region {:.3e} Msun",
            run.c, run.chi2, run.source_rms_arcsec, run.grid_mass_region_msun
        ));
        starts.push(run);
    }
    let bad_start = starts.iter().find(|r| r.label == "bad").cloned();

    // The data's best fit: the same objective minimised much further, from both starts.
    let mut best_runs = Vec::new();
    for (label, mass, c0) in [starts_spec[1], starts_spec[3]] {
        let mut rc = config.reconstruct_config(field, config.best_fit_iterations);
        rc.solver.method = SolverMethod::AcceleratedGradient;
        rc.solver.start_cell_mass_msun = mass;
        rc.solver.start_c = c0;
        let rec = run_one(
            simulation,
            LayerSource::Given(std::slice::from_ref(layer_true)),
            &rc,
            "best fit",
        )?;
        let r = scorer.score(&rec, "best fit")?.report;
        let run = start_run(
            &format!("best fit from the {label} start"),
            mass,
            c0,
            &rec,
            &r,
        );
        say(&format!(
            "best fit, {label} start ({} iterations): C {:.3}, chi2 {:.4e}, grid mass in the arc region {:.3e} Msun",
            config.best_fit_iterations, run.c, run.chi2, run.grid_mass_region_msun
        ));
        best_runs.push(run);
    }
    let system = &case_iii.reconstruction.system;
    let truth_lens = simulation
        .truth_model()
        .build_lens()
        .map_err(PaperError::Model)?;
    let truth_chi2 = lens_equation_chi2(&system.constraints, &system.distance_ratios, &truth_lens);
    let best_fit = BestFit {
        iterations: config.best_fit_iterations,
        truth_chi2,
        truth_source_rms_arcsec: (truth_chi2 / row_weight_sum(&case_iii.reconstruction)).sqrt(),
        runs: best_runs,
    };
    say(&format!(
        "best fit: the truth's own chi2 is {truth_chi2:.4e}"
    ));

    let defaults = config.reconstruct_config(field, config.iterations);
    // The galaxy-model layer with a prior on C of each width (made here: the rows borrow them).
    let held_layers: Vec<Layer> = C_PRIOR_SIGMAS
        .iter()
        .map(|&sigma| Layer {
            prior_sigma: Some(sigma),
            ..layer_model.clone()
        })
        .collect();
    let mut sweep = Vec::new();
    // `rc = None`: the default case (ii) run, already scored.
    let mut row = |parameter: &str, value: String, is_default: bool, rc: Option<_>, layers| {
        let r = match rc {
            Some(rc) => {
                let rec = run_one(simulation, layers, &rc, "sweep")?;
                scorer.score(&rec, "sweep")?.report
            }
            None => case_ii.report.clone(),
        };
        say(&format!(
            "sweep, {parameter} = {value}: median deflection error {:.2}\", C {:?}",
            r.deflection_error_median_arcsec, r.c
        ));
        sweep.push(SweepRow {
            parameter: parameter.to_string(),
            value,
            is_default,
            best: false,
            c: r.c,
            deflection_error_median_arcsec: r.deflection_error_median_arcsec,
            deflection_error_p90_arcsec: r.deflection_error_p90_arcsec,
            profile_max_rel_error: r.profile_max_rel_error,
            einstein_radius_arcsec_z3: r.einstein_radius_arcsec_z3,
        });
        Ok::<(), PaperError>(())
    };
    let model = LayerSource::Given(std::slice::from_ref(layer_model));
    for factor in CELL_SIGMA_FACTORS {
        let mut rc = defaults.clone();
        rc.grid.cell_sigma_factor = factor;
        let is_default = factor == defaults.grid.cell_sigma_factor;
        let rc = (!is_default).then_some(rc);
        row(
            "cell_sigma_factor",
            format!("{factor}"),
            is_default,
            rc,
            model,
        )?;
    }
    for w in [
        Weighting::EqualPerPixel,
        Weighting::EqualPerImage,
        Weighting::EqualPerSystem,
    ] {
        let mut rc = defaults.clone();
        rc.constraints.weighting = w;
        let name = serde_json::to_value(w)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| format!("{w:?}"));
        let is_default = w == defaults.constraints.weighting;
        let rc = (!is_default).then_some(rc);
        row("weighting", name, is_default, rc, model)?;
    }
    // The prior on C: the galaxy-model layer with a prior of each width ("none" is case ii).
    row("c_prior_sigma", "none".to_string(), true, None, model)?;
    for (sigma, held) in C_PRIOR_SIGMAS.iter().zip(&held_layers) {
        row(
            "c_prior_sigma",
            format!("{sigma}"),
            false,
            Some(defaults.clone()),
            LayerSource::Given(std::slice::from_ref(held)),
        )?;
    }
    // The member layer from members.cat (what a user of `wslap reconstruct --members` gets).
    let (catalog, _) = parse_member_catalog(
        &simulation.member_catalog_text(),
        "members.cat",
        Some(simulation.reference),
    )
    .map_err(|e| PaperError::Members(Box::new(e)))?;
    let default_members = MemberConfig::default();
    for (label, r_s, exponent) in R_S_LAWS {
        let mut rc = defaults.clone();
        rc.members.r_s_lstar_kpc = r_s;
        rc.members.size_exponent = exponent;
        let is_default =
            r_s == default_members.r_s_lstar_kpc && exponent == default_members.size_exponent;
        row(
            "member_r_s_law",
            label.to_string(),
            is_default,
            Some(rc),
            LayerSource::Members(&catalog),
        )?;
    }
    mark_best(&mut sweep);
    Ok(Studies {
        starts,
        bad_start,
        best_fit: Some(best_fit),
        sweep,
    })
}

/// Sum of the weights of a reconstruction's rows (two per pixel), 1/arcsec^2.
fn row_weight_sum(rec: &Reconstruction) -> f64 {
    rec.system
        .constraints
        .pixels
        .iter()
        .map(|p| 2.0 * p.weight)
        .sum()
}

/// A run of case (iii)'s data from a start (`mass`, `c0`), with its scores `r`.
fn start_run(label: &str, mass: f64, c0: f64, rec: &Reconstruction, r: &CaseReport) -> StartRun {
    // In f64: QADP's own report of the objective comes from its single-precision pass, and
    // chi2 is a small difference of large terms (the frame shift's constant).
    let objective = crate::solver::objective(&rec.system.a, &rec.system.b, &rec.x);
    let chi2 = 2.0 * objective + rec.system.theta_w_theta;
    StartRun {
        label: label.to_string(),
        start_cell_mass_msun: mass,
        start_c: c0,
        c: r.c.first().copied().unwrap_or(f64::NAN),
        objective,
        chi2,
        source_rms_arcsec: (chi2.max(0.0) / row_weight_sum(rec)).sqrt(),
        image_plane_rms_arcsec: rec.image_plane_rms_arcsec(false),
        grid_mass_msun: r.grid_mass_msun,
        grid_mass_region_msun: r.grid_mass_region_msun,
        deflection_error_median_arcsec: r.deflection_error_median_arcsec,
    }
}

/// Marks the row with the lowest median deflection error of each parameter.
fn mark_best(rows: &mut [SweepRow]) {
    let params: Vec<String> = rows.iter().map(|r| r.parameter.clone()).collect();
    for p in params {
        let best = rows
            .iter()
            .enumerate()
            .filter(|(_, r)| r.parameter == p)
            .min_by(|a, b| {
                a.1.deflection_error_median_arcsec
                    .total_cmp(&b.1.deflection_error_median_arcsec)
            })
            .map(|(k, _)| k);
        if let Some(k) = best {
            rows[k].best = true;
        }
    }
}
