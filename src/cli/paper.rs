//! `wslap paper`: the paper's test on the simulated A1689-like cluster (Sendra et al., sections
//! 4 and 5): the three cases, the convergence study, report.json, report.md and the figures.

use std::fs;
use std::path::{Path, PathBuf};

use clap::Args;
use wslap::paper::{render_figures, report_markdown, run_paper, Case, CaseSettings, PaperConfig};
use wslap::{write_simulation, InputKind};

use super::input::read_text;
use super::reconstruct::write_reconstruction;

/// Reproduces the WSLAP+ paper's test: simulates the cluster and its arcs (as `wslap simulate`),
/// reconstructs it on a 32 x 32 grid with QADP without galaxies, with the perturbed
/// "galaxy-model" layer and with the "galaxy-true" layer, runs the convergence study (reasonable
/// start, bad start, no galaxies), and writes into DIR: the simulation (truth/, arcs.json,
/// images.cat, members.cat, arcs.png), one folder of `wslap reconstruct` files per case,
/// report.json, report.md and the figures (maps.png, profiles.png, soft-component.png,
/// convergence.png, deflection-error.png).
#[derive(Debug, Args)]
pub struct PaperArgs {
    /// Output folder (created if missing).
    #[arg(long, value_name = "DIR", default_value = "paper")]
    out: PathBuf,
    /// QADP iterations of the three cases.
    #[arg(long, default_value_t = 8000)]
    iterations: usize,
    /// QADP iterations of the convergence study.
    #[arg(long, default_value_t = 50_000)]
    long: usize,
    /// Seed of the simulation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Map pixels per side of the products.
    #[arg(long, default_value_t = 256)]
    pixels: usize,
    /// Start mass of every cell in the cases and the reasonable start, Msun.
    #[arg(long)]
    start_cell_mass: Option<f64>,
    /// Start value of C in the cases and the reasonable start.
    #[arg(long)]
    start_c: Option<f64>,
    /// Gaussian width of a cell over its size (default 1.25: the best of the sweep in
    /// report.md on this cluster; the general default of `wslap reconstruct` is 0.75).
    #[arg(long)]
    cell_sigma: Option<f64>,
    /// Row weighting: equal_per_image, equal_per_pixel or equal_per_system.
    #[arg(long)]
    weighting: Option<String>,
    /// Skip the studies of report.md (C from several starts, the data's best fit, the sweep of
    /// the open defaults): about half the run time.
    #[arg(long)]
    no_studies: bool,
    /// Solve the cases with `wslap reconstruct`'s default objective (image-plane residuals, the
    /// regulariser chosen by cross-validation, the exact minimiser) instead of the paper's QADP.
    #[arg(long)]
    default_objective: bool,
    /// The cases to run, comma-separated: i (no galaxies), ii (galaxy-model), iii
    /// (galaxy-true). The studies need ii and iii.
    #[arg(long, value_delimiter = ',', default_value = "i,ii,iii")]
    cases: Vec<String>,
    /// Skip the convergence study (three runs of --long iterations).
    #[arg(long)]
    no_convergence: bool,
    /// Settings (JSON, as `wslap reconstruct --config` reads) laid over each case's: e.g.
    /// `{"objective": {"strength": 0.1}}` with --default-objective to try one strength.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
}

pub fn run(args: &PaperArgs) -> Result<(), String> {
    super::input::check_out_dir(&args.out)?;
    let mut config = PaperConfig {
        iterations: args.iterations,
        long_iterations: args.long,
        map_pixels: args.pixels,
        ..PaperConfig::default()
    };
    config.simulation.seed = args.seed;
    config.studies = !args.no_studies;
    config.default_objective = args.default_objective;
    config.convergence = !args.no_convergence;
    if let Some(path) = &args.config {
        let name = path.display().to_string();
        let text = read_text(path, InputKind::Config)?;
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| format!("{name}: not JSON: {e}"))?;
        if !value.is_object() {
            return Err(format!(
                "{name}: settings are a JSON object, e.g. {{\"objective\": {{\"strength\": 0.1}}}}"
            ));
        }
        config.case_settings = Some(CaseSettings {
            source_name: name,
            value,
        });
    }
    config.cases = args
        .cases
        .iter()
        .map(|name| {
            Case::parse(name.trim()).ok_or_else(|| {
                format!("--cases: \"{name}\" is not a case: give i, ii or iii, comma-separated")
            })
        })
        .collect::<Result<_, _>>()?;
    if let Some(m) = args.start_cell_mass {
        config.reasonable_start_cell_mass_msun = m;
    }
    if let Some(c) = args.start_c {
        config.reasonable_start_c = c;
    }
    if let Some(s) = args.cell_sigma {
        config.cell_sigma_factor = s;
    }
    if let Some(w) = &args.weighting {
        config.weighting = serde_json::from_value(serde_json::Value::String(w.clone()))
            .map_err(|e| format!("--weighting {w}: {e}"))?;
    }
    let run = run_paper(&config, &mut |line| println!("{line}")).map_err(|e| e.to_string())?;
    let dir = &args.out;
    fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    write_simulation(&run.simulation, dir).map_err(|e| e.to_string())?;
    for case in &run.cases {
        write_reconstruction(&case.reconstruction, &dir.join(case.case.dir()))?;
    }
    let write = |name: &str, bytes: &[u8]| -> Result<(), String> {
        let path = dir.join(name);
        fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    let json = serde_json::to_string_pretty(&run.report).map_err(|e| e.to_string())?;
    write("report.json", json.as_bytes())?;
    write("report.md", report_markdown(&run.report).as_bytes())?;
    for figure in render_figures(&run).map_err(|e| e.to_string())? {
        write(figure.file_name, &figure.png)?;
    }
    print_checks(&run.report, dir);
    Ok(())
}

fn print_checks(report: &wslap::paper::PaperReport, dir: &Path) {
    for c in &report.checks {
        println!(
            "[{}] {}: {}",
            if c.passed { "ok" } else { "NO" },
            c.name,
            c.detail
        );
    }
    println!(
        "wrote {} (report.md, report.json, figures) in {:.1} s",
        dir.display(),
        report.timings_ms.get("total").copied().unwrap_or(0.0) / 1e3
    );
}
