//! Stepping through the iterations: a reconstruction in the app keeps iterates at increasing
//! iteration counts, the last one the solution, and the mass map can show any of them.

use crate::fixtures::teaching_session;
use serde_json::json;
use wslap::app::{
    RunKind, Session, StoredIterates, ViewOptions, APP_KEPT_ITERATES, MAX_STORED_ITERATE_VALUES,
};
use wslap::{Control, Iterate};

/// The teaching example with the paper's QADP (the app's example settings), quick.
fn qadp_session() -> Session {
    let mut s = teaching_session();
    for (path, value) in [
        ("reconstruct.solver.method", json!("qadp")),
        ("reconstruct.solver.iterations", json!(800)),
        ("reconstruct.objective.regulariser", json!("none")),
        ("reconstruct.objective.strength", json!(0)),
        ("reconstruct.objective.image_plane_iterations", json!(0)),
        ("reconstruct.products.pixels", json!(96)),
    ] {
        s.set_field(path, value).unwrap();
    }
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    s
}

/// kappa under the middle of the map drawn with `opts`, and the rendered PNG.
fn centre_and_png(s: &Session, opts: &ViewOptions) -> (f64, Vec<u8>) {
    let frame = s.kappa_frame(opts).unwrap();
    let (cx, cy) = (
        frame.map_left + 0.45 * frame.map_side,
        frame.map_top + 0.5 * frame.map_side,
    );
    let kappa = s.hover(opts, cx, cy).unwrap().expect("on the map").kappa;
    (kappa, s.kappa_view(opts).unwrap().png)
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_mass_map_steps_through_the_kept_iterates() {
    let s = qadp_session();
    let r = s.result().unwrap();
    let list = r
        .iterate_list()
        .expect("a reconstruction keeps its iterates");
    let counts: Vec<usize> = list.steps.iter().map(|i| i.iteration).collect();
    assert_eq!(list.method, "qadp");
    assert_eq!(list.iterations, 800);
    assert!(
        counts.len() > 20 && counts.len() <= APP_KEPT_ITERATES,
        "{counts:?}"
    );
    assert!(counts.windows(2).all(|w| w[0] < w[1]), "{counts:?}");
    assert_eq!((counts[0], counts.last()), (0, Some(&800)));
    let rec = r.reconstruction().unwrap();
    assert_eq!(rec.iterates.last().unwrap().x, rec.x);
    let bytes: usize = rec.iterates.iter().map(|i| 8 * i.x.len()).sum();
    assert!(bytes <= APP_KEPT_ITERATES * 8 * rec.system.n_columns());

    let opts = ViewOptions::default();
    let at = |k: usize| ViewOptions {
        iterate: Some(k),
        ..opts
    };
    let (kappa_final, png_final) = centre_and_png(&s, &opts);
    // The last iterate is the solution: the same map (the title adds its iteration).
    let last = counts.len() - 1;
    let (kappa_last, _) = centre_and_png(&s, &at(last));
    assert_eq!(kappa_last, kappa_final);
    // An early iterate has less mass in the middle (measured: kappa 0.76 after 10 updates,
    // 4.4 after 800), and its figure differs.
    let early = counts.iter().position(|&c| c >= 10).unwrap();
    let (kappa_early, png_early) = centre_and_png(&s, &at(early));
    assert!(
        kappa_early < 0.5 * kappa_final,
        "kappa {kappa_early} at iteration {} against {kappa_final}",
        counts[early]
    );
    assert_ne!(png_early, png_final);
    // Drawn again, the same iterate gives the same figure (its maps are kept).
    assert_eq!(s.kappa_view(&at(early)).unwrap().png, png_early);
    // Another source redshift redraws its curves too.
    let mut s = s;
    s.set_z_source(4.0).unwrap();
    assert_ne!(s.kappa_view(&at(early)).unwrap().png, png_early);

    let err = s.kappa_view(&at(counts.len())).unwrap_err().to_string();
    assert!(err.contains(&format!("iterate {}", counts.len())), "{err}");
}

/// Relative difference allowed between kappa of an iterate before and after a reload (the
/// project keeps the iterates as `f32`).
const STORED_ITERATE_RTOL: f64 = 1e-5;

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_restored_project_keeps_its_iterates_to_step_through() {
    let s = qadp_session();
    let project = s.project_json().unwrap();
    let mut t = Session::new();
    let report = t.open_project(&project, "project.json").unwrap();
    assert_eq!(report.result, "restored", "{}", report.message);
    let list = s.result().unwrap().iterate_list().unwrap();
    assert_eq!(t.result().unwrap().iterate_list(), Some(list.clone()));
    let early = list.steps.iter().position(|i| i.iteration >= 10).unwrap();
    let at = ViewOptions {
        iterate: Some(early),
        ..ViewOptions::default()
    };
    let (before, _) = centre_and_png(&s, &at);
    let (after, _) = centre_and_png(&t, &at);
    assert!(
        (after / before - 1.0).abs() < STORED_ITERATE_RTOL,
        "kappa {after} after the reload, {before} before"
    );

    // A project of before the iterates were kept opens without them: no slider.
    let mut value: serde_json::Value = serde_json::from_str(&project).unwrap();
    value["result"].as_object_mut().unwrap().remove("iterates");
    let mut u = Session::new();
    u.open_project(&value.to_string(), "old.json").unwrap();
    assert!(u.result().unwrap().iterate_list().is_none());
    let opts = ViewOptions {
        iterate: Some(0),
        ..ViewOptions::default()
    };
    assert!(u.kappa_view(&opts).is_err());

    // Iterates that do not fit the result are left out, and the message says why.
    value["result"]["iterates"] = serde_json::to_value(
        StoredIterates::from_iterates(&s.result().unwrap().reconstruction().unwrap().iterates)
            .unwrap(),
    )
    .unwrap();
    value["result"]["iterates"]["unknowns"] = json!(3);
    let report = u.open_project(&value.to_string(), "odd.json").unwrap();
    assert_eq!(report.result, "restored");
    assert!(
        report.message.contains("stored iterates were not used")
            && report.message.contains("3 unknowns"),
        "{}",
        report.message
    );
    assert!(u.result().unwrap().iterate_list().is_none());
}

/// A run with more iterate values than a project keeps is thinned (the first and the last
/// stay); a single iterate is not kept (no slider).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn stored_iterates_are_bounded() {
    let unknowns = MAX_STORED_ITERATE_VALUES / 10;
    let iterates: Vec<Iterate> = (0..41)
        .map(|k| Iterate {
            iteration: k * 10,
            objective: 1.0 / (k as f64 + 1.0),
            x: vec![k as f64; unknowns],
        })
        .collect();
    let stored = StoredIterates::from_iterates(&iterates).unwrap();
    assert!(stored.steps.len() * unknowns <= MAX_STORED_ITERATE_VALUES);
    assert!(stored.steps.len() >= 6, "{} kept", stored.steps.len());
    assert_eq!(stored.steps[0].iteration, 0);
    assert_eq!(stored.steps.last().unwrap().iteration, 400);
    let back = stored.to_iterates(unknowns).unwrap();
    assert_eq!(back.last().unwrap().x, iterates.last().unwrap().x);
    assert!(StoredIterates::from_iterates(&iterates[..1]).is_none());
}
