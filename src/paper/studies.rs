//! The runs behind the caveats and choices of `report.md`, each at the case iteration count:
//!
//! - **Starts**: case (iii) from several starts (C0 = 0.001, the reasonable start, C0 = 1, the
//!   reasonable C0 with 10x the cell mass and with the true soft mass spread over the cells, and
//!   the bad start), each with its final C, lens-equation chi2 and grid mass in the arc region:
//!   how much the answer depends on the start, and whether a lower chi2 means a truer mass.
//! - **Best fit**: the minimiser of the same objective, approached with the accelerated
//!   projected gradient from the reasonable and the bad start, next to the chi2 of the
//!   simulated lens itself on the same rows: whether the data's best fit is the truth.
//! - **Sweep**: the defaults [`crate::method`] leaves open — the cell width (Gaussian sigma over the
//!   cell size), the row weights, and the member scale-radius law of a layer built from the
//!   member catalogue — and the optional prior on C (`members.c_prior_sigma`, off by default),
//!   scored by case (ii)'s median deflection error in the arc region (the realistic case:
//!   galaxy positions known, masses not).

use super::metrics::lens_equation_chi2;
use super::report::{BestFit, CaseReport, StartRun, Studies, SweepRow};
use super::{run_plan, CaseRun, Job, PaperConfig, PaperError, Scorer};
use crate::catalog::{parse_member_catalog, MemberCatalog};
use crate::inversion::{Layer, MemberConfig, Weighting};
use crate::reconstruct::{LayerSource, ReconstructConfig, Reconstruction, SolverMethod};
use crate::simulate::Simulation;

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

/// Runs the start study, the best fit and the sweep.
///
/// In the three phases of [`super::run_paper`]: plan the rows ([`plan_studies`]), run the new
/// ones side by side and score each ([`run_plan`]), then sort them into the tables with a line
/// each ([`collect_studies`]); last, the truth's own chi2 for the best fit ([`best_fit`]).
pub(super) fn run_studies(
    config: &PaperConfig,
    simulation: &Simulation,
    scorer: &Scorer<'_>,
    inputs: &StudyInputs<'_>,
    say: &mut dyn FnMut(&str),
) -> Result<Studies, PaperError> {
    // The galaxy-model layer with a prior on C of each width (made here: the jobs borrow them).
    let held_layers: Vec<Layer> = C_PRIOR_SIGMAS
        .iter()
        .map(|&sigma| Layer {
            prior_sigma: Some(sigma),
            ..inputs.layer_model.clone()
        })
        .collect();
    // The member layer from members.cat (what a user of `wslap reconstruct --members` gets).
    let (catalog, _) = parse_member_catalog(
        &simulation.member_catalog_text(),
        "members.cat",
        Some(simulation.reference),
    )
    .map_err(|e| PaperError::Members(Box::new(e)))?;
    let plan = plan_studies(config, simulation, inputs, &held_layers, &catalog);
    // Each new run keeps its scores and its f64 chi2.
    let done = run_plan(simulation, plan, |row, rec| {
        let report = scorer.score(&rec, row.job_name())?.report;
        Ok(Scores::of(&rec, report))
    })?;
    let (starts, best_runs, mut sweep) = collect_studies(config, inputs, done, say);
    let bad_start = starts.iter().find(|r| r.label == "bad").cloned();
    let best_fit = best_fit(config, simulation, inputs.case_iii, best_runs, say)?;
    mark_best(&mut sweep);
    Ok(Studies {
        starts,
        bad_start,
        best_fit: Some(best_fit),
        sweep,
    })
}

/// The starts of the start study, `(label, cell mass in Msun, C0)`; the best fit starts from
/// the "reasonable" and the "bad" one.
fn start_specs(config: &PaperConfig, simulation: &Simulation) -> [(&'static str, f64, f64); 6] {
    let soft_per_cell = simulation.soft_mass_msun / (config.grid_cells * config.grid_cells) as f64;
    let reasonable_mass = config.reasonable_start_cell_mass_msun;
    [
        ("C0 = 0.001", reasonable_mass, 0.001),
        ("reasonable", reasonable_mass, config.reasonable_start_c),
        ("C0 = 1", reasonable_mass, 1.0),
        // Higher cell starts with the reasonable C0: 10x the reasonable cells, and the true soft
        // mass spread evenly over the cells.
        (
            "cells x10",
            10.0 * reasonable_mass,
            config.reasonable_start_c,
        ),
        (
            "cells = soft mass",
            soft_per_cell,
            config.reasonable_start_c,
        ),
        (
            "bad",
            config.bad_start_cell_factor * soft_per_cell,
            config.bad_start_c,
        ),
    ]
}

/// Every row of the studies, in report order, with the job that computes it; the runs they
/// share with the cases (the reasonable start is case iii, the default row of each sweep group
/// case ii) have none and are reused.
fn plan_studies<'a>(
    config: &PaperConfig,
    simulation: &Simulation,
    inputs: &StudyInputs<'a>,
    held_layers: &'a [Layer],
    catalog: &'a MemberCatalog,
) -> Vec<(Row, Option<Job<'a>>)> {
    let field = simulation.config.field_arcsec;
    let starts_spec = start_specs(config, simulation);
    let defaults = config.reconstruct_config(field, config.iterations);
    let truth_layer = LayerSource::Given(std::slice::from_ref(inputs.layer_true));
    let mut plan: Vec<(Row, Option<Job>)> = Vec::new();
    for (label, mass, c0) in starts_spec {
        let row = Row::Start { label, mass, c0 };
        if label == "reasonable" {
            plan.push((row, None));
            continue;
        }
        let mut rc = defaults.clone();
        rc.solver.start_cell_mass_msun = mass;
        rc.solver.start_c = c0;
        plan.push((row, Some(job(truth_layer, rc, "start study"))));
    }
    let best_fit_starts = starts_spec
        .into_iter()
        .filter(|(label, ..)| matches!(*label, "reasonable" | "bad"));
    for (label, mass, c0) in best_fit_starts {
        let mut rc = config.reconstruct_config(field, config.best_fit_iterations);
        rc.solver.method = SolverMethod::AcceleratedGradient;
        rc.solver.start_cell_mass_msun = mass;
        rc.solver.start_c = c0;
        let row = Row::BestFit { label, mass, c0 };
        plan.push((row, Some(job(truth_layer, rc, "best fit"))));
    }
    plan_sweep(
        &mut plan,
        &defaults,
        inputs.layer_model,
        held_layers,
        catalog,
    );
    plan
}

/// The rows of the sweep of defaults, each on case (ii)'s data: the cell width, the row
/// weights, the prior on C and the member scale-radius law.
fn plan_sweep<'a>(
    plan: &mut Vec<(Row, Option<Job<'a>>)>,
    defaults: &ReconstructConfig,
    layer_model: &'a Layer,
    held_layers: &'a [Layer],
    catalog: &'a MemberCatalog,
) {
    let model = LayerSource::Given(std::slice::from_ref(layer_model));
    let sweep_row = |parameter, value: String, is_default| Row::Sweep {
        parameter,
        value,
        is_default,
    };
    for factor in CELL_SIGMA_FACTORS {
        let mut rc = defaults.clone();
        rc.grid.cell_sigma_factor = factor;
        let is_default = factor == defaults.grid.cell_sigma_factor;
        let row = sweep_row("cell_sigma_factor", format!("{factor}"), is_default);
        plan.push((row, (!is_default).then(|| job(model, rc, "sweep"))));
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
        let row = sweep_row("weighting", name, is_default);
        plan.push((row, (!is_default).then(|| job(model, rc, "sweep"))));
    }
    // The prior on C: the galaxy-model layer with a prior of each width ("none" is case ii).
    plan.push((sweep_row("c_prior_sigma", "none".to_string(), true), None));
    for (sigma, held) in C_PRIOR_SIGMAS.iter().zip(held_layers) {
        let layers = LayerSource::Given(std::slice::from_ref(held));
        let row = sweep_row("c_prior_sigma", format!("{sigma}"), false);
        plan.push((row, Some(job(layers, defaults.clone(), "sweep"))));
    }
    let default_members = MemberConfig::default();
    for (label, r_s, exponent) in R_S_LAWS {
        let mut rc = defaults.clone();
        rc.members.r_s_lstar_kpc = r_s;
        rc.members.size_exponent = exponent;
        let is_default =
            r_s == default_members.r_s_lstar_kpc && exponent == default_members.size_exponent;
        let row = sweep_row("member_r_s_law", label.to_string(), is_default);
        plan.push((row, Some(job(LayerSource::Members(catalog), rc, "sweep"))));
    }
}

/// The start study, the best-fit runs and the sweep from the rows in plan order (a row without
/// a run of its own takes case iii's or case ii's), with one line each to `say`.
#[allow(clippy::type_complexity)]
fn collect_studies(
    config: &PaperConfig,
    inputs: &StudyInputs<'_>,
    done: Vec<(Row, Option<Scores>)>,
    say: &mut dyn FnMut(&str),
) -> (Vec<StartRun>, Vec<StartRun>, Vec<SweepRow>) {
    let (case_ii, case_iii) = (inputs.case_ii, inputs.case_iii);
    let mut starts = Vec::new();
    let mut best_runs = Vec::new();
    let mut sweep = Vec::new();
    for (row, scores) in done {
        let scores = match scores {
            Some(scores) => scores,
            None if matches!(row, Row::Start { .. }) => {
                Scores::of(&case_iii.reconstruction, case_iii.report.clone())
            }
            None => Scores::of(&case_ii.reconstruction, case_ii.report.clone()),
        };
        match row {
            Row::Start { label, mass, c0 } => {
                let run = scores.start_run(label.to_string(), mass, c0);
                say(&format!(
                    "start study, {label}: C {:.3}, chi2 {:.4e} (source-plane rms {:.3}\"), grid mass in the arc region {:.3e} Msun",
                    run.c, run.chi2, run.source_rms_arcsec, run.grid_mass_region_msun
                ));
                starts.push(run);
            }
            Row::BestFit { label, mass, c0 } => {
                let run = scores.start_run(format!("best fit from the {label} start"), mass, c0);
                say(&format!(
                    "best fit, {label} start ({} iterations): C {:.3}, chi2 {:.4e}, grid mass in the arc region {:.3e} Msun",
                    config.best_fit_iterations, run.c, run.chi2, run.grid_mass_region_msun
                ));
                best_runs.push(run);
            }
            Row::Sweep {
                parameter,
                value,
                is_default,
            } => {
                let r = &scores.report;
                say(&format!(
                    "sweep, {parameter} = {value}: median deflection error {:.2}\", C {:?}",
                    r.deflection_error_median_arcsec, r.c
                ));
                sweep.push(SweepRow {
                    parameter: parameter.to_string(),
                    value,
                    is_default,
                    best: false,
                    c: r.c.clone(),
                    deflection_error_median_arcsec: r.deflection_error_median_arcsec,
                    deflection_error_p90_arcsec: r.deflection_error_p90_arcsec,
                    profile_max_rel_error: r.profile_max_rel_error,
                    einstein_radius_arcsec_z3: r.einstein_radius_arcsec_z3,
                });
            }
        }
    }
    (starts, best_runs, sweep)
}

/// The data's best fit (`runs`) against the simulated lens itself, on case (iii)'s rows.
fn best_fit(
    config: &PaperConfig,
    simulation: &Simulation,
    case_iii: &CaseRun,
    runs: Vec<StartRun>,
    say: &mut dyn FnMut(&str),
) -> Result<BestFit, PaperError> {
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
        runs,
    };
    say(&format!(
        "best fit: the truth's own chi2 is {truth_chi2:.4e}"
    ));
    Ok(best_fit)
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

/// One row of the studies: which table it belongs to and what it varies.
enum Row {
    /// Case (iii) from a start (cell mass, C0) at the case iteration count.
    Start {
        label: &'static str,
        mass: f64,
        c0: f64,
    },
    /// Case (iii)'s objective minimised from a start.
    BestFit {
        label: &'static str,
        mass: f64,
        c0: f64,
    },
    /// A value of one open default (case ii's data).
    Sweep {
        parameter: &'static str,
        value: String,
        is_default: bool,
    },
}

impl Row {
    fn job_name(&self) -> &'static str {
        match self {
            Row::Start { .. } => "start study",
            Row::BestFit { .. } => "best fit",
            Row::Sweep { .. } => "sweep",
        }
    }
}

fn job<'a>(layers: LayerSource<'a>, config: ReconstructConfig, name: &'static str) -> Job<'a> {
    Job {
        layers,
        config,
        name,
    }
}

/// What the studies keep of a run: its scores and its lens-equation fit.
struct Scores {
    report: CaseReport,
    /// Final objective `phi` in f64. In f64 because QADP's own report of the objective comes
    /// from its single-precision pass, and chi2 is a small difference of large terms (the frame
    /// shift's constant).
    objective: f64,
    chi2: f64,
    row_weight_sum: f64,
    image_plane_rms_arcsec: Option<f64>,
}

impl Scores {
    fn of(rec: &Reconstruction, report: CaseReport) -> Self {
        let objective = crate::solver::objective(&rec.system.a, &rec.system.b, &rec.x);
        Self {
            report,
            objective,
            chi2: 2.0 * objective + rec.system.theta_w_theta,
            row_weight_sum: row_weight_sum(rec),
            image_plane_rms_arcsec: rec.image_plane_rms_arcsec(false),
        }
    }

    /// The run as a row of the start study (or of the best fit) from (`mass`, `c0`).
    fn start_run(&self, label: String, mass: f64, c0: f64) -> StartRun {
        let r = &self.report;
        StartRun {
            label,
            start_cell_mass_msun: mass,
            start_c: c0,
            c: r.c.first().copied().unwrap_or(f64::NAN),
            objective: self.objective,
            chi2: self.chi2,
            source_rms_arcsec: (self.chi2.max(0.0) / self.row_weight_sum).sqrt(),
            image_plane_rms_arcsec: self.image_plane_rms_arcsec,
            grid_mass_msun: r.grid_mass_msun,
            grid_mass_region_msun: r.grid_mass_region_msun,
            deflection_error_median_arcsec: r.deflection_error_median_arcsec,
        }
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
