//! The model file (`src/model.rs`): the documented example, defaults, and one error per bad input.

use crate::common;

use common::assert_rel;
use glam::DVec2;
use wslap::{ComponentSpec, ModelError, ModelFile};
use wslap::{Cosmology, LensPlane, MassComponent};
use wslap::{Gaussian, Sis};

fn plane(z_lens: f64) -> LensPlane {
    LensPlane::new(Cosmology::default(), z_lens).expect("valid lens plane")
}

// ---------------------------------------------------------------- the model file

/// The documented example of `src/model.rs`.
const EXAMPLE_MODEL: &str = r#"{"cosmology": {"h0": 70.0, "omega_m": 0.3}, "z_lens": 0.3, "reference": {"ra": 3.586, "dec": -30.4},
 "components": [
   {"type": "nfw", "x": 0.0, "y": 0.0, "m200": 1.0e15, "c200": 5.0, "q": 0.8, "pa": 30.0},
   {"type": "tnfw", "x": 20.0, "y": 3.0, "m200": 1.0e12, "c200": 10.0, "r_trunc": 15.0},
   {"type": "sis", "x": 10.0, "y": -5.0, "sigma_v": 250.0},
   {"type": "point", "x": 0.0, "y": 0.0, "mass": 1.0e12},
   {"type": "gaussian", "x": 0.0, "y": 0.0, "mass": 1.0e13, "sigma": 5.0}]}"#;

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn example_model_parses_builds_and_round_trips() {
    let model = ModelFile::from_json_str(EXAMPLE_MODEL, "example.json").expect("example parses");
    assert_eq!(model.components.len(), 5);
    let reference = model.reference.expect("reference given");
    assert_eq!((reference.ra_deg, reference.dec_deg), (3.586, -30.4));
    assert_eq!(model.components[0].kind(), "nfw");
    let lens = model.build_lens().expect("example builds");
    assert_eq!(lens.components.len(), 5);
    let p = DVec2::new(7.0, -11.0);
    let k = lens.kappa(p);
    assert!(k.is_finite() && k > 0.0, "kappa {k}");
    let again = ModelFile::from_json_str(&model.to_json_string(), "example.json").expect("re-read");
    assert_eq!(again, model);
    assert_eq!(again.build_lens().expect("builds").kappa(p), k);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn model_defaults_and_simple_lens() {
    let text = r#"{"z_lens": 0.3, "components": [
        {"type": "sis", "x": 10.0, "y": -5.0, "sigma_v": 250.0},
        {"type": "gaussian", "x": 1, "y": 2, "mass": 1e13, "sigma": 5}]}"#;
    let model = ModelFile::from_json_str(text, "m.json").expect("parses");
    assert_eq!(model.cosmology, Cosmology::default());
    assert_eq!(model.reference, None);
    let lens = model.build_lens().expect("builds");
    let lp = plane(0.3);
    let sis = Sis::new(DVec2::new(10.0, -5.0), 250.0).expect("sis");
    let gauss = Gaussian::new(DVec2::new(1.0, 2.0), 1e13, 5.0, &lp).expect("gaussian");
    let p = DVec2::new(-4.0, 6.5);
    assert_eq!(lens.deflection(p), sis.deflection(p) + gauss.deflection(p));
    assert_eq!(lens.kappa(p), sis.kappa(p) + gauss.kappa(p));
    let q_default = r#"{"z_lens": 0.3, "components": [{"type": "nfw", "x": 0, "y": 0, "m200": 1e14, "c200": 4}]}"#;
    let q_default: ModelFile = serde_json::from_str(q_default).expect("shape parses");
    match q_default.components[0] {
        ComponentSpec::Nfw { q, pa, .. } => assert_eq!((q, pa), (1.0, 0.0)),
        other => panic!("expected nfw, got {other:?}"),
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn model_nfw_axis_ratio_selects_the_elliptical_profile() {
    let nfw = |q: f64| {
        let text = format!(
            r#"{{"z_lens": 0.3, "components": [{{"type": "nfw", "x": 0, "y": 0, "m200": 1e15, "c200": 5, "q": {q}}}]}}"#
        );
        let model = ModelFile::from_json_str(&text, "nfw.json").expect("valid nfw");
        model.build_lens().expect("builds")
    };
    let (on_x, on_y) = (DVec2::new(10.0, 0.0), DVec2::new(0.0, 10.0));
    let round = nfw(1.0);
    assert_rel(
        "q = 1 is round",
        round.kappa(on_x),
        round.kappa(on_y),
        1e-12,
    );
    // pa = 0: the major axis is +x, so kappa is higher at (10, 0) than at (0, 10).
    let flat = nfw(0.8);
    assert!(
        flat.kappa(on_x) > 1.05 * flat.kappa(on_y),
        "q = 0.8 must be elliptical"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn demo_models_parse() {
    for (name, text) in [
        ("cluster", wslap::CLUSTER_MODEL_JSON),
        ("teaching", wslap::TEACHING_MODEL_JSON),
    ] {
        let model = ModelFile::from_json_str(text, name).expect("demo model is valid");
        assert!(
            !model.build_lens().expect("builds").components.is_empty(),
            "{name}"
        );
    }
}

/// Parses `text` and returns the error message, which must exist.
fn model_error(text: &str) -> (ModelError, String) {
    let err = ModelFile::from_json_str(text, "model.json").expect_err("must be rejected");
    let message = err.to_string();
    (err, message)
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn model_errors_name_component_and_field() {
    let sis = r#"{"type": "sis", "x": 0, "y": 0, "sigma_v": 200}"#;
    let with = |c: &str| format!("{{\"z_lens\": 0.3,\n \"components\": [{sis},\n  {c}]}}");

    let (_, m) = model_error(&with(r#"{"type": "sis", "x": 0, "y": 0, "sigma_v": -3}"#));
    let expected =
        "model.json: component 1 (sis): sigma_v = -3 is not allowed (a velocity dispersion must be above 0 and at most 1e4 km/s; the richest clusters have about 1500)";
    assert_eq!(m, expected);

    let (e, m) = model_error(&with(r#"{"type": "point", "x": 0, "y": 0, "mass": -1e12}"#));
    assert!(
        matches!(
            e,
            ModelError::BadComponent {
                index: 1,
                kind: "point",
                field: "mass",
                ..
            }
        ),
        "{m}"
    );

    let (e, m) = model_error(&with(
        r#"{"type": "nfw", "x": 0, "y": 0, "m200": 1e14, "c200": 4, "q": 1.2}"#,
    ));
    assert!(
        matches!(
            e,
            ModelError::BadComponent {
                index: 1,
                kind: "nfw",
                field: "q",
                ..
            }
        ),
        "{m}"
    );
    assert!(m.contains("q = 1.2"), "{m}");

    let (e, m) = model_error(&with(
        r#"{"type": "nfw", "x": 0, "y": 0, "m200": 0, "c200": 4}"#,
    ));
    assert!(
        matches!(
            e,
            ModelError::BadComponent {
                index: 1,
                kind: "nfw",
                field: "m200",
                ..
            }
        ),
        "{m}"
    );
    let tnfw = r#"{"type": "tnfw", "x": 0, "y": 0, "m200": 1e12, "c200": 9, "r_trunc": -2}"#;
    let (e, m) = model_error(&with(tnfw));
    assert!(
        matches!(
            e,
            ModelError::BadComponent {
                index: 1,
                kind: "tnfw",
                field: "r_trunc",
                ..
            }
        ),
        "{m}"
    );

    let (e, m) = model_error(&with(r#"{"type": "sis", "x": 0, "y": 0, "sigmav": 200}"#));
    assert!(
        matches!(
            e,
            ModelError::ComponentSyntax {
                index: 1,
                line: 3,
                ..
            }
        ),
        "{m}"
    );
    assert!(
        m.starts_with("model.json: line 3, column ") && m.contains("component 1 (sis)"),
        "{m}"
    );
    assert!(m.contains("unknown field 'sigmav'"), "{m}");

    let (e, m) = model_error(&with(r#"{"type": "epl", "x": 0, "y": 0}"#));
    assert!(
        matches!(e, ModelError::ComponentSyntax { index: 1, .. }),
        "{m}"
    );
    assert!(
        m.contains("component 1 (epl)") && m.contains("must be one of") && m.contains("(got epl)"),
        "{m}"
    );

    let (e, m) = model_error(&with(
        r#"{"type": "gaussian", "x": 0, "y": 0, "mass": 1e12}"#,
    ));
    assert!(
        matches!(e, ModelError::ComponentSyntax { index: 1, .. }),
        "{m}"
    );
    assert!(m.contains("the field 'sigma' is missing"), "{m}");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn model_errors_at_top_level() {
    let sis = r#"{"type": "sis", "x": 0, "y": 0, "sigma_v": 200}"#;

    let (e, m) = model_error(&format!("{{\"components\": [{sis}]}}"));
    assert!(matches!(e, ModelError::Syntax { line: 1, .. }), "{m}");
    assert!(m.contains("the field 'z_lens' is missing"), "{m}");

    let (_, m) = model_error(&format!(
        "{{\"z_lens\": 0.3, \"z_source\": 2, \"components\": [{sis}]}}"
    ));
    assert!(m.contains("unknown field 'z_source'"), "{m}");

    let (e, m) = model_error(&format!("{{\"z_lens\": 0.3,\n\"components\": [{sis},]\n}}"));
    assert!(matches!(e, ModelError::Syntax { line: 2, .. }), "{m}");
    assert!(m.starts_with("model.json: line 2, column "), "{m}");

    let (e, m) = model_error("{\"z_lens\": 0.3, \"components\": [\n");
    assert!(matches!(e, ModelError::Syntax { line: 2, .. }), "{m}");

    let (e, m) = model_error("{\"z_lens\": 0.3, \"components\": []}");
    assert!(matches!(e, ModelError::NoComponents { .. }), "{m}");

    let (e, m) = model_error(&format!("{{\"z_lens\": 0, \"components\": [{sis}]}}"));
    assert!(
        matches!(e, ModelError::Cosmology { .. }) && m.contains("z_lens = 0"),
        "{m}"
    );

    let bad_h0 =
        format!("{{\"cosmology\": {{\"h0\": -70}}, \"z_lens\": 0.3, \"components\": [{sis}]}}");
    let (_, m) = model_error(&bad_h0);
    assert!(
        m.starts_with("model.json: ") && m.contains("h0 = -70"),
        "{m}"
    );

    let bad_dec = format!(
        "{{\"reference\": {{\"ra\": 10, \"dec\": 95}}, \"z_lens\": 0.3, \"components\": [{sis}]}}"
    );
    let (e, m) = model_error(&bad_dec);
    assert!(
        matches!(e, ModelError::BadReference { field: "dec", .. }),
        "{m}"
    );

    // NaN cannot be written in JSON, but a model built in code can hold one.
    let mut model =
        ModelFile::from_json_str(&format!("{{\"z_lens\": 0.3, \"components\": [{sis}]}}"), "")
            .expect("valid");
    model.components[0] = ComponentSpec::Sis {
        x: f64::NAN,
        y: 0.0,
        sigma_v: 200.0,
    };
    let m = model.validate().expect_err("NaN rejected").to_string();
    assert!(m.starts_with("model: component 0 (sis): x = NaN"), "{m}");
}

/// A velocity dispersion far past any cluster's is refused where it is written, not met as
/// NaN pixels in the maps (1e200 overflowed `sigma^2`).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn velocity_dispersions_are_bounded() {
    for (kind, extra) in [("sis", ""), ("sie", ", \"q\": 0.8, \"pa\": 0")] {
        let text = format!(
            "{{\"z_lens\": 0.3, \"components\": [{{\"type\": \"{kind}\", \"x\": 0, \"y\": 0, \
             \"sigma_v\": 1e200{extra}}}]}}"
        );
        let (_, m) = model_error(&text);
        assert!(
            m.contains("sigma_v = 1e200 is not allowed") && m.contains("at most 1e4 km/s"),
            "{m}"
        );
    }
    let ok = "{\"z_lens\": 0.3, \"components\": [{\"type\": \"sis\", \"x\": 0, \"y\": 0, \
              \"sigma_v\": 1500}]}";
    assert!(wslap::ModelFile::from_json_str(ok, "model.json").is_ok());
}
