//! `report.md` of `wslap paper`: the cases, the checks, the studies and the convergence study
//! as Markdown tables.

use std::fmt::Write as _;

use super::report::{PaperReport, RunSeries, TruthReport};
use super::studies::Studies;

/// `report.md`: what was run, the numbers, the checks.
pub fn markdown(report: &PaperReport) -> String {
    let mut s = String::new();
    let t = &report.truth;
    let _ = writeln!(s, "# WSLAP+ paper test: the simulated A1689-like cluster\n");
    let _ = writeln!(
        s,
        "Truth: soft (dark) mass {:.3e} Msun, galaxies {:.3e} Msun inside the field ({:.3e} and {:.3e} inside the arc region r < {:.1}\", where errors and the grid mass are measured); Einstein radius at z_s = 3: {:.1}\"; {} systems, {} arc pixels.\n",
        t.soft_mass_msun, t.galaxy_mass_msun, t.soft_mass_region_msun, t.galaxy_mass_region_msun, t.arc_region_radius_arcsec, t.einstein_radius_arcsec_z3, t.n_systems, t.n_arc_pixels
    );
    let _ = writeln!(s, "## The three cases\n");
    let _ = writeln!(
        s,
        "| case | grid mass (Msun) | in arc region (Msun) | C | defl. err. median (\") | p90 (\") | max profile rel. err. | theta_E z=3 (\") | curve distance (\") | beta error (\"^2) | radial curve |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
    for key in ["no_galaxies", "galaxy_model", "galaxy_true"] {
        if let Some(c) = report.cases.get(key) {
            let _ = writeln!(
                s,
                "| {key} | {:.3e} | {:.3e} | {} | {:.2} | {:.2} | {:.3} | {:.1} | {} | {:.1} | {} |",
                c.grid_mass_msun,
                c.grid_mass_region_msun,
                c_list(&c.c),
                c.deflection_error_median_arcsec,
                c.deflection_error_p90_arcsec,
                c.profile_max_rel_error,
                c.einstein_radius_arcsec_z3,
                c.critical_curve_distance_arcsec
                    .map_or("none".to_string(), |d| format!("{d:.2}")),
                c.beta_error,
                c.radial_curve_found
            );
        }
    }
    let _ = writeln!(s, "\n## The paper's findings, measured\n");
    for c in &report.checks {
        let mark = if c.passed { "yes" } else { "NO" };
        let _ = writeln!(s, "- [{mark}] {}: {}", c.name, c.detail);
    }
    studies_markdown(&mut s, &report.studies, t);
    let conv = &report.convergence;
    let _ = writeln!(s, "\n## Convergence study\n");
    let _ = writeln!(s, "| iteration | grid mass reasonable | C reasonable | grid mass bad start | C bad start | grid mass no galaxies | beta error reasonable | beta error no galaxies |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let marks = [100, 300, 1000, 3000, 8000, 20000, 50000];
    for m in marks {
        if conv.iterations.last().is_some_and(|&last| m > last) {
            continue;
        }
        let at = |v: &[f64]| {
            RunSeries::at(v, &conv.iterations, m).map_or("-".to_string(), |x| format!("{x:.3e}"))
        };
        let at_c = |v: &[f64]| {
            RunSeries::at(v, &conv.iterations, m).map_or("-".to_string(), |x| format!("{x:.3}"))
        };
        let _ = writeln!(
            s,
            "| {m} | {} | {} | {} | {} | {} | {} | {} |",
            at(&conv.reasonable.grid_mass_msun),
            at_c(&conv.reasonable.c),
            at(&conv.bad_start.grid_mass_msun),
            at_c(&conv.bad_start.c),
            at(&conv.no_galaxies.grid_mass_msun),
            at(&conv.reasonable.beta_error),
            at(&conv.no_galaxies.beta_error),
        );
    }
    let _ = writeln!(s, "\n## Settings\n");
    for (k, v) in &report.settings {
        let _ = writeln!(s, "- {k}: {v}");
    }
    let _ = writeln!(s, "\n## Timings (ms)\n");
    for (k, v) in &report.timings_ms {
        let _ = writeln!(s, "- {k}: {v:.0}");
    }
    s
}

/// The start study and the sweep of defaults, as tables.
fn studies_markdown(s: &mut String, studies: &Studies, t: &TruthReport) {
    if !studies.starts.is_empty() {
        let _ = writeln!(s, "\n## Case (iii) from several starts\n");
        let _ = writeln!(
            s,
            "Same data, same layer (galaxy-true), same iterations; only the start differs. chi2 is the weighted squared residual of the lens equation (what QADP lowers). If the data pinned C down, every start would end near the same C; a lower chi2 with a worse mass is the drift towards the over-massive \"point-source solution\" that the iteration count stops.\n"
        );
        let _ = writeln!(s, "| start | cell mass (Msun) | C0 | final C | chi2 | source-plane rms (\") | image-plane rms (\") | grid mass in arc region (vs soft {:.3e}) | defl. err. median (\") |", t.soft_mass_region_msun);
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
        for r in &studies.starts {
            let _ = writeln!(
                s,
                "| {} | {:.2e} | {} | {:.3} | {:.4e} | {:.3} | {} | {:.3e} ({:+.1}%) | {:.2} |",
                r.label,
                r.start_cell_mass_msun,
                r.start_c,
                r.c,
                r.chi2,
                r.source_rms_arcsec,
                r.image_plane_rms_arcsec
                    .map_or("-".to_string(), |v| format!("{v:.2}")),
                r.grid_mass_region_msun,
                100.0 * (r.grid_mass_region_msun / t.soft_mass_region_msun - 1.0),
                r.deflection_error_median_arcsec
            );
        }
    }
    if !studies.sweep.is_empty() {
        let _ = writeln!(s, "\n## The open defaults, measured (case ii)\n");
        let _ = writeln!(
            s,
            "Each row changes one setting of case (ii) (galaxy-model layer; the member rows build the layer from members.cat instead; the c_prior_sigma rows add a prior on C around 1 of that width, which `wslap reconstruct` leaves off). \"best\" = lowest median deflection error of its group; \"default\" = this run's setting (cell width and weighting of `wslap paper`; the member law of `wslap reconstruct`).\n"
        );
        let _ = writeln!(s, "| setting | value | default | best | C | defl. err. median (\") | p90 (\") | max profile rel. err. | theta_E z=3 (\") |");
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
        for r in &studies.sweep {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {:.2} | {:.2} | {:.3} | {:.1} |",
                r.parameter,
                r.value,
                if r.is_default { "yes" } else { "" },
                if r.best { "yes" } else { "" },
                c_list(&r.c),
                r.deflection_error_median_arcsec,
                r.deflection_error_p90_arcsec,
                r.profile_max_rel_error,
                r.einstein_radius_arcsec_z3
            );
        }
    }
}

/// Factors C, `"1.234, 0.567"` (also in the checks of `report.rs`).
pub(super) fn c_list(c: &[f64]) -> String {
    let each: Vec<String> = c.iter().map(|v| format!("{v:.3}")).collect();
    each.join(", ")
}
