//! Cosmology and the simple mass components (SIS, point mass, Gaussian) against astropy and
//! lenstronomy, analytic limits, consistency loops.

use crate::common;

use common::{assert_abs, assert_rel};
use glam::DVec2;
use serde::Deserialize;
use wslap::ComponentSpec;
use wslap::{
    gaussian_unit_deflection, gaussian_unit_hessian, sis_theta_e_arcsec, Gaussian, PointMass,
    ProfileError, Sis,
};
use wslap::{Cosmology, CosmologyError, LensPlane, MassComponent};

/// Distances, densities and ratios vs astropy ([method §1] asks for 1e-6).
///
/// [method §1]: wslap::method#1-frames-and-units
const COSMOLOGY_RTOL: f64 = 1e-6;
/// Fields vs lenstronomy: the same formulae with the same constants (errors reached ~3e-14);
/// 1e-9 leaves room for distance differences far below COSMOLOGY_RTOL, and is tighter than the
/// 1e-5 the project asks for.
const PROFILE_RTOL: f64 = 1e-9;
/// Absolute floor, as a fraction of the largest Hessian entry at the sample: lenstronomy's
/// kappa is `(f_xx + f_yy)/2`, so in a Gaussian's tail it is rounding noise of that size
/// (it is even negative there); and a point mass's kappa is exactly 0.
const PROFILE_ATOL_OF_HESSIAN: f64 = 1e-12;
/// Finite-difference step in arcsec: truncation ~ (h/r)^2 ~ 1e-6 at r = 1 arcsec, rounding
/// ~ 1e-16 |alpha| / h.
const FD_STEP_ARCSEC: f64 = 1e-3;
/// Finite-difference checks, relative to the size of the Hessian at the point.
const FD_RTOL: f64 = 1e-5;
/// Closed form vs series in the Gaussian on both sides of the switch, and analytic limits.
const GAUSSIAN_LIMIT_RTOL: f64 = 1e-12;
/// Enclosed mass by Simpson integration of kappa (4000 intervals) vs the analytic value.
const ENCLOSED_MASS_RTOL: f64 = 1e-9;

fn plane(z_lens: f64) -> LensPlane {
    LensPlane::new(Cosmology::default(), z_lens).expect("valid lens plane")
}

// ---------------------------------------------------------------- cosmology vs astropy

#[derive(Deserialize)]
struct CosmologyRef {
    cosmologies: Vec<CosmologyCase>,
}
#[derive(Deserialize)]
struct CosmologyCase {
    h0: f64,
    omega_m: f64,
    distances: Vec<DistanceRow>,
    pairs: Vec<PairRow>,
}
#[derive(Deserialize)]
struct DistanceRow {
    z: f64,
    d_a_mpc: f64,
    rho_crit_msun_per_mpc3: f64,
    sigma_cr_ref_msun_per_arcsec2: f64,
}
#[derive(Deserialize)]
struct PairRow {
    z1: f64,
    z2: f64,
    d_a_z1z2_mpc: f64,
    distance_ratio: f64,
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn cosmology_matches_astropy() {
    let reference: CosmologyRef =
        serde_json::from_str(include_str!("../data/cosmology.json")).expect("cosmology.json");
    assert_eq!(reference.cosmologies.len(), 2);
    for case in &reference.cosmologies {
        let cosmo = Cosmology::new(case.h0, case.omega_m).expect("valid cosmology");
        for row in &case.distances {
            let what = |q: &str| format!("H0={} Om={} z={}: {q}", case.h0, case.omega_m, row.z);
            let d_a = cosmo.angular_diameter_distance_mpc(row.z);
            assert_rel(&what("D_A"), d_a, row.d_a_mpc, COSMOLOGY_RTOL);
            let rho = cosmo.critical_density_msun_per_mpc3(row.z);
            assert_rel(
                &what("rho_crit"),
                rho,
                row.rho_crit_msun_per_mpc3,
                COSMOLOGY_RTOL,
            );
            let lp = LensPlane::new(cosmo, row.z).expect("lens plane");
            let sigma = lp.sigma_cr_ref_msun_per_arcsec2;
            assert_rel(
                &what("Sigma_cr_ref"),
                sigma,
                row.sigma_cr_ref_msun_per_arcsec2,
                COSMOLOGY_RTOL,
            );
            assert_rel(
                &what("lens-plane D_l"),
                lp.d_l_mpc,
                row.d_a_mpc,
                COSMOLOGY_RTOL,
            );
        }
        for row in &case.pairs {
            let what = |q: &str| format!("H0={} z1={} z2={}: {q}", case.h0, row.z1, row.z2);
            let d12 = cosmo.angular_diameter_distance_z1z2_mpc(row.z1, row.z2);
            assert_rel(&what("D_A(z1,z2)"), d12, row.d_a_z1z2_mpc, COSMOLOGY_RTOL);
            let ratio = LensPlane::new(cosmo, row.z1)
                .and_then(|lp| lp.distance_ratio(row.z2))
                .expect("source behind lens");
            assert_rel(&what("D_ls/D_s"), ratio, row.distance_ratio, COSMOLOGY_RTOL);
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn lens_plane_rejects_bad_redshifts() {
    let lp = plane(0.3);
    for z_s in [0.3, 0.1, -1.0, f64::NAN, f64::INFINITY] {
        match lp.distance_ratio(z_s) {
            Err(CosmologyError::SourceNotBehindLens { z_lens, .. }) => assert_eq!(z_lens, 0.3),
            other => panic!("z_s = {z_s}: expected SourceNotBehindLens, got {other:?}"),
        }
    }
    let err = lp.distance_ratio(0.2).unwrap_err().to_string();
    assert!(
        err.contains("z_s = 0.2") && err.contains("z_l = 0.3"),
        "{err}"
    );
    for z_l in [0.0, -0.5, f64::NAN] {
        match LensPlane::new(Cosmology::default(), z_l) {
            Err(CosmologyError::BadFieldValue(e)) => assert_eq!(e.field, "cosmology.z_lens"),
            other => panic!("z_l = {z_l}: expected BadFieldValue, got {other:?}"),
        }
    }
}

// ---------------------------------------------------------------- profiles vs lenstronomy

#[derive(Deserialize)]
struct ProfilesRef {
    z_lens: f64,
    cosmology: Cosmology,
    cases: Vec<ProfileCase>,
}
#[derive(Deserialize)]
struct ProfileCase {
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

#[track_caller]
fn assert_close(what: &str, a: f64, b: f64, hessian_scale: f64) {
    assert!(
        (a - b).abs() <= PROFILE_RTOL * b.abs() + PROFILE_ATOL_OF_HESSIAN * hessian_scale,
        "{what}: got {a:e}, lenstronomy {b:e}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn simple_profiles_match_lenstronomy() {
    let reference: ProfilesRef =
        serde_json::from_str(include_str!("../data/simple_profiles.json")).expect("profiles json");
    let lp = LensPlane::new(reference.cosmology, reference.z_lens).expect("lens plane");
    assert_eq!(reference.cases.len(), 5);
    for case in &reference.cases {
        let component = case.component.build(&lp).expect("valid component");
        for s in &case.samples {
            let p = DVec2::new(s.x, s.y);
            let what = |q: &str| format!("{} at ({}, {}): {q}", case.component.kind(), s.x, s.y);
            let scale = s.hessian.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert_close(&what("kappa"), component.kappa(p), s.kappa, scale);
            let a = component.deflection(p);
            assert_close(&what("alpha_x"), a.x, s.alpha[0], scale);
            assert_close(&what("alpha_y"), a.y, s.alpha[1], scale);
            let h = component.hessian(p);
            for k in 0..3 {
                let name = ["psi_xx", "psi_xy", "psi_yy"][k];
                assert_close(&what(name), h[k], s.hessian[k], scale);
            }
        }
    }
}

// ---------------------------------------------------------------- analytic checks

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sis_einstein_radius() {
    // 4 pi (1000 / 299792.458)^2 rad = 28.8399 arcsec.
    assert_rel(
        "theta_E(1000 km/s)",
        sis_theta_e_arcsec(1000.0),
        28.8399,
        1e-5,
    );
    let sis = Sis::new(DVec2::new(3.0, -2.0), 1000.0).expect("valid SIS");
    let te = sis.theta_e_ref_arcsec();
    let on_ring = DVec2::new(3.0, -2.0) + DVec2::from_angle(0.7) * te;
    assert_rel(
        "|alpha| on the Einstein ring",
        sis.deflection(on_ring).length(),
        te,
        1e-12,
    );
    assert_rel("kappa on the Einstein ring", sis.kappa(on_ring), 0.5, 1e-12);
    assert_eq!(sis.deflection(DVec2::new(3.0, -2.0)), DVec2::ZERO);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn point_mass_einstein_radius() {
    let lp = plane(0.3);
    let m = 1.0e12;
    let pm = PointMass::new(DVec2::ZERO, m, &lp).expect("valid point mass");
    let expected = (8.14385e-9 * m / lp.d_l_mpc).sqrt(); // wslap::method §1
    assert_rel("point theta_E", pm.theta_e_ref_arcsec(), expected, 1e-5);
    let p = DVec2::new(0.0, pm.theta_e_ref_arcsec());
    assert_rel(
        "|alpha| at theta_E",
        pm.deflection(p).length(),
        pm.theta_e_ref_arcsec(),
        1e-12,
    );
    assert_eq!(pm.kappa(p), 0.0);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn gaussian_centre_limit() {
    let lp = plane(0.3);
    let (m, s) = (1.0e13, 2.5);
    let g = Gaussian::new(DVec2::new(1.0, 1.0), m, s, &lp).expect("valid Gaussian");
    let kappa0 = m / (2.0 * std::f64::consts::PI * s * s * lp.sigma_cr_ref_msun_per_arcsec2);
    assert_rel("kappa(0)", g.kappa(DVec2::new(1.0, 1.0)), kappa0, 1e-9);
    assert_eq!(g.deflection(DVec2::new(1.0, 1.0)), DVec2::ZERO);
    let h = g.hessian(DVec2::new(1.0, 1.0));
    assert_rel("psi_xx(0)", h[0], kappa0, 1e-9);
    assert_rel("psi_yy(0)", h[2], kappa0, 1e-9);
    assert_eq!(h[1], 0.0);
    // Just off centre, alpha -> b^2 d / (2 s^2) = kappa(0) d.
    let d = DVec2::new(3e-7, -4e-7);
    let a = g.deflection(DVec2::new(1.0, 1.0) + d);
    assert_rel("alpha_x near 0", a.x, kappa0 * d.x, 1e-9);
    assert_rel("alpha_y near 0", a.y, kappa0 * d.y, 1e-9);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn gaussian_series_and_closed_form_agree() {
    // u = r^2/(2 s^2) = 0.5 is where the code switches from series to closed form.
    let s = 1.0;
    let (r_lo, r_hi) = ((1.0f64 - 1e-9).sqrt(), (1.0f64 + 1e-9).sqrt());
    let (a_lo, _) = gaussian_unit_deflection(r_lo, 0.0, s);
    let (a_hi, _) = gaussian_unit_deflection(r_hi, 0.0, s);
    // alpha(r) itself changes by ~ 1e-9 relative across the gap.
    assert_rel("alpha across the switch", a_lo, a_hi, 2e-9);
    let h_lo = gaussian_unit_hessian(0.6 * r_lo, 0.8 * r_lo, s);
    let h_hi = gaussian_unit_hessian(0.6 * r_hi, 0.8 * r_hi, s);
    for k in 0..3 {
        assert_rel("hessian across the switch", h_lo[k], h_hi[k], 5e-9);
    }
    // Trace of the unit Hessian equals 2 kappa = e^-u / s^2 everywhere, incl. the series range.
    for r in [0.0, 1e-5, 0.1, 0.7, 0.99, 1.01, 2.0, 6.0] {
        let h = gaussian_unit_hessian(r * 0.6, r * 0.8, s);
        let two_kappa = (-r * r / (2.0 * s * s)).exp() / (s * s);
        // Relative to the terms summed: far out, 2 kappa is a tiny difference of O(1/r^2) terms.
        let tol = GAUSSIAN_LIMIT_RTOL * (h[0].abs() + h[1].abs() + h[2].abs());
        assert_abs(&format!("trace at r = {r}"), h[0] + h[2], two_kappa, tol);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn gaussian_enclosed_mass() {
    let lp = plane(0.4);
    let (m, s) = (5.0e12, 3.0);
    let g = Gaussian::new(DVec2::ZERO, m, s, &lp).expect("valid Gaussian");
    let sigma_cr = lp.sigma_cr_ref_msun_per_arcsec2;
    for radius in [1.0, 3.0, 7.5, 40.0] {
        let analytic = m * -(-radius * radius / (2.0 * s * s)).exp_m1();
        // Simpson on 2 pi r kappa(r) Sigma_cr.
        let n = 4000;
        let h = radius / n as f64;
        let f = |r: f64| 2.0 * std::f64::consts::PI * r * g.kappa(DVec2::new(r, 0.0)) * sigma_cr;
        let inner: f64 = (1..n)
            .map(|k| f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        let integral = (f(0.0) + f(radius) + inner) * h / 3.0;
        assert_rel(
            &format!("M(<{radius}) by integration"),
            integral,
            analytic,
            ENCLOSED_MASS_RTOL,
        );
        // Gauss's law: |alpha(R)| R = M(<R) / (pi Sigma_cr).
        let from_alpha = g.deflection(DVec2::new(0.0, radius)).length()
            * radius
            * std::f64::consts::PI
            * sigma_cr;
        assert_rel(
            &format!("M(<{radius}) from alpha"),
            from_alpha,
            analytic,
            1e-9,
        );
    }
}

// ---------------------------------------------------------------- consistency loops

/// Every simple component, off-centre, with a name for messages.
fn simple_components() -> Vec<(&'static str, Box<dyn MassComponent>)> {
    let lp = plane(0.3);
    let c = DVec2::new(0.4, -0.3);
    vec![
        ("sis", Box::new(Sis::new(c, 600.0).expect("sis"))),
        (
            "point",
            Box::new(PointMass::new(c, 3.0e12, &lp).expect("point")),
        ),
        (
            "gaussian wide",
            Box::new(Gaussian::new(c, 2.0e13, 6.0, &lp).expect("gaussian")),
        ),
        (
            "gaussian narrow",
            Box::new(Gaussian::new(c, 1.0e12, 0.8, &lp).expect("gaussian")),
        ),
    ]
}

/// Sample points between 1 and 40 arcsec from the centres, from a fixed-seed LCG.
fn sample_points(n: usize) -> Vec<DVec2> {
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let r = 1.0 + 39.0 * next() * next();
            DVec2::new(0.4, -0.3) + DVec2::from_angle(std::f64::consts::TAU * next()) * r
        })
        .collect()
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn hessian_divergence_and_curl_match_finite_differences() {
    let h = FD_STEP_ARCSEC;
    let (ex, ey) = (DVec2::new(h, 0.0), DVec2::new(0.0, h));
    for (name, comp) in simple_components() {
        for p in sample_points(40) {
            let dx = (comp.deflection(p + ex) - comp.deflection(p - ex)) / (2.0 * h);
            let dy = (comp.deflection(p + ey) - comp.deflection(p - ey)) / (2.0 * h);
            let hes = comp.hessian(p);
            let scale = hes[0].abs() + hes[1].abs() + hes[2].abs();
            let tol = FD_RTOL * scale;
            let what = |q: &str| format!("{name} at ({:.3}, {:.3}): {q}", p.x, p.y);
            assert_abs(
                &what("div alpha = 2 kappa"),
                dx.x + dy.y,
                2.0 * comp.kappa(p),
                tol,
            );
            assert_abs(&what("curl alpha = 0"), dy.x - dx.y, 0.0, tol);
            assert_abs(&what("psi_xx"), hes[0], dx.x, tol);
            assert_abs(&what("psi_xy"), hes[1], 0.5 * (dy.x + dx.y), tol);
            assert_abs(&what("psi_yy"), hes[2], dy.y, tol);
            assert_abs(
                &what("trace = 2 kappa"),
                hes[0] + hes[2],
                2.0 * comp.kappa(p),
                1e-12 * scale,
            );
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn fields_finite_everywhere_including_centres() {
    let comps = simple_components();
    let centre = DVec2::new(0.4, -0.3);
    let mut points: Vec<DVec2> = (0..=40)
        .flat_map(|j| {
            (0..=40).map(move |i| centre + DVec2::new(i as f64 - 20.0, j as f64 - 20.0) * 0.5)
        })
        .collect();
    assert!(points.contains(&centre), "the grid must contain the centre");
    for r in [0.0, 1e-300, 1e-12, 1e-9, 1e-7, 1e6, 1e300] {
        points.push(centre + DVec2::new(r, 0.0));
        points.push(centre + DVec2::new(0.6, -0.8) * r);
    }
    for (name, comp) in &comps {
        for &p in &points {
            let (k, a, h) = (comp.kappa(p), comp.deflection(p), comp.hessian(p));
            let finite = k.is_finite() && a.is_finite() && h.iter().all(|v| v.is_finite());
            assert!(finite, "{name} at {p}: kappa {k}, alpha {a}, hessian {h:?}");
        }
        assert_eq!(
            comp.deflection(centre),
            DVec2::ZERO,
            "{name}: alpha at the centre"
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_profile_parameters_are_named() {
    let lp = plane(0.3);
    let field = |r: Result<(), ProfileError>| r.expect_err("must be rejected");
    let e = field(Sis::new(DVec2::ZERO, -3.0).map(|_| ()));
    assert_eq!(
        e.to_string(),
        "sis: sigma_v = -3 is not allowed (a velocity dispersion must be above 0 and at most 1e4 km/s; the richest clusters have about 1500)"
    );
    let e = field(PointMass::new(DVec2::ZERO, f64::INFINITY, &lp).map(|_| ()));
    assert_eq!(e.field(), "mass");
    let e = field(Gaussian::new(DVec2::ZERO, 1e12, 0.0, &lp).map(|_| ()));
    assert_eq!(
        e.to_string(),
        "gaussian: sigma = 0 is not allowed (must be positive and finite)"
    );
    let e = field(Gaussian::new(DVec2::ZERO, f64::NAN, 1.0, &lp).map(|_| ()));
    assert_eq!(e.field(), "mass");
    let e = field(Gaussian::new(DVec2::new(0.0, f64::NAN), 1e12, 1.0, &lp).map(|_| ()));
    assert_eq!(e.field(), "y");
    let e = field(Sis::from_theta_e(DVec2::ZERO, 0.0).map(|_| ()));
    assert_eq!(e.field(), "theta_e");
}
