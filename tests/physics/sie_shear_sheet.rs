//! The singular isothermal ellipsoid, external shear and mass sheet against lenstronomy
//! (`tests/data/sie_shear_sheet.json`, from `tests/data/sie_shear_sheet_reference.py`), and the
//! SIE's analytic Hessian against finite differences of its own deflection.

use glam::DVec2;
use serde::Deserialize;
use wslap::{ComponentSpec, Cosmology, LensPlane, MassComponent, Sie, Sis};

use crate::common::assert_abs;

/// Deflection: lenstronomy's SIE has a core of 1e-10 arcsec and rounds `q = 1` to `1 - 1e-8`;
/// both move its values by less than this relative amount.
const FIELD_RTOL: f64 = 1e-7;
/// Hessian and kappa (its half trace): lenstronomy differentiates its SIE deflection with a
/// step of 1e-10 arcsec, so they carry an absolute error near `1e-16 |alpha| / 1e-10`
/// (`|alpha|` in arcsec); this is that times 20. The analytic Hessian is checked to 1e-6
/// against our own central differences below.
const HESSIAN_ATOL_PER_ALPHA: f64 = 2e-5;

#[derive(Deserialize)]
struct Reference {
    z_lens: f64,
    cosmology: Cosmology,
    cases: Vec<Case>,
}
#[derive(Deserialize)]
struct Case {
    component: ComponentSpec,
    samples: Vec<Sample>,
}
#[derive(Deserialize)]
struct Sample {
    x: f64,
    y: f64,
    kappa: f64,
    alpha: [f64; 2],
    hessian: [f64; 3],
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sie_shear_sheet_match_lenstronomy() {
    let reference: Reference =
        serde_json::from_str(include_str!("../data/sie_shear_sheet.json")).expect("json");
    let lp = LensPlane::new(reference.cosmology, reference.z_lens).expect("lens plane");
    assert_eq!(reference.cases.len(), 6);
    for case in &reference.cases {
        let c = case.component.build(&lp).expect("valid component");
        for s in &case.samples {
            let p = DVec2::new(s.x, s.y);
            let what = |q: &str| format!("{} at ({}, {}): {q}", case.component.kind(), s.x, s.y);
            let alpha_scale = s.alpha[0].hypot(s.alpha[1]);
            let tol = HESSIAN_ATOL_PER_ALPHA * alpha_scale + 1e-12;
            assert_abs(&what("kappa"), c.kappa(p), s.kappa, tol);
            let a = c.deflection(p);
            assert_abs(&what("alpha_x"), a.x, s.alpha[0], FIELD_RTOL * alpha_scale);
            assert_abs(&what("alpha_y"), a.y, s.alpha[1], FIELD_RTOL * alpha_scale);
            let h = c.hessian(p);
            for (i, name) in ["psi_xx", "psi_xy", "psi_yy"].iter().enumerate() {
                assert_abs(&what(name), h[i], s.hessian[i], tol);
            }
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sie_hessian_is_the_derivative_of_its_deflection() {
    let sie = Sie::new(DVec2::new(1.0, -2.0), 700.0, 0.55, 37.0).expect("valid SIE");
    let step = 1e-5;
    for p in [
        DVec2::new(4.0, 1.0),
        DVec2::new(-3.0, -7.5),
        DVec2::new(1.2, -1.9),
    ] {
        let dx = (sie.deflection(p + DVec2::X * step) - sie.deflection(p - DVec2::X * step))
            / (2.0 * step);
        let dy = (sie.deflection(p + DVec2::Y * step) - sie.deflection(p - DVec2::Y * step))
            / (2.0 * step);
        let h = sie.hessian(p);
        let tol = 1e-6 * h.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert_abs("psi_xx", h[0], dx.x, tol);
        assert_abs("psi_xy", h[1], dy.x, tol);
        assert_abs("psi_yx", h[1], dx.y, tol);
        assert_abs("psi_yy", h[2], dy.y, tol);
        assert_abs("kappa = trace/2", sie.kappa(p), 0.5 * (h[0] + h[2]), 1e-12);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn round_sie_is_the_sis_and_the_centre_is_finite() {
    let c = DVec2::new(3.0, 4.0);
    let sie = Sie::new(c, 500.0, 1.0, 12.0).expect("valid SIE");
    let sis = Sis::new(c, 500.0).expect("valid SIS");
    let p = DVec2::new(-1.0, 2.5);
    assert_abs("kappa", sie.kappa(p), sis.kappa(p), 1e-14);
    assert_abs(
        "alpha",
        (sie.deflection(p) - sis.deflection(p)).length(),
        0.0,
        1e-13,
    );
    let q = Sie::new(c, 500.0, 0.3, 12.0).expect("valid SIE");
    assert_eq!(q.deflection(c), DVec2::ZERO);
    assert!(q.kappa(c).is_finite() && q.hessian(c).iter().all(|v| v.is_finite()));
    for bad in [0.0, 0.005, 1.2, f64::NAN] {
        assert!(Sie::new(c, 500.0, bad, 0.0).is_err(), "q = {bad}");
    }
}
