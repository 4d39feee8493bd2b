//! The run kinds (reconstruct, forward, look-up), the solver setting, z_s redraws without
//! solving, hold-outs, cross-validation, the refined grid and the "auto" strength; the
//! result's files (summary.json, sources.json, FITS).

use crate::common;
use crate::fixtures::{solved, teaching_session};
use serde_json::json;
use wslap::app::examples::TEACHING_SOURCES;
use wslap::Control;
use wslap::TEACHING_MODEL_JSON;
use wslap::{app::DataRole, app::RunKind, app::Session, app::ViewOptions};

const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The "Solver" setting reaches the run: the accelerated gradient lowers the lens-equation
/// chi2 below QADP's in the same iterations, and summary.json names the method.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_solver_setting_chooses_the_method() {
    let chi2 = |s: &Session| {
        let r = s.result().unwrap().reconstruction().unwrap();
        2.0 * wslap::quadratic_objective(&r.system.a, &r.system.b, &r.x) + r.system.theta_w_theta
    };
    // The same objective, minimised by QADP and by the accelerated gradient in 400 iterations.
    let mut qadp = teaching_session();
    qadp.set_field("reconstruct.solver.method", json!("qadp"))
        .unwrap();
    qadp.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let mut s = teaching_session();
    assert!(s
        .set_field("reconstruct.solver.method", json!("newton"))
        .is_err());
    s.set_field("reconstruct.solver.method", json!("accelerated_gradient"))
        .unwrap();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    assert!(chi2(&s) < chi2(&qadp), "{} vs {}", chi2(&s), chi2(&qadp));
    let summary: serde_json::Value =
        serde_json::from_str(&s.result().unwrap().summary_json().unwrap()).unwrap();
    assert_eq!(
        summary["settings"]["solver"]["method"], "accelerated_gradient",
        "{summary}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn reconstruction_gives_curves_views_hover_and_the_cli_files() {
    let mut reports = 0;
    let mut s = teaching_session();
    s.run(RunKind::Reconstruct, &mut |_| {
        reports += 1;
        Control::Continue
    })
    .unwrap();
    assert!(reports >= 4, "{reports} progress reports");
    let r = s.result().unwrap();
    assert!(
        !r.products().curves.tangential.is_empty(),
        "no tangential curve"
    );
    let summary: serde_json::Value = serde_json::from_str(&r.summary_json().unwrap()).unwrap();
    for key in [
        "settings",
        "c_per_layer",
        "grid_mass_msun",
        "einstein_radius_arcsec",
        "maps",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    let sources: serde_json::Value = serde_json::from_str(&r.sources_json().unwrap()).unwrap();
    assert_eq!(sources.as_array().unwrap().len(), TEACHING_SOURCES.len());
    // The summary's median image offset is the median of sources.json's offsets.
    let mut offsets: Vec<f64> = sources
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["observed"].as_array().unwrap().iter())
        .filter_map(|o| o["offset_arcsec"].as_f64())
        .collect();
    offsets.sort_by(f64::total_cmp);
    let n = offsets.len();
    assert!(n >= 6, "{n} offsets");
    let median = summary["image_offset_median_arcsec"].as_f64().unwrap();
    // Equal but for the last bit that reading the decimal JSON back may change.
    let recomputed = 0.5 * (offsets[(n - 1) / 2] + offsets[n / 2]);
    assert!(
        (median - recomputed).abs() <= 4.0 * f64::EPSILON * median,
        "{median} vs {recomputed}"
    );
    assert!(median <= summary["image_plane_rms_arcsec"].as_f64().unwrap());
    let opts = ViewOptions::default();
    for view in [
        s.kappa_view(&opts).unwrap(),
        s.source_view(&opts).unwrap(),
        s.data_view(&opts).unwrap(),
    ] {
        assert!(
            view.png.starts_with(PNG_MAGIC) && view.png.len() > 2000,
            "{}",
            view.name
        );
    }
    // The map's centre pixel of the kappa figure: kappa of a cluster core is large.
    let frame = s.kappa_frame(&opts).unwrap();
    let (cx, cy) = (
        frame.map_left + frame.map_side / 2.0,
        frame.map_top + frame.map_side / 2.0,
    );
    let inside = s.hover(&opts, cx, cy).unwrap().expect("inside the map");
    assert!(inside.kappa.is_finite() && inside.magnification.is_finite());
    assert!(s.hover(&opts, 1.0, 1.0).unwrap().is_none());
    let fits = r.products().fits_files().unwrap();
    assert_eq!(fits.len(), 7);
    let header = String::from_utf8_lossy(&fits[0].1[..2880]).to_string();
    assert!(
        header.contains("NAXIS1  =                   64"),
        "{header}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_higher_source_redshift_redraws_a_larger_einstein_radius_without_solving() {
    let mut s = solved();
    let x = s.result().unwrap().reconstruction().unwrap().x.clone();
    let r2 = s.result().unwrap().products().curves.einstein_radius_arcsec;
    s.set_z_source(6.0).unwrap();
    let p = &s.result().unwrap().products();
    let r6 = p.curves.einstein_radius_arcsec;
    // The redraw has only the stored maps: the radius is measured on them, or is a lower bound.
    assert_eq!(
        p.einstein_radius_map_arcsec,
        (!p.curves.tangential_leaves_map).then_some(p.maps.geometry().size_arcsec)
    );
    assert!(
        r6 > r2 && r2 > 0.0,
        "Einstein radius {r2} at z_s = 2, {r6} at z_s = 6"
    );
    assert_eq!(s.result().unwrap().reconstruction().unwrap().x, x);
    assert!(
        s.set_z_source(0.1).is_err(),
        "a source in front of the lens"
    );
    assert_eq!(s.settings.reconstruct.products.z_source, 6.0);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn forward_and_lookup_modes_agree_on_the_einstein_radius() {
    /// Deflection maps differentiated by central differences vs the analytic Hessian: the
    /// Einstein radius agrees to a fraction of the 1-arcsec pixel.
    const RADIUS_ATOL_ARCSEC: f64 = 0.5;
    let mut s = Session::new();
    s.load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    s.set_field("z_lens", json!(0.3)).unwrap();
    s.set_field("reconstruct.products.size_arcsec", json!(64.0))
        .unwrap();
    s.set_field("reconstruct.products.pixels", json!(64))
        .unwrap();
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    let forward = s.result().unwrap().products().curves.einstein_radius_arcsec;
    let fits = s.result().unwrap().products().fits_files().unwrap();
    let file = |name: &str| fits.iter().find(|(n, _)| *n == name).unwrap().1.clone();
    s.load_fits(0, "x.fits", &file("x-arcsec-deflect.fits"))
        .unwrap();
    s.load_fits(1, "y.fits", &file("y-arcsec-deflect.fits"))
        .unwrap();
    assert!(s.load_fits(1, "bad.fits", b"SIMPLE = nonsense").is_err());
    s.run(RunKind::Lookup, &mut |_| Control::Continue).unwrap();
    let lookup = s.result().unwrap().products().curves.einstein_radius_arcsec;
    common::assert_abs("Einstein radius", lookup, forward, RADIUS_ATOL_ARCSEC);
}

/// Systems held out in the settings are left out of the fit and predicted, as with
/// `wslap reconstruct --holdout`: marked in sources.json, summarised apart in summary.json, and
/// a project of such a run reopens with the same linear system (its X fits). Bad lists are
/// refused and the old one kept.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn held_out_systems_are_predicted_and_survive_a_project() {
    let mut s = teaching_session();
    s.set_field("holdout", json!(["2"])).unwrap();
    for bad in [json!(["2", "2"]), json!([""]), json!([" 3"]), json!("2")] {
        assert!(s.set_field("holdout", bad.clone()).is_err(), "{bad}");
    }
    assert_eq!(s.settings.holdout, ["2"]);
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let r = s.result().unwrap();
    let sources: serde_json::Value = serde_json::from_str(&r.sources_json().unwrap()).unwrap();
    for src in sources.as_array().unwrap() {
        assert_eq!(src["held_out"], src["id"] == "2", "{}", src["id"]);
    }
    let summary: serde_json::Value = serde_json::from_str(&r.summary_json().unwrap()).unwrap();
    assert_eq!(summary["systems_fitted"], json!(["1", "3", "4"]));
    let held = summary["holdout_image_offset_median_arcsec"].as_f64();
    assert!(held.is_some_and(f64::is_finite), "{summary}");
    let text = s.project_json().unwrap();
    let mut t = Session::new();
    let report = t.open_project(&text, "p.json").unwrap();
    assert_eq!(report.result, "restored", "{}", report.message);
    assert_eq!(t.settings.holdout, ["2"]);
    let (a, b) = (r, t.result().unwrap());
    let (ka, kb) = (&a.products().maps.kappa.data, &b.products().maps.kappa.data);
    let worst = ka
        .iter()
        .zip(kb)
        .map(|(p, q)| (p - q).abs() / p.abs().max(1e-12))
        .fold(0.0, f64::max);
    assert!(worst <= 1e-9, "kappa differs by {worst:e} (relative)");
    // An id the data does not have stops the run with its name; the result stays.
    s.set_field("holdout", json!(["9"])).unwrap();
    let err = s
        .run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap_err()
        .to_string();
    assert!(err.contains("\"9\""), "{err}");
    assert!(s.result.is_some());
}

/// Cross-validation in the app: one fold per system when there are fewer than five fitted
/// systems (the hold-out setting's systems are not among them), each fold the same as a run
/// with that group held out, and the session's result untouched.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn cross_validation_predicts_each_system_and_keeps_the_result() {
    let mut s = teaching_session();
    assert_eq!(s.default_folds().unwrap(), 4);
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let before = s.result().unwrap().summary_json().unwrap();
    // Natively the folds run side by side, their reports interleaved.
    let mut folds_seen = std::collections::BTreeSet::new();
    let cv = s
        .cross_validate(2, &mut |fold, _| {
            folds_seen.insert(fold);
            Control::Continue
        })
        .unwrap();
    assert_eq!(folds_seen.into_iter().collect::<Vec<_>>(), [1, 2]);
    assert_eq!(s.result().unwrap().summary_json().unwrap(), before);
    assert_eq!(cv.systems.len(), 4);
    // The folds' convergence is on the result's maps (the same settings make the same maps),
    // and its files are the CLI's, the figure with the result's curves.
    let products = &s.result().unwrap().products();
    let kappa = cv.kappa.as_ref().expect("the folds' kappa maps");
    assert_eq!(kappa.spread.geometry, products.maps.geometry());
    let files = s.crossval_files(&cv).unwrap();
    let names: Vec<&str> = files.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "crossval-kappa-mean.fits",
            "crossval-kappa-spread.fits",
            "crossval-kappa-spread.png"
        ]
    );
    let (fits, png) = (&files[1].1, &files[2].1);
    let spread = wslap::read_image(fits, "spread").unwrap().to_map().unwrap();
    assert_eq!(spread.data.len(), kappa.spread.data.len());
    assert!(png.starts_with(b"\x89PNG"));
    for run in &cv.runs {
        let mut t = teaching_session();
        t.set_field("holdout", json!(run.held_out)).unwrap();
        t.run(RunKind::Reconstruct, &mut |_| Control::Continue)
            .unwrap();
        let r = t.result().unwrap();
        let alone: Vec<_> = r
            .reconstruction()
            .unwrap()
            .sources
            .iter()
            .filter(|x| x.held_out)
            .collect();
        let folded: Vec<_> = cv
            .systems
            .iter()
            .filter(|x| x.fold == run.fold)
            .map(|x| &x.report)
            .collect();
        assert_eq!(folded, alone, "fold {}", run.fold);
    }
    s.set_field("holdout", json!(["4"])).unwrap();
    assert_eq!(s.default_folds().unwrap(), 3);
    let err = Session::new().default_folds().unwrap_err().to_string();
    assert!(
        err.contains("load an image catalogue or an arcs file"),
        "{err}"
    );
}

/// The multi-resolution grid from the app's settings: one refinement splits a quarter of the
/// 256 cells in four (256 + 3 x 64 = 448 cells), and a project of such a
/// run asks for a new solve instead of restoring X on the wrong grid.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_refined_grid_runs_and_its_project_asks_for_a_new_solve() {
    let mut s = teaching_session();
    s.set_field("reconstruct.grid.refinements", json!(1))
        .unwrap();
    assert!(s
        .set_field("reconstruct.grid.refinements", json!(5))
        .is_err());
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let r = s.result().unwrap();
    let summary: serde_json::Value = serde_json::from_str(&r.summary_json().unwrap()).unwrap();
    assert_eq!(
        summary["grid_cells"],
        256 + 3 * 64,
        "{}",
        summary["grid_cells"]
    );
    let levels: Vec<usize> = r
        .reconstruction()
        .unwrap()
        .convergence
        .iter()
        .map(|c| c.level)
        .collect();
    // One series per solve: the refinement levels, then each update of the image-plane weights.
    let passes = 1 + s.settings.reconstruct.objective.image_plane_iterations;
    assert_eq!((levels[0], *levels.last().unwrap()), (0, passes));
    let mut t = Session::new();
    let report = t
        .open_project(&s.project_json().unwrap(), "p.json")
        .unwrap();
    assert_eq!(report.result, "solve_needed", "{}", report.message);
}

/// Cross-validation of an "auto" run: each fold makes the choice again on the systems it fits
/// and, as the whole run does, passes over a map crowded over those systems (the group it
/// predicts has no say). Natively only, as the test below.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn folds_pass_over_crowded_maps_as_the_whole_run_does() {
    let mut s = crate::fixtures::crowding_auto_session();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    // System 4's redshift was estimated: every fold fits it, and holds out one of the others.
    let cv = s.cross_validate(3, &mut |_, _| Control::Continue).unwrap();
    assert_eq!(cv.runs.len(), 3);
    let mut moved = 0;
    for run in &cv.runs {
        let chosen = run.chosen.expect("an auto choice");
        let crowding = run.crowding.expect("recorded");
        assert_eq!(crowding.systems, 4 - run.held_out.len(), "{run:?}");
        if run.crowded_maps.is_empty() {
            assert!(!crowding.distrusted(), "{run:?}");
        } else {
            moved += 1;
            assert!(
                run.crowded_maps
                    .iter()
                    .all(|p| p.crowding.distrusted() && p.candidate != chosen),
                "{run:?}"
            );
        }
    }
    eprintln!("folds that passed over a crowded map: {moved} of 3");
    assert!(moved > 0, "{:?}", cv.runs);
}

/// A run that estimates a redshift chooses its strength twice: from the systems with a
/// redshift, then again with the estimated one fitted in every fold. In pieces, as the app's
/// workers run it (the first round's trials, the reconstruction, the second round's trials
/// with its estimates, the choice made again), it gives what one "auto" run gives. Natively
/// only, as the test above.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn second_round_in_pieces_equals_one_auto_run() {
    let mut s = crate::fixtures::crowding_auto_session();
    let (candidates, folds) = s.strength_plan().unwrap().expect("auto has a plan");
    assert_eq!((candidates.len(), folds), (4, 3));
    let trials = |s: &Session, e: Option<&wslap::EstimatedRedshifts>| -> Vec<_> {
        candidates
            .iter()
            .map(|c| {
                s.strength_trial(c, folds, e, &mut |_| Control::Continue)
                    .unwrap()
            })
            .collect()
    };
    let first = trials(&s, None);
    s.run_with_trials(first, folds, &mut |_| Control::Continue)
        .unwrap();
    let round = s.second_strength_round().expect("a redshift was estimated");
    assert_eq!((&round.candidates, round.folds), (&candidates, folds));
    let ids: Vec<&str> = round
        .estimates
        .z_estimates
        .iter()
        .map(|(id, _)| id.as_str())
        .collect();
    assert_eq!(ids, ["4"]);
    assert_eq!(round.estimates.z_estimate_errors.len(), 1);
    let again = trials(&s, Some(&round.estimates));
    // The second round's folds fit system 4 and hold out only the others: its rows differ.
    assert_ne!(again, trials(&s, None));
    s.choose_again_with_trials(again, &mut |_| Control::Continue)
        .unwrap();
    assert!(s.second_strength_round().is_none(), "chosen twice already");
    let (pieces, whole) = summaries_before_and_after_one_run(&mut s);
    let choice = &whole["strength_choice"];
    assert_eq!(pieces["strength_choice"], *choice);
    // Here the second round prefers a finer grid (8 -> 16 cells a side), whose map predicts
    // far more images than observed for every system: it is passed over for the next
    // candidate, whose map is not crowded, in the pieces as in the whole run. So what they
    // compare is that candidate's refit at the estimated redshift.
    let first = &choice["before_estimates"];
    assert!(first["strength"].is_f64(), "{choice}");
    let crowded = &choice["crowded_maps"];
    assert_eq!(crowded.as_array().map(Vec::len), Some(1), "{choice}");
    assert_eq!(crowded[0]["cells"], 16, "{choice}");
    let share =
        |c: &serde_json::Value, n: &serde_json::Value| c.as_f64().unwrap() / n.as_f64().unwrap();
    assert!(
        share(&crowded[0]["crowded_systems"], &crowded[0]["systems"]) > 1.0 / 3.0,
        "{choice}"
    );
    let verdict = &whole["verdict"];
    assert!(
        share(&verdict["systems_far_more_predicted"], &verdict["systems"]) <= 1.0 / 3.0,
        "{verdict}"
    );
    assert_ne!(
        (&first["strength"], &first["cells"]),
        (&choice["chosen"], &choice["chosen_cells"]),
        "{choice}"
    );
    assert!(
        choice["rule"].as_str().unwrap().contains("estimated"),
        "{choice}"
    );
    for key in ["grid_mass_msun", "free_redshifts", "grid_cells"] {
        assert_eq!(pieces[key], whole[key], "{key}");
    }
    let cells = choice["chosen_cells"].as_u64().unwrap();
    assert_eq!(whole["grid_cells"].as_u64().unwrap(), cells * cells);
    // The worker's whole run (first fit, estimates, refit) is timed, not only the refit.
    let (t, stages) = (
        &pieces["timings_ms"],
        ["system_ms", "solve_ms", "products_ms"],
    );
    let refit: f64 = stages.iter().map(|k| t[k].as_f64().unwrap()).sum();
    assert!(t["total_ms"].as_f64().unwrap() > refit, "{t}");
}

/// An "auto" strength in pieces, as the app's parallel workers run it: the plan, one trial
/// per candidate, then the reconstruction with the trials gives what one "auto" run gives.
/// Natively only: the pieces are the same code on wasm32, and eighteen reconstructions in a
/// debug wasm build would dominate the browser run.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn auto_strength_in_pieces_equals_one_auto_run() {
    let mut s = teaching_session();
    s.set_field("reconstruct.objective.strength", json!("auto"))
        .unwrap();
    s.set_field("reconstruct.objective.candidates", json!([0.01, 1.0]))
        .unwrap();
    let (candidates, folds) = s.strength_plan().unwrap().expect("auto has a plan");
    use wslap::{Candidate, Regulariser::Curvature, Regulariser::Density, Regulariser::Gradient};
    // Each grid (the default scales 0.5, 0.75 and 1 of grid.cells, coarsest first) with each
    // regulariser and strength (the least-mass one fitted without the external shear).
    let n = s.settings.reconstruct.grid.cells;
    let grids = [0.5, 0.75, 1.0].map(|f: f64| (f * n as f64).round() as usize);
    let expected: Vec<Candidate> = grids
        .iter()
        .flat_map(|&cells| {
            [
                (Gradient, 0.01),
                (Gradient, 1.0),
                (Curvature, 0.01),
                (Curvature, 1.0),
                (Density, 0.01),
                (Density, 1.0),
            ]
            .map(|(regulariser, strength)| Candidate {
                regulariser,
                strength,
                cells: Some(cells),
            })
        })
        .collect();
    assert_eq!(candidates, expected);
    assert!(folds >= 2, "{folds} folds");
    let trials: Vec<_> = candidates
        .iter()
        .map(|c| {
            s.strength_trial(c, folds, None, &mut |_| Control::Continue)
                .unwrap()
        })
        .collect();
    s.run_with_trials(trials, folds, &mut |_| Control::Continue)
        .unwrap();
    let (pieces, whole) = summaries_before_and_after_one_run(&mut s);
    assert_eq!(pieces["strength_choice"], whole["strength_choice"]);
    assert_eq!(pieces["grid_mass_msun"], whole["grid_mass_msun"]);
    assert_eq!(pieces["settings"]["objective"]["strength"], "auto");
    // The reconstruction is made on the chosen grid.
    let cells = whole["strength_choice"]["chosen_cells"].as_u64().unwrap();
    assert!(grids.contains(&(cells as usize)), "{cells}");
    assert_eq!(whole["grid_cells"].as_u64().unwrap(), cells * cells);
    // A number needs no plan.
    s.set_field("reconstruct.objective.strength", json!(0.1))
        .unwrap();
    assert!(s.strength_plan().unwrap().is_none());
}

/// Published-style deflection maps with NaN and zero borders (tests/data/hff_borders_*, see
/// hff_borders_reference.py) load with a warning counting the pixels without data; the look-up
/// runs, the view draws them blank and the read-out says "no data" there.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn deflection_maps_with_blank_borders_read_no_data_there() {
    let mut s = Session::new();
    let x = include_bytes!("../data/hff_borders_x-arcsec-deflect.fits");
    let y = include_bytes!("../data/hff_borders_y-arcsec-deflect.fits");
    let report = s.load_fits(0, "x.fits", x).unwrap();
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    assert!(
        report.warnings[0].starts_with("x.fits: 446 pixels have no data (178 NaN or blank, 268"),
        "{:?}",
        report.warnings
    );
    s.load_fits(1, "y.fits", y).unwrap();
    s.set_field("z_lens", json!(0.3)).unwrap();
    s.run(RunKind::Lookup, &mut |_| Control::Continue).unwrap();
    let opts = ViewOptions::default();
    assert!(s.kappa_view(&opts).unwrap().png.starts_with(PNG_MAGIC));
    let frame = s.kappa_frame(&opts).unwrap();
    let middle = frame.map_top + frame.map_side / 2.0;
    let centre = s
        .hover(&opts, frame.map_left + frame.map_side / 2.0, middle)
        .unwrap()
        .expect("inside the map");
    assert!(!centre.no_data && centre.kappa.is_finite(), "{centre:?}");
    // The 3 East (left) columns have no data.
    let edge = s
        .hover(&opts, frame.map_left + 0.02 * frame.map_side, middle)
        .unwrap()
        .expect("inside the map");
    assert!(edge.no_data && edge.kappa.is_nan(), "{edge:?}");
    // Counter images: found from a point with data (all on pixels with data), refused by name
    // from one without.
    let c = s.counter_images(glam::DVec2::new(4.0, 1.0)).unwrap();
    assert!(!c.images.is_empty());
    for im in &c.images {
        let p = im.position_arcsec;
        assert!(p.is_finite() && im.magnification.is_finite(), "{im:?}");
    }
    let err = s
        .counter_images(glam::DVec2::new(-9.5, 0.0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("no data there"), "{err}");
}

/// `summary.json` of `s`'s result, then of the result of one whole reconstruction run with the
/// same data and settings.
#[cfg(not(target_arch = "wasm32"))]
fn summaries_before_and_after_one_run(s: &mut Session) -> (serde_json::Value, serde_json::Value) {
    let summary = |s: &Session| -> serde_json::Value {
        serde_json::from_str(&s.result().unwrap().summary_json().unwrap()).unwrap()
    };
    let pieces = summary(s);
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    (pieces, summary(s))
}
