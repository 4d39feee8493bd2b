//! The browser app's core (`wslap::app`): loading files without losing data, settings, the
//! three run kinds, z_s redraws, views, hover read-outs, downloads and project files. These are
//! the paths the web worker uses; they run natively and in a dedicated worker.

mod common;

use glam::DVec2;
use serde_json::json;
use wslap::app::examples::{teaching_image_catalog, TEACHING_SOURCES};
use wslap::app::{
    system_rgb, DataRole, RunKind, Session, ViewOptions, MAX_STORED_FITS_BYTES, OBSERVED_RGB,
    PREDICTED_RGB, SHOWN_MIN_MAGNIFICATION,
};
use wslap::demo::TEACHING_MODEL_JSON;
use wslap::render::{LegendPlace, PIXEL_ALPHA};
use wslap::solver::Control;

/// A quick reconstruction: 16 x 16 cells, 400 iterations, 64-pixel maps.
fn teaching_session() -> Session {
    let mut s = Session::new();
    s.name = "teaching".into();
    let cat = teaching_image_catalog().unwrap();
    s.load_text(DataRole::Images, "images.cat", &cat).unwrap();
    for (path, value) in [
        ("z_lens", json!(0.3)),
        ("reconstruct.grid.cells", json!(16)),
        ("reconstruct.solver.iterations", json!(400)),
        ("reconstruct.products.pixels", json!(64)),
    ] {
        s.set_field(path, value).unwrap();
    }
    s
}

fn solved() -> Session {
    let mut s = teaching_session();
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    s
}

const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn teaching_catalogue_has_multiple_images_of_every_source() {
    let cat = teaching_image_catalog().unwrap();
    for (id, _, _) in TEACHING_SOURCES {
        let n = cat
            .lines()
            .filter(|l| l.starts_with(&format!("{id}.")))
            .count();
        assert!(n >= 2, "system {id} has {n} images:\n{cat}");
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn committed_teaching_catalogue_is_up_to_date() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("www/examples/teaching/images.cat");
    let fresh = teaching_image_catalog().unwrap();
    if std::env::var_os("WSLAP_REGENERATE").is_some() {
        std::fs::write(&path, &fresh).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert_eq!(
        committed,
        fresh,
        "run with WSLAP_REGENERATE=1 to rewrite {}",
        path.display()
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_bad_file_names_its_line_and_keeps_what_was_loaded() {
    let mut s = teaching_session();
    let before = s.data.images.clone();
    let err = s
        .load_text(
            DataRole::Images,
            "bad.cat",
            "1.1 1.0 2.0 0.1 0.1 0 1.5\n1.2 x 2.0 0.1 0.1 0 1.5\n",
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("bad.cat") && err.contains("line 2"), "{err}");
    assert_eq!(s.data.images, before);
    let err = s
        .load_text(DataRole::Arcs, "arcs.json", "{\n  \"systems\": [\n   oops")
        .unwrap_err();
    assert!(err.to_string().contains("line 3"), "{err}");
    assert!(s.data.arcs.is_none());
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_bad_setting_is_refused_and_the_old_value_kept() {
    let mut s = Session::new();
    let err = s
        .set_field("reconstruct.grid.cells", json!(0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("cells"), "{err}");
    assert_eq!(s.settings.reconstruct.grid.cells, 32);
    assert!(s.set_field("z_lens", json!(-1.0)).is_err());
    assert!(s.set_field("no.such.field", json!(1)).is_err());
    assert!(s
        .set_field("reconstruct.constraints.mode", json!("sideways"))
        .is_err());
    s.set_field("reconstruct.constraints.mode", json!("point"))
        .unwrap();
    s.set_field("reconstruct.grid.width_arcsec", json!(80.0))
        .unwrap();
    s.set_field("reconstruct.grid.width_arcsec", json!(null))
        .unwrap();
    assert_eq!(s.settings.reconstruct.grid.width_arcsec, None);
    let err = s
        .set_field("reconstruct.members.c_prior_sigma", json!(-0.1))
        .unwrap_err()
        .to_string();
    assert!(err.contains("c_prior_sigma"), "{err}");
    assert_eq!(s.settings.reconstruct.members.c_prior_sigma, None);
    s.set_field("reconstruct.members.c_prior_sigma", json!(0.1))
        .unwrap();
    assert_eq!(s.settings.reconstruct.members.c_prior_sigma, Some(0.1));
    assert_eq!(
        s.settings.reconstruct.products.pixels,
        wslap::app::APP_MAP_PIXELS
    );
}

/// The "Solver" setting reaches the run: the accelerated gradient lowers the lens-equation
/// chi2 below QADP's in the same iterations, and summary.json names the method.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_solver_setting_chooses_the_method() {
    let chi2 = |s: &Session| {
        let r = s.result().unwrap().reconstruction.as_ref().unwrap();
        2.0 * wslap::solver::objective(&r.system.a, &r.system.b, &r.x) + r.system.theta_w_theta
    };
    let qadp = solved();
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
        !r.products.curves.tangential.is_empty(),
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
    assert_eq!(median, 0.5 * (offsets[(n - 1) / 2] + offsets[n / 2]));
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
    let fits = r.products.fits_files().unwrap();
    assert_eq!(fits.len(), 6);
    let header = String::from_utf8_lossy(&fits[0].1[..2880]).to_string();
    assert!(
        header.contains("NAXIS1  =                   64"),
        "{header}"
    );
}

/// The map draws the predicted images down to `|mu|` = [`SHOWN_MIN_MAGNIFICATION`]; the
/// demagnified central images below it stay in `sources.json`.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_map_leaves_out_the_demagnified_predicted_images() {
    let s = solved();
    let r = s.result().unwrap();
    let all: Vec<_> = r
        .reconstruction
        .iter()
        .flat_map(|rec| rec.sources.iter())
        .flat_map(|src| src.predicted.iter())
        .collect();
    let faint = all
        .iter()
        .filter(|p| p.magnification.abs() < SHOWN_MIN_MAGNIFICATION)
        .count();
    let shown = r.predicted();
    println!("{} predicted, {faint} fainter than the limit", all.len());
    assert!(faint > 0, "the teaching lens predicts no demagnified image");
    assert_eq!(shown.len(), all.len() - faint);
    for p in &shown {
        let image = all.iter().find(|a| a.position_arcsec == *p).unwrap();
        assert!(image.magnification.abs() >= SHOWN_MIN_MAGNIFICATION);
    }
    let sources: serde_json::Value = serde_json::from_str(&r.sources_json().unwrap()).unwrap();
    let listed: usize = sources
        .as_array()
        .unwrap()
        .iter()
        .map(|src| src["predicted"].as_array().unwrap().len())
        .sum();
    assert_eq!(listed, all.len());
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_higher_source_redshift_redraws_a_larger_einstein_radius_without_solving() {
    let mut s = solved();
    let x = s
        .result()
        .unwrap()
        .reconstruction
        .as_ref()
        .unwrap()
        .x
        .clone();
    let r2 = s.result().unwrap().products.curves.einstein_radius_arcsec;
    s.set_z_source(6.0).unwrap();
    let p = &s.result().unwrap().products;
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
    assert_eq!(s.result().unwrap().reconstruction.as_ref().unwrap().x, x);
    assert!(
        s.set_z_source(0.1).is_err(),
        "a source in front of the lens"
    );
    assert_eq!(s.settings.reconstruct.products.z_source, 6.0);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_project_reopens_with_the_maps_rebuilt_from_x() {
    let s = solved();
    let text = s.project_json().unwrap();
    let mut t = Session::new();
    let report = t.open_project(&text, "p.json").unwrap();
    assert_eq!(report.result, "restored", "{}", report.message);
    let (a, b) = (s.result().unwrap(), t.result().unwrap());
    // serde_json's float parsing may differ from the written value in the last bit.
    const KAPPA_RTOL: f64 = 1e-9;
    let worst = a
        .products
        .maps
        .kappa
        .data
        .iter()
        .zip(&b.products.maps.kappa.data)
        .map(|(p, q)| (p - q).abs() / p.abs().max(1e-12))
        .fold(0.0, f64::max);
    assert!(worst <= KAPPA_RTOL, "kappa differs by {worst:e} (relative)");
    assert_eq!(t.settings, s.settings);
    assert_eq!(t.data.images, s.data.images);
    // A broken project changes nothing.
    let err = t
        .open_project("{\"format\": \"other\", \"version\": 1}", "q.json")
        .unwrap_err();
    assert!(err.to_string().contains("q.json"), "{err}");
    assert!(t.result.is_some());
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
    let forward = s.result().unwrap().products.curves.einstein_radius_arcsec;
    let fits = s.result().unwrap().products.fits_files().unwrap();
    let file = |name: &str| fits.iter().find(|(n, _)| *n == name).unwrap().1.clone();
    s.load_fits(0, "x.fits", &file("x-arcsec-deflect.fits"))
        .unwrap();
    s.load_fits(1, "y.fits", &file("y-arcsec-deflect.fits"))
        .unwrap();
    assert!(s.load_fits(1, "bad.fits", b"SIMPLE = nonsense").is_err());
    s.run(RunKind::Lookup, &mut |_| Control::Continue).unwrap();
    let lookup = s.result().unwrap().products.curves.einstein_radius_arcsec;
    common::assert_abs("Einstein radius", lookup, forward, RADIUS_ATOL_ARCSEC);
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn committed_teaching_model_is_the_demo_model() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("www/examples/teaching/model.json");
    let committed = std::fs::read_to_string(&path).unwrap();
    assert_eq!(committed.trim(), TEACHING_MODEL_JSON.trim());
}

/// A forward run of the teaching model on a 64-pixel, 64-arcsec map, and its deflection FITS.
fn forward_session() -> (Session, Vec<u8>, Vec<u8>) {
    let mut s = Session::new();
    s.load_text(DataRole::Model, "model.json", TEACHING_MODEL_JSON)
        .unwrap();
    for (path, value) in [
        ("z_lens", json!(0.3)),
        ("reconstruct.products.size_arcsec", json!(64.0)),
        ("reconstruct.products.pixels", json!(64)),
    ] {
        s.set_field(path, value).unwrap();
    }
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    let fits = s.result().unwrap().products.fits_files().unwrap();
    let file = |name: &str| fits.iter().find(|(n, _)| *n == name).unwrap().1.clone();
    let (x, y) = (file("x-arcsec-deflect.fits"), file("y-arcsec-deflect.fits"));
    (s, x, y)
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
    assert_eq!(b.products.curves.z_source, 3.0);
    assert_eq!(
        a.products.curves.einstein_radius_arcsec,
        b.products.curves.einstein_radius_arcsec
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

/// Two systems of 3 x 3 arc pixels (0.5 arcsec) on the teaching model's map.
const TWO_ARCS_JSON: &str = r#"{"systems": [
  {"id": "a", "z": 2.0, "pixels": [[-10.5, 9.5], [-10, 9.5], [-9.5, 9.5], [-10.5, 10], [-10, 10],
     [-9.5, 10], [-10.5, 10.5], [-10, 10.5], [-9.5, 10.5]]},
  {"id": "b", "z": 2.0, "pixels": [[9.5, -10.5], [10, -10.5], [10.5, -10.5], [9.5, -10], [10, -10],
     [10.5, -10], [9.5, -9.5], [10, -9.5], [10.5, -9.5]]}
]}"#;

fn rgb(pm: &tiny_skia::Pixmap, (x, y): (f32, f32)) -> [u8; 3] {
    let p = pm.pixel(x as u32, y as u32).expect("inside the figure");
    [p.red(), p.green(), p.blue()]
}

/// Where a predicted image lands on an observed one (a good fit), the observed image's marker
/// (the data) is drawn on top: the centre of every observed marker has the observed colour.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn observed_images_are_drawn_over_the_predicted_ones() {
    let s = solved();
    let r = s.result().unwrap();
    let opts = ViewOptions {
        show_members: false,
        ..ViewOptions::default()
    };
    let frame = s.kappa_frame(&opts).unwrap();
    let map = tiny_skia::Pixmap::decode_png(&s.kappa_view(&opts).unwrap().png).unwrap();
    let predicted: Vec<_> = r
        .predicted()
        .iter()
        .map(|&p| frame.arcsec_to_screen(p))
        .collect();
    let mut covered = 0;
    for &o in &r.marks.observed {
        let at = frame.arcsec_to_screen(o);
        // A predicted cross within 2 screen pixels also covers this centre.
        if predicted
            .iter()
            .any(|p| (p.0 - at.0).hypot(p.1 - at.1) < 2.0)
        {
            covered += 1;
        }
        assert_eq!(rgb(&map, at), OBSERVED_RGB, "observed image at {o}");
    }
    assert_ne!(OBSERVED_RGB, PREDICTED_RGB);
    // The test means something only if some predicted images do land on observed ones.
    println!(
        "{covered} of {} observed images have a predicted image on them",
        r.marks.observed.len()
    );
    assert!(covered > 0);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arc_pixels_are_drawn_in_system_colours_and_the_legend_leaves_the_map_free() {
    /// Channel tolerance of the alpha blend (rounding of 8-bit colours).
    const BLEND_TOL: i32 = 3;
    let (mut s, _, _) = forward_session();
    s.load_text(DataRole::Arcs, "arcs.json", TWO_ARCS_JSON)
        .unwrap();
    s.run(RunKind::Forward, &mut |_| Control::Continue).unwrap();
    let r = s.result().unwrap();
    assert_eq!(r.marks.arcs.len(), 2);
    assert_eq!(r.marks.arc_pixel_mas, 500);
    let below = ViewOptions::default();
    let bare = ViewOptions {
        show_observed: false,
        ..below
    };
    let frame = s.kappa_frame(&below).unwrap();
    let decode = |o: &ViewOptions| tiny_skia::Pixmap::decode_png(&s.kappa_view(o).unwrap().png);
    let (with, without) = (decode(&below).unwrap(), decode(&bare).unwrap());
    assert_eq!((with.width(), with.height()), (frame.width, frame.height));
    for (k, centre) in [(0, DVec2::new(-10.0, 10.0)), (1, DVec2::new(10.0, -10.0))] {
        let at = frame.arcsec_to_screen(centre);
        let (fg, bg) = (system_rgb(k), rgb(&without, at));
        let got = rgb(&with, at);
        for c in 0..3 {
            let want = PIXEL_ALPHA * fg[c] as f32 + (1.0 - PIXEL_ALPHA) * bg[c] as f32;
            assert!(
                (got[c] as i32 - want.round() as i32).abs() <= BLEND_TOL,
                "system {k}: {got:?} is not {fg:?} at {PIXEL_ALPHA} over {bg:?}"
            );
        }
    }
    assert_ne!(system_rgb(0), system_rgb(1));
    // Legend under the map: the map is the same with or without it except for the arcs;
    // its text (dark pixels) lies below the x-axis title, and the figure is taller than
    // the one with the legend in the map's corner.
    let inside = ViewOptions {
        legend: LegendPlace::InsideTopRight,
        ..below
    };
    let corner = decode(&inside).unwrap();
    let (x0, y0) = (frame.map_left + frame.map_side * 0.75, frame.map_top + 4.0);
    let differs = |a: &tiny_skia::Pixmap, b: &tiny_skia::Pixmap| {
        (0..20).any(|k| {
            rgb(a, (x0 + 2.0 * k as f32, y0 + 6.0)) != rgb(b, (x0 + 2.0 * k as f32, y0 + 6.0))
        })
    };
    assert!(differs(&corner, &without), "the corner legend is not drawn");
    let bare_inside = decode(&ViewOptions {
        show_observed: false,
        ..inside
    })
    .unwrap();
    assert!(corner.height() < with.height());
    assert!(bare_inside.height() < without.height());
    assert!(!differs(&with, &without), "the legend covers the map");
    let legend_rows = (frame.map_top + frame.map_side + 40.0) as u32..with.height();
    let dark = legend_rows
        .flat_map(|y| (0..with.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| rgb(&with, (x as f32, y as f32)).iter().all(|&c| c < 60))
        .count();
    assert!(
        dark > 50,
        "no legend text under the map ({dark} dark pixels)"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn the_data_view_follows_the_show_toggles() {
    let mut s = Session::new();
    s.load_text(DataRole::Arcs, "arcs.json", TWO_ARCS_JSON)
        .unwrap();
    s.load_text(
        DataRole::Members,
        "members.cat",
        "#REFERENCE 3 0 0\n1 0.0 0.0 1 1 0 17.0 1\n2 -8.0 -6.0 1 1 0 18.5 1\n",
    )
    .unwrap();
    let all = ViewOptions::default();
    let png = |o: &ViewOptions| s.data_view(o).unwrap().png;
    let no_members = ViewOptions {
        show_members: false,
        ..all
    };
    let no_images = ViewOptions {
        show_observed: false,
        ..all
    };
    let nothing = ViewOptions {
        show_members: false,
        show_observed: false,
        ..all
    };
    let views = [png(&all), png(&no_members), png(&no_images), png(&nothing)];
    for (i, a) in views.iter().enumerate() {
        for b in &views[i + 1..] {
            assert_ne!(a, b, "two settings of the toggles draw the same view");
        }
    }
    // Same figure size: toggling does not move the field.
    let size = |p: &[u8]| {
        let pm = tiny_skia::Pixmap::decode_png(p).unwrap();
        (pm.width(), pm.height())
    };
    assert_eq!(size(&views[0][..]).0, size(&views[3][..]).0);
}
