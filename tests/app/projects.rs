//! Project files: a reconstruction reopens with its maps rebuilt from X, a look-up keeps its
//! deflection maps, and a broken or oversized FITS in a project is refused.

use crate::fixtures::{forward_session, solved};
use serde_json::json;
use wslap::Control;
use wslap::RunStatus;
use wslap::{app::DataRole, app::RunKind, app::Session, app::MAX_STORED_FITS_BYTES};

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_project_reopens_with_the_maps_rebuilt_from_x() {
    let s = solved();
    let text = s.project_json().unwrap();
    let mut t = Session::new();
    let report = t.open_project(&text, "p.json").unwrap();
    assert_eq!(report.result, "restored", "{}", report.message);
    // Each file reports as it did when it was loaded: its counts and warnings.
    let images = s.data.images.as_ref().unwrap();
    let by_hand = Session::new()
        .load_text(DataRole::Images, &images.name, &images.text)
        .unwrap();
    assert_eq!(report.files, [by_hand]);
    assert!(
        report.files[0].summary.contains("systems"),
        "{:?}",
        report.files
    );
    // The run's warnings come back as its summary.json lists them, also those that
    // rebuilding from X cannot find again (what a run's redshift estimates said).
    let mut project: serde_json::Value = serde_json::from_str(&text).unwrap();
    let said = "system 3: redshift estimated z = 2.18 (68%: 1.39 - 3.23) ..., and fitted at it";
    project["result"]["summary"]["warnings"]
        .as_array_mut()
        .unwrap()
        .push(json!(said));
    let mut u = Session::new();
    u.open_project(&project.to_string(), "p.json").unwrap();
    let back = &u.result().unwrap().reconstruction().unwrap().warnings;
    let mut expected = s
        .result()
        .unwrap()
        .reconstruction()
        .unwrap()
        .warnings
        .clone();
    expected.push(said.to_string());
    assert_eq!(*back, expected);
    let (a, b) = (s.result().unwrap(), t.result().unwrap());
    // serde_json's float parsing may differ from the written value in the last bit.
    const KAPPA_RTOL: f64 = 1e-9;
    let worst = a
        .products()
        .maps
        .kappa
        .data
        .iter()
        .zip(&b.products().maps.kappa.data)
        .map(|(p, q)| (p - q).abs() / p.abs().max(1e-12))
        .fold(0.0, f64::max);
    assert!(worst <= KAPPA_RTOL, "kappa differs by {worst:e} (relative)");
    // One result type: the reopened reconstruction says it was restored, not solved.
    let solved_status = a.reconstruction().unwrap().status;
    assert!(
        matches!(solved_status, RunStatus::Solved(_)),
        "{solved_status}"
    );
    assert_eq!(b.reconstruction().unwrap().status, RunStatus::Restored);
    let summary: serde_json::Value = serde_json::from_str(&b.summary_json().unwrap()).unwrap();
    assert_eq!(summary["status"], "Restored");
    assert_eq!(t.settings, s.settings);
    assert_eq!(t.data.images, s.data.images);
    // A broken project changes nothing.
    let err = t
        .open_project("{\"format\": \"other\", \"version\": 1}", "q.json")
        .unwrap_err();
    assert!(err.to_string().contains("q.json"), "{err}");
    // A project saved by a newer version says so with both versions, even when the rest of it
    // would not read here (a field this version does not know).
    let newer = text
        .replacen("\"version\": 1", "\"version\": 7", 1)
        .replacen(
            "\"settings\": {",
            "\"settings\": \"moved\", \"settings_v7\": {",
            1,
        );
    assert!(newer.contains("settings_v7") && newer.contains("\"version\": 7"));
    let err = t.open_project(&newer, "newer.json").unwrap_err();
    assert_eq!(
        err.to_string(),
        "newer.json: saved by a newer version of wslap (project format version 7; this version \
         reads version 1): open it with that version, or update this one"
    );
    let err = t
        .open_project(
            "{\"format\": \"wslap-project\", \"version\": 0}",
            "old.json",
        )
        .unwrap_err();
    assert!(err.to_string().contains("version 0 is not one"), "{err}");
    // Truncated in the middle of a save: where it ends is said.
    let err = t
        .open_project(&text[..text.len() / 2], "cut.json")
        .unwrap_err();
    assert!(err.to_string().starts_with("cut.json: line "), "{err}");
    // Not JSON: the place is said once.
    let err = t.open_project("{\"format\": wslap}", "r.json").unwrap_err();
    assert_eq!(err.to_string(), "r.json: line 1, column 12: expected value");
    assert!(t.result.is_some());
}

/// An "auto" result made on a grid other than the settings' (its choice took 8 cells a side,
/// the settings say 16) reopens on that grid, with its choice: it used to be refused ("X has
/// 277 values, expected 1045") and had to be solved again.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn an_auto_project_reopens_on_the_grid_its_choice_took() {
    let mut s = crate::fixtures::teaching_session();
    for (path, value) in [
        ("reconstruct.objective.strength", json!("auto")),
        ("reconstruct.objective.candidates", json!([0.1])),
        ("reconstruct.objective.auto_grid_scales", json!([0.5])),
        (
            "reconstruct.objective.auto_regularisers",
            json!(["gradient"]),
        ),
    ] {
        s.set_field(path, value).unwrap();
    }
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let mut t = Session::new();
    let report = t
        .open_project(&s.project_json().unwrap(), "p.json")
        .unwrap();
    assert_eq!(report.result, "restored", "{}", report.message);
    let summary = |s: &Session| -> serde_json::Value {
        serde_json::from_str(&s.result().unwrap().summary_json().unwrap()).unwrap()
    };
    let (a, b) = (summary(&s), summary(&t));
    assert_eq!(a["grid_cells"], json!(64));
    for key in ["grid_cells", "strength_choice"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    // serde_json's float parsing may differ from the written value in the last bit.
    let mass = |v: &serde_json::Value| v["grid_mass_msun"].as_f64().unwrap();
    assert!((mass(&a) / mass(&b) - 1.0).abs() < 1e-9, "{a} / {b}");
    assert_eq!(b["settings"]["objective"]["strength"], "auto");
    assert_eq!(b["settings"]["grid"]["cells"], json!(16));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_lookup_project_keeps_its_deflection_maps() {
    let (_, fx, fy) = forward_session();
    let mut s = Session::new();
    s.set_field("z_lens", json!(0.3)).unwrap();
    s.set_field("reconstruct.products.z_source", json!(3.0))
        .unwrap();
    s.load_fits(0, "alpha_x.fits", &fx).unwrap();
    s.load_fits(1, "alpha_y.fits", &fy).unwrap();
    s.run(RunKind::Lookup, &mut |_| Control::Continue).unwrap();
    let text = s.project_json().unwrap();
    let project: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(project["data"]["deflection_x"]["name"], "alpha_x.fits");

    let mut t = Session::new();
    let report = t.open_project(&text, "lookup.json").unwrap();
    assert_eq!(report.result, "recomputed", "{}", report.message);
    for axis in 0..2 {
        let (a, b) = (
            s.data.deflection[axis].as_ref().unwrap(),
            t.data.deflection[axis].as_ref().unwrap(),
        );
        assert_eq!(a.name, b.name);
        assert_eq!(a.map.data, b.map.data, "axis {axis}: the map changed");
        assert_eq!(
            b.fits.as_deref(),
            Some([fx.as_slice(), fy.as_slice()][axis])
        );
    }
    let (a, b) = (s.result().unwrap(), t.result().unwrap());
    assert_eq!(b.kind, RunKind::Lookup);
    assert_eq!(b.products().curves.z_source, 3.0);
    assert_eq!(
        a.products().curves.einstein_radius_arcsec,
        b.products().curves.einstein_radius_arcsec
    );
    // The reopened session writes the same data (the summary's timings differ).
    let again: serde_json::Value = serde_json::from_str(&t.project_json().unwrap()).unwrap();
    assert!(again["data"] == project["data"], "the stored data changed");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_project_with_a_broken_or_oversized_fits_is_refused_and_changes_nothing() {
    let (mut s, fx, _) = forward_session();
    s.load_fits(0, "alpha_x.fits", &fx).unwrap();
    let text = s.project_json().unwrap();
    let mut project: serde_json::Value = serde_json::from_str(&text).unwrap();
    project["data"]["deflection_x"]["fits_base64"] = json!("AAAA*AAA");
    let before = s.project_json().unwrap();
    let err = s
        .open_project(&project.to_string(), "p.json")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("p.json") && err.contains("alpha_x.fits") && err.contains("not base64"),
        "{err}"
    );
    // Just above the stated limit (base64 of MAX_STORED_FITS_BYTES + 3 bytes and more).
    let too_big = "A".repeat((MAX_STORED_FITS_BYTES / 3 + 2) * 4);
    project["data"]["deflection_x"]["fits_base64"] = json!(too_big);
    let err = s
        .open_project(&project.to_string(), "p.json")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(&MAX_STORED_FITS_BYTES.to_string()) && err.contains("alpha_x.fits"),
        "{err}"
    );
    assert_eq!(s.project_json().unwrap(), before);
    // A project written before FITS maps were stored still opens.
    project["data"]
        .as_object_mut()
        .unwrap()
        .remove("deflection_x");
    let report = s.open_project(&project.to_string(), "old.json").unwrap();
    assert_eq!(report.result, "recomputed", "{}", report.message);
    assert!(s.data.deflection[0].is_none());
}

/// The weak-lensing synthetic of tests/inversion/shear.rs in the app: the arclets load as their
/// own file (a bad one is refused with its line and keeps the good one), the run fits them, and
/// the project keeps them and rebuilds the same map from X.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_project_keeps_its_arclets() {
    use wslap::app::DataRole;
    let mut s = Session::new();
    let images = include_str!("../data/weak_lensing/images.cat");
    let arclets = include_str!("../data/weak_lensing/arclets.cat");
    s.load_text(DataRole::Images, "images.cat", images).unwrap();
    let report = s
        .load_text(DataRole::Shear, "arclets.cat", arclets)
        .unwrap();
    assert_eq!(report.summary, "3000 arclets (weak lensing)");
    let bad = arclets.replacen(
        "1 166.2124 139.8925 0.5000 0.20041",
        "1 166.2124 139.8925 0.5000 -0.2",
        1,
    );
    let err = s.load_text(DataRole::Shear, "bad.cat", &bad).unwrap_err();
    assert_eq!(
        err.to_string(),
        "bad.cat: line 4, column 5 (b): '-0.2' is negative: ellipse semi-axes must be >= 0 arcsec"
    );
    assert_eq!(s.data.shear.as_ref().unwrap().name, "arclets.cat");
    for (path, value) in [
        ("z_lens", json!(0.32)),
        ("reconstruct.grid.cells", json!(16)),
        ("reconstruct.products.pixels", json!(64)),
        ("reconstruct.objective.regulariser", json!("density")),
        ("reconstruct.objective.strength", json!(0.01)),
        ("reconstruct.shear.shape_noise", json!(0.3)),
    ] {
        s.set_field(path, value).unwrap();
    }
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let summary: serde_json::Value =
        serde_json::from_str(&s.result().unwrap().summary_json().unwrap()).unwrap();
    assert_eq!(summary["weak_lensing"]["arclets"], 3000);
    let text = s.project_json().unwrap();
    let mut t = Session::new();
    let report = t.open_project(&text, "wl.json").unwrap();
    assert_eq!(report.result, "restored", "{}", report.message);
    assert_eq!(t.data.shear, s.data.shear);
    let (a, b) = (s.result().unwrap(), t.result().unwrap());
    let worst = a
        .products()
        .maps
        .kappa
        .data
        .iter()
        .zip(&b.products().maps.kappa.data)
        .map(|(p, q)| (p - q).abs() / p.abs().max(1e-12))
        .fold(0.0, f64::max);
    assert!(worst <= 1e-9, "kappa differs by {worst:e} (relative)");
    let restored: serde_json::Value =
        serde_json::from_str(&t.result().unwrap().summary_json().unwrap()).unwrap();
    assert_eq!(restored["weak_lensing"]["arclets"], 3000);
}
