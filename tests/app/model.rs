//! A loaded model file over a reconstruction: its profile and critical curves, kept for the
//! next run of the same field, in the reconstruction's sky frame; a Lenstool `.par` as the
//! model file.

use crate::fixtures::{count_near, solved, teaching_session};
use glam::DVec2;
use serde_json::json;
use wslap::Control;
use wslap::TEACHING_MODEL_JSON;
use wslap::{
    app::profile_relative_differences, app::DataRole, app::RunKind, app::Session, app::ViewOptions,
    app::MODEL_CURVE_RGB,
};

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn committed_teaching_model_is_the_demo_model() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("www/examples/teaching/model.json");
    let committed = std::fs::read_to_string(&path).unwrap();
    assert_eq!(committed.trim(), TEACHING_MODEL_JSON.trim());
}

/// Over a reconstruction, the profile view draws the loaded model file's profile (the true lens
/// of the examples) in the reconstruction's bins. Its enclosed mass is checked independently
/// with Gauss's theorem on the model's own deflection (`div alpha = 2 kappa`, so
/// `M(<R) = Sigma_cr / 2 * circle integral of alpha . r_hat R dphi`), which also holds for the
/// off-centre satellite. The map's pixels sample the SIS cusp at their centres, which misses a
/// fixed mass near r = 0: measured, the profile is low by 0.256 pixel / R (2.1% at 11 arcsec,
/// 0.8% at 30, with 0.94-arcsec pixels); the test allows 0.35 pixel / R.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_profile_view_compares_a_reconstruction_with_the_loaded_model() {
    let mut s = teaching_session();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let palette_1 = wslap::PALETTE[1];
    let without = s.radial_view(&ViewOptions::default()).unwrap();
    let without = tiny_skia::Pixmap::decode_png(&without.png).unwrap();
    assert_eq!(
        count_near(&without, palette_1),
        0,
        "no model, no model line"
    );

    s.load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    let r = s.result().unwrap();
    let (name, profile) = s.model_profile(r).unwrap().expect("the model's profile");
    assert_eq!(name, "model.json");
    assert_eq!(profile.r_edges_arcsec, r.products().profile.r_edges_arcsec);
    let model = wslap::ModelFile::from_json_str(TEACHING_MODEL_JSON, "model.json").unwrap();
    let lens = model.build_lens().unwrap();
    let sigma_cr = r.products().plane.sigma_cr_ref_msun_per_arcsec2;
    let pixel = r.products().maps.geometry().pixel_arcsec();
    let mut checked = 0;
    for (&radius, &mass) in profile
        .r_edges_arcsec
        .iter()
        .zip(&profile.enclosed_mass_msun)
    {
        if radius < 10.0 {
            continue;
        }
        let steps = 2000;
        let flux: f64 = (0..steps)
            .map(|k| {
                let phi = std::f64::consts::TAU * (k as f64 + 0.5) / steps as f64;
                let n = DVec2::new(phi.cos(), phi.sin());
                use wslap::MassComponent;
                lens.deflection(radius * n).dot(n) * radius * std::f64::consts::TAU / steps as f64
            })
            .sum();
        let gauss = 0.5 * flux * sigma_cr;
        assert!(
            (mass / gauss - 1.0).abs() <= 0.35 * pixel / radius,
            "M(<{radius}) = {mass:.4e} Msun from the profile, {gauss:.4e} from Gauss's theorem"
        );
        checked += 1;
    }
    assert!(checked >= 3, "{checked} radii checked");
    let with = s.radial_view(&ViewOptions::default()).unwrap();
    let with = tiny_skia::Pixmap::decode_png(&with.png).unwrap();
    assert!(
        count_near(&with, palette_1) > 200,
        "the model's dashed lines: {} pixels",
        count_near(&with, palette_1)
    );
    // A third panel, of the relative differences, below the two.
    let panel = (without.height() + 8) / 2;
    assert_eq!(with.height(), 3 * panel - 8);
    assert_eq!(with.width(), without.width());
    let lower = with
        .clone_rect(
            tiny_skia::IntRect::from_xywh(0, 2 * panel as i32, with.width(), panel - 8).unwrap(),
        )
        .unwrap();
    assert!(
        count_near(&lower, wslap::PALETTE[2]) > 200,
        "the enclosed mass's relative difference: {} pixels",
        count_near(&lower, wslap::PALETTE[2])
    );
    // Its values: the reconstruction against the model, bin by bin.
    let (kappa, mass) = profile_relative_differences(&r.products().profile, &profile);
    assert_eq!(kappa.len(), profile.kappa.len());
    for ((rk, dk), (&r0, (&ours, &theirs))) in kappa.iter().zip(
        r.products()
            .profile
            .r_arcsec
            .iter()
            .zip(r.products().profile.kappa.iter().zip(&profile.kappa)),
    ) {
        assert_eq!(*rk, r0);
        assert!((dk - (ours / theirs - 1.0)).abs() < 1e-12);
    }
    assert_eq!(
        mass.len(),
        profile.enclosed_mass_msun.len() - 1,
        "M(<0) = 0 is left out"
    );
}

/// Relative differences: a profile 10% above another is +0.1 in every bin; bins where the
/// model has nothing are left out.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn relative_differences_of_profiles() {
    let model = wslap::RadialProfile {
        r_arcsec: vec![1.0, 3.0, 5.0],
        kappa: vec![2.0, 0.0, 0.5],
        r_edges_arcsec: vec![0.0, 2.0, 4.0, 6.0],
        enclosed_mass_msun: vec![0.0, 1e12, 1e12, 2e12],
    };
    let ours = wslap::RadialProfile {
        kappa: model.kappa.iter().map(|k| 1.1 * k).collect(),
        enclosed_mass_msun: model.enclosed_mass_msun.iter().map(|m| 1.1 * m).collect(),
        ..model.clone()
    };
    let (kappa, mass) = profile_relative_differences(&ours, &model);
    assert_eq!(kappa.iter().map(|p| p.0).collect::<Vec<_>>(), [1.0, 5.0]);
    assert_eq!(
        mass.iter().map(|p| p.0).collect::<Vec<_>>(),
        [2.0, 4.0, 6.0]
    );
    for (_, d) in kappa.iter().chain(&mass) {
        assert!((d - 0.1).abs() < 1e-12, "{d}");
    }
}

/// Over a reconstruction, the kappa view draws the loaded model's critical curves (white,
/// dashed) unless turned off. They are traced on the model's own maps; checked against the
/// curves of an independent forward run of the same model (another session, its own map),
/// point by point within a pixel of the model's map.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_kappa_view_draws_the_loaded_model_curves() {
    let mut s = teaching_session();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    assert!(
        s.model_curves(s.result().unwrap()).unwrap().is_none(),
        "no model loaded"
    );
    s.load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    let r = s.result().unwrap();
    let curves = s.model_curves(r).unwrap().expect("the model's curves");
    assert_eq!(curves.name, "model.json");
    assert!(!curves.tangential.is_empty());

    let mut forward = Session::new();
    forward
        .load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    forward
        .set_field(
            "reconstruct.products.z_source",
            json!(r.products().curves.z_source),
        )
        .unwrap();
    forward
        .run(RunKind::Forward, &mut |_| Control::Continue)
        .unwrap();
    let truth = &forward.result().unwrap().products();
    // The teaching model has no sky reference: its frame is the reconstruction's (no shift;
    // the shift is checked with the profile below).
    assert_eq!(truth.reference, None);
    let model_pixel = r.products().maps.geometry().size_arcsec / 64.0;
    let nearest = |p: DVec2, lines: &[Vec<DVec2>]| {
        lines
            .iter()
            .flatten()
            .map(|q| q.distance(p))
            .fold(f64::INFINITY, f64::min)
    };
    let mut checked = 0;
    for (ours, theirs) in [
        (&curves.tangential, &truth.curves.tangential),
        (&curves.radial, &truth.curves.radial),
    ] {
        for &p in ours.iter().flatten() {
            let d = nearest(p, theirs);
            assert!(
                d < model_pixel,
                "{p}: {d} arcsec from the forward run's curve"
            );
            checked += 1;
        }
    }
    assert!(checked > 50, "{checked} points");

    let pixels = |show_model_curves: bool| {
        let opts = ViewOptions {
            show_model_curves,
            show_members: false,
            ..ViewOptions::default()
        };
        // Only the map counts: the figure's white margins change with its legend's text.
        let f = s.kappa_frame(&opts).unwrap();
        let png = s.kappa_view(&opts).unwrap().png;
        let pm = tiny_skia::Pixmap::decode_png(&png).unwrap();
        let (x, y, side) = (f.map_left as u32, f.map_top as u32, f.map_side as u32);
        let map = pm
            .clone_rect(tiny_skia::IntRect::from_xywh(x as i32, y as i32, side, side).unwrap())
            .unwrap();
        count_near(&map, MODEL_CURVE_RGB)
    };
    let (with, without) = (pixels(true), pixels(false));
    assert!(
        with > without + 200,
        "white pixels: {with} with the model's curves, {without} without"
    );
}

/// The model's maps are computed once for a field: a second reconstruction of the same data
/// reuses them (the same curves, no new computation), another map width computes them again.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_model_maps_are_kept_for_the_next_run_of_the_same_field() {
    let mut s = solved();
    s.load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    assert_eq!(s.model_maps_computed(), 0);
    let first = s.model_curves(s.result().unwrap()).unwrap().unwrap();
    s.model_profile(s.result().unwrap()).unwrap().unwrap();
    assert_eq!(s.model_maps_computed(), 1);
    let run = |s: &mut Session| {
        s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
            .unwrap();
        s.model_curves(s.result().unwrap()).unwrap().unwrap()
    };
    s.set_field("reconstruct.solver.iterations", json!(300))
        .unwrap();
    assert_eq!(run(&mut s), first);
    assert_eq!(s.model_maps_computed(), 1);
    let width = s.result().unwrap().products().maps.geometry().size_arcsec;
    s.set_field("reconstruct.products.size_arcsec", json!(width + 10.0))
        .unwrap();
    assert_ne!(run(&mut s), first);
    assert_eq!(s.model_maps_computed(), 2);
}

/// The model's profile and curves are taken about the reconstruction's sky origin: a model
/// file whose frame is 3 arcsec north of the catalogue's, with its components moved to the same
/// sky positions, gives the same profile and the same curves. A model at another lens redshift is not compared (`None`).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_model_profile_follows_the_sky_frame_and_the_lens_plane() {
    let mut s = solved();
    let profile_of = |s: &mut Session, text: &str| {
        s.load_text(DataRole::Model, "model.json", text).unwrap();
        s.model_profile(s.result().unwrap()).unwrap()
    };
    let same_frame = r#"{"z_lens": 0.3, "reference": {"ra": 150.0, "dec": 2.2}, "components": [
        {"type": "sis", "x": 0.0, "y": 0.0, "sigma_v": 700.0},
        {"type": "sis", "x": 18.0, "y": 6.0, "sigma_v": 150.0}]}"#;
    let north = format!(
        r#"{{"z_lens": 0.3, "reference": {{"ra": 150.0, "dec": {}}}, "components": [
        {{"type": "sis", "x": 0.0, "y": -3.0, "sigma_v": 700.0}},
        {{"type": "sis", "x": 18.0, "y": 3.0, "sigma_v": 150.0}}]}}"#,
        2.2 + 3.0 / 3600.0
    );
    let (_, a) = profile_of(&mut s, same_frame).unwrap();
    let curves_a = s.model_curves(s.result().unwrap()).unwrap().unwrap();
    let (_, b) = profile_of(&mut s, &north).unwrap();
    for (x, y) in a.enclosed_mass_msun.iter().zip(&b.enclosed_mass_msun) {
        assert!((x - y).abs() <= 1e-6 * x.abs().max(1.0), "{x} vs {y}");
    }
    // So do its critical curves, drawn in the reconstruction's frame.
    let curves_b = s.model_curves(s.result().unwrap()).unwrap().unwrap();
    let points = |c: &wslap::app::ModelCurves| -> Vec<DVec2> {
        c.tangential
            .iter()
            .chain(&c.radial)
            .flatten()
            .copied()
            .collect()
    };
    let (pa, pb) = (points(&curves_a), points(&curves_b));
    assert!(!pa.is_empty());
    assert_eq!(pa.len(), pb.len());
    for (p, q) in pa.iter().zip(&pb) {
        assert!(p.distance(*q) < 1e-6, "{p} vs {q}");
    }
    // Unmoved, the components sit 3 arcsec off the centre: the inner profile drops.
    let unmoved = same_frame.replace("\"dec\": 2.2", &format!("\"dec\": {}", 2.2 + 3.0 / 3600.0));
    let (_, c) = profile_of(&mut s, &unmoved).unwrap();
    assert!(
        c.kappa[0] < 0.8 * a.kappa[0],
        "{} vs {}",
        c.kappa[0],
        a.kappa[0]
    );
    let other_plane = same_frame.replace("\"z_lens\": 0.3", "\"z_lens\": 0.35");
    assert!(profile_of(&mut s, &other_plane).is_none());
    assert!(s.radial_view(&ViewOptions::default()).is_ok());
}

/// A published Lenstool model (AS1063's CATS gold `bestopt.par`) as the model file: forward
/// maps equal to the library's model of the same files, its potfile members taken from the
/// loaded member catalogue (an error says so when there is none), and its curves drawn over a
/// reconstruction at the model's z_lens (not at another).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn a_lenstool_par_is_a_model_file_with_the_member_catalogue_as_its_potfile() {
    use wslap::load_lenstool_model;
    use wslap::{ProductOptions, Products};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/AS1063/lenstool_cats");
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
    let (par, members) = (
        "cats_gold_bestopt.par",
        "cats_gold_ref_potential_w_clumpNE.cat",
    );

    // Without the member catalogue the model loads but cannot be evaluated.
    let mut s = Session::new();
    let report = s.load_text(DataRole::Model, par, &read(par)).unwrap();
    assert!(
        report.summary.starts_with("Lenstool model: ")
            && report
                .summary
                .contains("potfile's members from the member catalogue")
            && report.summary.ends_with("at z_lens = 0.3475"),
        "{}",
        report.summary
    );
    let err = s
        .run(RunKind::Forward, &mut |_| Control::Continue)
        .unwrap_err()
        .to_string();
    assert!(err.contains("needs the member catalogue"), "{err}");

    // With it: the forward maps are the library's.
    s.load_text(DataRole::Members, members, &read(members))
        .unwrap();
    for (path, value) in [
        ("reconstruct.products.z_source", json!(2.0)),
        ("reconstruct.products.size_arcsec", json!(160.0)),
        ("reconstruct.products.pixels", json!(100)),
    ] {
        s.set_field(path, value).unwrap();
    }
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    let ours = s.result().unwrap().products().curves.einstein_radius_arcsec;
    let model = load_lenstool_model(&dir.join(par), &[&dir.join(members)]).unwrap();
    let opts = ProductOptions {
        z_source: 2.0,
        size_arcsec: 160.0,
        pixels: 100,
        ..ProductOptions::default()
    };
    let library = Products::from_lens(&model.lens, model.plane, model.reference, &opts).unwrap();
    assert_eq!(ours, library.curves.einstein_radius_arcsec);
    assert!((25.0..35.0).contains(&ours), "{ours}");

    // Over a reconstruction of the gold images at the model's z_lens, its curves are drawn.
    let images = "cats_gold_mul_gold.cat";
    s.load_text(DataRole::Images, images, &read(images))
        .unwrap();
    for (path, value) in [
        ("z_lens", json!(0.3475)),
        ("reconstruct.grid.cells", json!(12)),
        ("reconstruct.solver.iterations", json!(200)),
        ("reconstruct.constraints.mode", json!("point")),
    ] {
        s.set_field(path, value).unwrap();
    }
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let curves = s
        .model_curves(s.result().unwrap())
        .unwrap()
        .expect("the model's curves");
    assert_eq!(curves.name, par);
    assert!(!curves.tangential.is_empty());
    assert!(s.model_profile(s.result().unwrap()).unwrap().is_some());
    assert_eq!(s.model_not_compared(s.result().unwrap()), None);
    assert_eq!(s.model_note(s.result().unwrap()), None);
    let profile = s.model_profile(s.result().unwrap()).unwrap().unwrap();
    // The z_lens of the CATS catalogues' papers (0.348) is 0.1% away in D_l: the model is
    // compared on its own plane (the same curves and masses), and the caption says so.
    s.set_field("z_lens", json!(0.348)).unwrap();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let r = s.result().unwrap();
    assert_eq!(s.model_curves(r).unwrap(), Some(curves));
    assert_eq!(s.model_profile(r).unwrap(), Some(profile));
    let note = s.model_note(r).unwrap();
    let prefix = "cats_gold_bestopt.par is compared at its own z_lens = 0.3475 (the \
                  reconstruction's is 0.348: their distances to the lens differ by ";
    assert!(note.starts_with(prefix) && note.ends_with("%)"), "{note}");
    let percent: f64 = note[prefix.len()..note.len() - 2].parse().unwrap();
    assert!((0.05..=0.15).contains(&percent), "{note}");
    // At another cluster's z_lens its kappa would not compare: no curves, and the result
    // says why.
    s.set_field("z_lens", json!(0.4)).unwrap();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    assert!(s.model_curves(s.result().unwrap()).unwrap().is_none());
    assert_eq!(
        s.model_note(s.result().unwrap()).as_deref(),
        Some(
            "cats_gold_bestopt.par is not compared: its z_lens = 0.3475 is not the \
             reconstruction's 0.4 (set z_lens to compare)"
        )
    );
    // Without its member catalogue it cannot be built: that is the reason given.
    s.data.clear(DataRole::Members);
    let why = s.model_not_compared(s.result().unwrap()).unwrap();
    assert!(why.contains("needs the member catalogue"), "{why}");
}

/// A `.par`'s potfile without a header in arcsec from the `.par`'s reference (A1835's published
/// model of Richard et al.: `199 -70.4727720 -22.8484800 ...`): loaded before the `.par` it is
/// refused with a hint to load the `.par` first; after it, it loads with a warning, the forward
/// model runs, and a reconstruction reads the members in the image catalogue's frame (here
/// 10 arcsec north of the `.par`'s reference: every member 10 arcsec lower).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_par_s_headerless_arcsec_potfile_loads_after_the_par() {
    let par = "runmode\n\treference 3 210.258650 2.878470\n\tend\n\
        potentiel O1\n\tprofil 81\n\tx_centre 0.0\n\ty_centre 0.0\n\tellipticite 0.2\n\
        \tangle_pos 10.0\n\tcore_radius_kpc 50.0\n\tcut_radius_kpc 1500.0\n\tv_disp 1100.0\n\
        \tz_lens 0.253\n\tend\n\
        potfile\n\tfilein 1 gal.cat\n\tzlens 0.253\n\ttype 81\n\tcorekpc 0.15\n\tmag0 17.0\n\
        \tsigma 0 150.0\n\tcutkpc 0 40.0\n\tslope 0 4.0\n\tvdslope 0 4.0\n\tend\n\
        cosmologie\n\tH0 70.0\n\tomegaM 0.3\n\tomegaX 0.7\n\tend\nfini\n";
    let members = "199 -70.4727720 -22.8484800 0.557 0.371 -63.100 17.39 0.10\n\
        106 -35.9541832 101.6661600 0.500 0.500 50.000 18.41 0.10\n\
        232 23.2212647 -52.7292000 0.563 0.280 -48.300 18.42 0.10\n";
    let mut s = Session::new();
    let error = s
        .load_text(DataRole::Members, "gal.cat", members)
        .unwrap_err();
    // The page tells this refusal from the rest by its code, not by its words.
    assert_eq!(error.code(), Some("wants-par"));
    let refused = error.to_string();
    for part in [
        "line 1",
        "not a right ascension",
        "potfile of a Lenstool .par",
        "load that .par as the model file first",
    ] {
        assert!(refused.contains(part), "{part:?} not in {refused}");
    }
    assert!(s.data.members.is_none());

    s.load_text(DataRole::Model, "bestopt.par", par).unwrap();
    // Until its member catalogue is loaded, the page names the one it lacks.
    let options = s.settings.par_options();
    assert_eq!(s.data.missing_potfile(&options).as_deref(), Some("gal.cat"));
    let report = s.load_text(DataRole::Members, "gal.cat", members).unwrap();
    assert_eq!(s.data.missing_potfile(&options), None);
    assert_eq!(report.summary, "3 members");
    let [w] = &report.warnings[..] else {
        panic!("{:?}", report.warnings)
    };
    assert!(w.contains("no #REFERENCE header"), "{w}");
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    let theta_e = s.result().unwrap().products().curves.einstein_radius_arcsec;
    assert!(theta_e > 5.0, "{theta_e}");

    let images = "#REFERENCE 3 210.258650 2.881247778\n\
        1.1 10.0 5.0 0.5 0.5 0 2.0 25\n1.2 -12.0 -8.0 0.5 0.5 0 2.0 25\n";
    s.load_text(DataRole::Images, "images.cat", images).unwrap();
    // Before a reconstruction, a z_lens that would not compare with the .par's is said.
    s.set_field("z_lens", json!(0.35)).unwrap();
    assert_eq!(
        s.model_z_lens_note().as_deref(),
        Some(
            "bestopt.par is at z_lens = 0.253 and the settings at 0.35: set z_lens to 0.253 if \
             the images are of its cluster (else the model is not compared)"
        )
    );
    s.set_field("z_lens", json!(0.253)).unwrap();
    assert_eq!(s.model_z_lens_note(), None);
    let data = s.parsed().unwrap();
    let got: Vec<DVec2> = data
        .members
        .unwrap()
        .members
        .iter()
        .map(|m| m.position)
        .collect();
    let want = [
        (-70.4727720, -22.8484800),
        (-35.9541832, 101.6661600),
        (23.2212647, -52.7292000),
    ];
    for (g, (x, y)) in got.iter().zip(want) {
        // 10 arcsec north, on the tangent planes of two references 10 arcsec apart.
        assert!(
            (g.x - x).abs() < 0.01 && (g.y - (y - 10.0)).abs() < 0.01,
            "{g} vs {x} {y}"
        );
    }
    // Another .par moves the members with its reference; a JSON model leaves them none (a
    // reconstruction refuses them): each is said when the model file loads. The same .par again
    // says nothing.
    let moved = par.replace("210.258650 2.878470", "210.258650 2.880000");
    let said = |report: wslap::app::LoadReport| report.warnings.join(" | ");
    let report = s.load_text(DataRole::Model, "other.par", &moved).unwrap();
    assert!(said(report).contains(
        "gal.cat was read as bestopt.par's potfile, in arcsec from its reference; it is \
             read now from other.par's, which is another: its members move with it"
    ),);
    s.load_text(DataRole::Model, "bestopt.par", par).unwrap();
    let report = s.load_text(DataRole::Model, "bestopt.par", par).unwrap();
    assert!(!said(report.clone()).contains("gal.cat"), "{report:?}");
    let report = s
        .load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    assert!(
        said(report.clone()).contains(
            "gal.cat was read as bestopt.par's potfile, in arcsec from its reference, and \
             model.json gives none: a reconstruction now refuses gal.cat. Load bestopt.par again"
        ),
        "{report:?}"
    );
}

/// A Lenstool model with a group at another redshift (tests/data/lenstool/multiplane.par with
/// one potfile, after A370's CATS bestopt.par): refused, naming the setting; with the
/// single-plane setting it loads, its report names the block moved, and it evaluates. The
/// member catalogue's rows with magnitude 99 are skipped with a warning in its report.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_multi_plane_lenstool_model_loads_with_the_single_plane_setting() {
    let full = include_str!("../data/lenstool/multiplane.par");
    let (start, end) = (
        full.find("potfile1\n").unwrap(),
        full.find("cosmologie\n").unwrap(),
    );
    let par = [&full[..start], &full[end..]].concat().replace(
        "\tmag\t\t  17.690000\n\tz_lens     0.3750",
        "\tmag\t\t  17.69\n\tz_lens     0.6",
    );
    let mut s = Session::new();
    let err = s
        .load_text(DataRole::Model, "group.par", &par)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("group.par:")
            && err.contains("`potentiel O2`")
            && err.contains("single-plane approximation"),
        "{err}"
    );
    s.set_field("lenstool_single_plane", json!(true)).unwrap();
    let report = s.load_text(DataRole::Model, "group.par", &par).unwrap();
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    assert!(
        report.warnings[0].contains("`potentiel O2`") && report.warnings[0].contains("z = 0.6"),
        "{:?}",
        report.warnings
    );
    let members = s
        .load_text(
            DataRole::Members,
            "members.cat",
            include_str!("../data/lenstool/members.cat"),
        )
        .unwrap();
    assert_eq!(members.summary, "3 members");
    assert_eq!(members.warnings.len(), 2, "{:?}", members.warnings);
    assert!(members
        .warnings
        .iter()
        .all(|w| w.contains("no measurement")));
    s.set_field("reconstruct.products.pixels", json!(48))
        .unwrap();
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    // Turned off again, the kept model is refused when read again.
    s.set_field("lenstool_single_plane", json!(false)).unwrap();
    let err = s.reload(DataRole::Model).unwrap_err().to_string();
    assert!(err.contains("multi-plane"), "{err}");
}
