//! The playground's "Observe" then "Invert": the first lesson's scene observed, its files
//! loaded into the app as the browser does, reconstructed with the suggested settings; the
//! reconstruction's Einstein radius against the truth's.

use wslap::app::{DataRole, RunKind, Session, ViewOptions};
use wslap::playground::{observe, ObserveOptions, Playground, Scene};
use wslap::Control;

/// The target: the Einstein radius within 10% of the truth's.
const EINSTEIN_RADIUS_RTOL: f64 = 0.10;
const FIRST_INVERSION: &str = include_str!("../../www/playground/scenes/first-inversion.json");

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn observing_then_inverting_the_first_lesson_recovers_its_einstein_radius() {
    let scene = Scene::from_json_str(FIRST_INVERSION).unwrap();
    let obs = observe(&scene, &ObserveOptions::default()).unwrap();
    assert!(obs.notes.is_empty(), "{:?}", obs.notes);
    let mut s = Session::new();
    s.set_field("z_lens", obs.z_lens.into()).unwrap();
    for (path, value) in &obs.settings {
        s.set_field(path, value.clone()).unwrap();
    }
    let files = [
        (DataRole::Arcs, "arcs.json", obs.arcs_json.as_deref()),
        (DataRole::Members, "members.cat", obs.members_cat.as_deref()),
        (DataRole::Model, "model.json", Some(obs.model_json.as_str())),
    ];
    for (role, name, text) in files {
        s.load_text(role, name, text.expect(name)).unwrap();
    }
    s.run(RunKind::Reconstruct, &mut |_| Control::Continue)
        .unwrap();
    let r = s.result().unwrap();
    let z_s = r.products().curves.z_source;
    let ours = r.products().curves.einstein_radius_arcsec;
    let pg = Playground::new(scene).unwrap();
    let frame = pg.frame(256);
    let plane = frame.curves.iter().find(|c| c.z == z_s).expect("the plane");
    let truth = plane.einstein_radius_arcsec;
    eprintln!("first inversion: Einstein radius at z_s = {z_s}: truth {truth:.2}, reconstruction {ours:.2}");
    assert!(
        (ours / truth - 1.0).abs() < EINSTEIN_RADIUS_RTOL,
        "{ours} vs {truth}"
    );
    // The comparison with the truth draws; without a model there is nothing to compare.
    let opts = ViewOptions {
        model_is_truth: true,
        ..ViewOptions::default()
    };
    let png = s.compare_view(&opts).unwrap();
    assert!(png.png.starts_with(b"\x89PNG"));
    // "Download figure" at 2x: the three panels drawn twice as large (parts rounded one by one).
    let size = |png: &[u8]| {
        let pm = tiny_skia::Pixmap::decode_png(png).expect("a PNG");
        (pm.width() as i64, pm.height() as i64)
    };
    let twice = s
        .compare_view(&ViewOptions {
            figure_scale: 2.0,
            ..opts
        })
        .unwrap();
    let ((w1, h1), (w2, h2)) = (size(&png.png), size(&twice.png));
    assert!(
        (w2 - 2 * w1).abs() <= 8 && (h2 - 2 * h1).abs() <= 8,
        "compare at 2x: {w2} x {h2}, at 1x {w1} x {h1}"
    );
    s.data.clear(DataRole::Model);
    let e = s.compare_view(&opts).unwrap_err().to_string();
    assert!(e.contains("model"), "{e}");
}
