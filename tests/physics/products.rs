//! Map products ([method §6]): lens maps, magnification, critical curves, caustics,
//! Einstein radius and radial profiles, checked on analytic lenses.
//!
//! [method §6]: wslap::method#6-products

use crate::common;

use common::{assert_abs, assert_rel};
use glam::DVec2;
use wslap::Sis;
use wslap::{critical_curves, einstein_radius_for, zero_contours, Polyline};
use wslap::{radial_profile, rect_disc_area, RadialBins, RadialError};
use wslap::{Cosmology, LensPlane, Map, MapGeometry, MassComponent};
use wslap::{LensMaps, MapsError, MAGNIFICATION_CLAMP};

/// Test lens: softened isothermal with an elliptical potential,
/// `psi = b sqrt(s^2 + (1 - e) x^2 + (1 + e) y^2)` about `center`; `kappa(centre) = b / s`.
#[derive(Debug)]
struct SoftEllipse {
    center: DVec2,
    b: f64,
    s: f64,
    e: f64,
}

impl SoftEllipse {
    /// `(w, qx, qy)` with `w = sqrt(s^2 + qx x^2 + qy y^2)`, `qx = 1 - e`, `qy = 1 + e`.
    fn w(&self, d: DVec2) -> (f64, f64, f64) {
        let (qx, qy) = (1.0 - self.e, 1.0 + self.e);
        (
            (self.s * self.s + qx * d.x * d.x + qy * d.y * d.y).sqrt(),
            qx,
            qy,
        )
    }
}

impl MassComponent for SoftEllipse {
    fn kappa(&self, p: DVec2) -> f64 {
        let h = self.hessian(p);
        0.5 * (h[0] + h[2])
    }
    fn deflection(&self, p: DVec2) -> DVec2 {
        let d = p - self.center;
        let (w, qx, qy) = self.w(d);
        DVec2::new(qx * d.x, qy * d.y) * (self.b / w)
    }
    fn hessian(&self, p: DVec2) -> [f64; 3] {
        let d = p - self.center;
        let (w, qx, qy) = self.w(d);
        let w3 = w * w * w;
        [
            self.b * (qx / w - qx * qx * d.x * d.x / w3),
            -self.b * qx * qy * d.x * d.y / w3,
            self.b * (qy / w - qy * qy * d.y * d.y / w3),
        ]
    }
}

/// SIS Einstein radius used throughout, arcsec.
const THETA_E_ARCSEC: f64 = 20.0;
/// Test maps: 128 pixels of 0.5 arcsec, centred on the origin.
const TEST_MAP: MapGeometry = MapGeometry {
    pixels: 128,
    size_arcsec: 64.0,
    center: DVec2::ZERO,
};
/// The brief's accuracy for curve positions and the Einstein radius: 0.1 pixel (arcsec).
const CURVE_TOL_ARCSEC: f64 = 0.1 * 0.5;

fn sis() -> Sis {
    Sis::from_theta_e(DVec2::ZERO, THETA_E_ARCSEC).expect("valid SIS")
}

fn ellipse() -> SoftEllipse {
    SoftEllipse {
        center: DVec2::new(1.3, -0.7),
        b: THETA_E_ARCSEC,
        s: 3.0,
        e: 0.2,
    }
}

/// Every closed polyline: at least 3 points, consecutive points distinct, each step (including
/// last -> first) within one cell (at most a pixel diagonal).
#[track_caller]
fn assert_closed_clean(curve: &Polyline, pixel_arcsec: f64) {
    assert!(curve.len() >= 3, "closed curve of {} points", curve.len());
    let step_max = pixel_arcsec * std::f64::consts::SQRT_2 * (1.0 + 1e-9);
    for k in 0..curve.len() {
        let (a, b) = (curve[k], curve[(k + 1) % curve.len()]);
        let d = a.distance(b);
        assert!(d > 0.0, "duplicate consecutive point {a} at index {k}");
        assert!(
            d <= step_max,
            "step {d} arcsec from index {k} is longer than a cell diagonal"
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sis_tangential_curve_is_one_circle_of_radius_f_theta_e() {
    let lens = sis();
    let maps = LensMaps::from_lens(&lens, TEST_MAP);
    for f in [1.0, 0.6] {
        let curves = critical_curves(&maps, f, 2.0, Some(&lens));
        assert_eq!(curves.tangential.len(), 1, "f = {f}: one tangential loop");
        assert!(
            curves.radial.is_empty(),
            "f = {f}: an SIS has no radial curve"
        );
        let loop_ = &curves.tangential[0];
        assert_closed_clean(loop_, TEST_MAP.pixel_arcsec());
        for p in loop_ {
            assert_abs(
                "SIS critical-curve radius",
                p.length(),
                f * THETA_E_ARCSEC,
                CURVE_TOL_ARCSEC,
            );
        }
        let r_e = curves.einstein_radius_arcsec;
        assert_abs(
            "SIS Einstein radius",
            r_e,
            f * THETA_E_ARCSEC,
            CURVE_TOL_ARCSEC,
        );
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sis_caustic_is_the_centre() {
    let lens = sis();
    let maps = LensMaps::from_lens(&lens, TEST_MAP);
    for exact in [true, false] {
        let lens_opt: Option<&dyn MassComponent> = if exact { Some(&lens) } else { None };
        let curves = critical_curves(&maps, 0.6, 2.0, lens_opt);
        let caustic = &curves.caustics.tangential[0];
        assert_eq!(
            caustic.len(),
            curves.tangential[0].len(),
            "one caustic vertex per curve vertex"
        );
        for beta in caustic {
            assert_abs(
                "SIS caustic |beta| (arcsec)",
                beta.length(),
                0.0,
                CURVE_TOL_ARCSEC,
            );
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn einstein_radius_for_uses_the_distance_ratio() {
    let plane = LensPlane::new(Cosmology::default(), 0.3).expect("plane");
    let f = plane.distance_ratio(2.0).expect("f");
    let r_e = einstein_radius_for(&sis(), TEST_MAP, &plane, 2.0).expect("radius");
    assert_abs(
        "SIS Einstein radius for z_s = 2",
        r_e,
        f * THETA_E_ARCSEC,
        CURVE_TOL_ARCSEC,
    );
    assert!(
        einstein_radius_for(&sis(), TEST_MAP, &plane, 0.2).is_err(),
        "source in front of lens"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn cored_ellipse_has_a_radial_curve_inside_the_tangential_one() {
    let lens = ellipse();
    let maps = LensMaps::from_lens(&lens, TEST_MAP);
    let curves = critical_curves(&maps, 1.0, 2.0, None);
    assert_eq!(curves.tangential.len(), 1, "one tangential loop");
    assert_eq!(curves.radial.len(), 1, "one radial loop");
    let (tan, rad) = (&curves.tangential[0], &curves.radial[0]);
    assert_closed_clean(tan, TEST_MAP.pixel_arcsec());
    assert_closed_clean(rad, TEST_MAP.pixel_arcsec());
    let dist = |c: &Polyline| {
        c.iter()
            .map(|p| p.distance(lens.center))
            .collect::<Vec<_>>()
    };
    let tan_min = dist(tan).into_iter().fold(f64::INFINITY, f64::min);
    let rad_max = dist(rad).into_iter().fold(0.0, f64::max);
    assert!(
        rad_max < tan_min,
        "radial curve (max r {rad_max}) inside tangential (min r {tan_min})"
    );
    // The tangential curve is elongated: the potential is steeper along y (e > 0).
    let x_extent = tan
        .iter()
        .map(|p| (p.x - lens.center.x).abs())
        .fold(0.0, f64::max);
    let y_extent = tan
        .iter()
        .map(|p| (p.y - lens.center.y).abs())
        .fold(0.0, f64::max);
    assert!(
        x_extent > y_extent * 1.05,
        "x extent {x_extent} vs y extent {y_extent}"
    );
    // Every vertex lies on lambda_t = 0 of the exact lens to a small fraction of its range.
    for p in tan {
        let [xx, xy, yy] = lens.hessian(*p);
        let lambda_t = 1.0 - (0.5 * (xx + yy) + (0.25 * (xx - yy).powi(2) + xy * xy).sqrt());
        assert_abs("lambda_t on the tangential curve", lambda_t, 0.0, 1e-3);
    }
    assert!(
        curves.einstein_radius_arcsec > tan_min,
        "Einstein radius beyond the curve's minimum"
    );
}

/// Maps with `gamma = 0` and `kappa = 1 - lambda`, so that `lambda_t = lambda_r = lambda` at f = 1.
fn maps_with_lambda(geometry: MapGeometry, lambda: impl Fn(DVec2) -> f64) -> LensMaps {
    let zero = Map::from_fn(geometry, |_| 0.0);
    LensMaps {
        kappa: Map::from_fn(geometry, |p| 1.0 - lambda(p)),
        gamma1: zero.clone(),
        gamma2: zero.clone(),
        alpha_x: zero.clone(),
        alpha_y: zero,
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn einstein_area_counts_holes_and_skips_open_curves() {
    // lambda_t < 0 only in the ring 5" < r < 10": the inner loop is a hole, so the area is
    // pi (10^2 - 5^2) and the effective radius sqrt(75)" (to the brief's 0.1 pixel).
    let ring = maps_with_lambda(TEST_MAP, |p| {
        (p.length() - 5.0) * (p.length() - 10.0) / 25.0
    });
    let curves = critical_curves(&ring, 1.0, 2.0, None);
    assert_eq!(curves.tangential.len(), 2, "outer and inner loop");
    let r_e = curves.einstein_radius_arcsec;
    assert_abs("ring Einstein radius", r_e, 75f64.sqrt(), CURVE_TOL_ARCSEC);
    // A disc of lambda_t < 0 cut by the map border is open and does not count; a whole disc
    // elsewhere on the map does.
    let cut = maps_with_lambda(TEST_MAP, |p| {
        let inside_cut = p.distance(DVec2::new(30.0, 0.0)) - 6.0;
        let inside_whole = p.distance(DVec2::new(-15.0, 0.0)) - 4.0;
        inside_cut.min(inside_whole)
    });
    let curves = critical_curves(&cut, 1.0, 2.0, None);
    assert_eq!(curves.tangential.len(), 2, "one open curve and one loop");
    assert_abs(
        "radius of the closed disc only",
        curves.einstein_radius_arcsec,
        4.0,
        CURVE_TOL_ARCSEC,
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn from_deflection_recovers_kappa_and_shear() {
    // Central differences on 0.5" pixels of a lens with a 3" core: the error (h^2/6 times the
    // third derivative of alpha) relative to the local kappa + |gamma| is below 0.5% beyond 5"
    // from the centre (measured: 0.34%); the first-order one-sided
    // differences on the map border stay within 1% there (measured: 0.61%).
    const INTERIOR_RTOL: f64 = 5e-3;
    const BORDER_RTOL: f64 = 1e-2;
    let lens = ellipse();
    let exact = LensMaps::from_lens(&lens, TEST_MAP);
    let fd = LensMaps::from_deflection(exact.alpha_x.clone(), exact.alpha_y.clone()).expect("maps");
    let n = TEST_MAP.pixels;
    let mut checked = 0;
    for j in 0..n {
        for i in 0..n {
            if TEST_MAP.pixel_center(i, j).distance(lens.center) < 5.0 {
                continue;
            }
            let border = i == 0 || j == 0 || i == n - 1 || j == n - 1;
            let rtol = if border { BORDER_RTOL } else { INTERIOR_RTOL };
            let (k, g1, g2) = (
                exact.kappa.at(i, j),
                exact.gamma1.at(i, j),
                exact.gamma2.at(i, j),
            );
            let atol = rtol * (k.abs() + g1.hypot(g2));
            assert_abs("kappa", fd.kappa.at(i, j), k, atol);
            assert_abs("gamma1", fd.gamma1.at(i, j), g1, atol);
            assert_abs("gamma2", fd.gamma2.at(i, j), g2, atol);
            checked += 1;
        }
    }
    assert!(checked > n * n / 2, "checked {checked} pixels");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn from_deflection_rejects_bad_maps() {
    let g = MapGeometry::centered(10.0, 4);
    let zero = Map::from_fn(g, |_| 0.0);
    let other = Map::from_fn(MapGeometry::centered(12.0, 4), |_| 0.0);
    let err = LensMaps::from_deflection(zero.clone(), other).unwrap_err();
    assert!(matches!(err, MapsError::GeometryMismatch { .. }), "{err}");
    let mut inf = zero.clone();
    inf.data[2 * 4 + 3] = f64::INFINITY;
    let err = LensMaps::from_deflection(zero.clone(), inf).unwrap_err();
    assert_eq!(
        err.to_string(),
        "alpha_y: pixel (column 3, row 2) holds inf, which is not finite"
    );
    // NaN is a pixel without data (tests/files/lenstool.rs), in both maps; none at all is
    // refused.
    let mut nan = zero.clone();
    nan.data[2 * 4 + 3] = f64::NAN;
    let maps = LensMaps::from_deflection(zero.clone(), nan.clone()).unwrap();
    assert!(maps.alpha_x.at(3, 2).is_nan() && maps.kappa.at(3, 2).is_nan());
    // (3, 3) on the top edge has no other neighbour along y: no derivative there either.
    let blank_at = |k: usize| maps.kappa.data[k].is_nan();
    let blanks: Vec<usize> = (0..16).filter(|&k| blank_at(k)).collect();
    assert_eq!(blanks, [2 * 4 + 3, 3 * 4 + 3]);
    let blank = Map::from_fn(g, |_| f64::NAN);
    let err = LensMaps::from_deflection(blank, nan).unwrap_err();
    assert_eq!(err, MapsError::NoData);
    let tiny = Map::from_fn(MapGeometry::centered(1.0, 1), |_| 0.0);
    let err = LensMaps::from_deflection(tiny.clone(), tiny).unwrap_err();
    assert!(
        matches!(err, MapsError::TooSmall { pixels: 1, .. }),
        "{err}"
    );
    let flat = Map::from_fn(MapGeometry::centered(0.0, 4), |_| 0.0);
    let err = LensMaps::from_deflection(flat.clone(), flat).unwrap_err();
    assert_eq!(err, MapsError::BadSize { size_arcsec: 0.0 });
    let mut short = zero.clone();
    short.data.pop();
    let err = LensMaps::from_deflection(short.clone(), short).unwrap_err();
    assert!(
        matches!(
            err,
            MapsError::WrongLength {
                expected: 16,
                found: 15,
                ..
            }
        ),
        "{err}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn magnification_matches_sis_and_is_finite() {
    // Pixel-centre values from the exact Hessian: only rounding differs.
    const RTOL: f64 = 1e-9;
    let maps = LensMaps::from_lens(&sis(), TEST_MAP);
    let mu = maps.magnification(1.0);
    assert!(mu
        .data
        .iter()
        .all(|v| v.is_finite() && v.abs() <= MAGNIFICATION_CLAMP));
    for (i, j) in [(120, 64), (64, 127), (10, 20), (110, 110)] {
        let r = TEST_MAP.pixel_center(i, j).length();
        assert!(r > THETA_E_ARCSEC, "test point outside the Einstein ring");
        assert_rel(
            "SIS magnification",
            mu.at(i, j),
            1.0 / (1.0 - THETA_E_ARCSEC / r),
            RTOL,
        );
    }
    // Exactly on a critical line det A = 0: the clamp, not infinity.
    let g = MapGeometry::centered(2.0, 2);
    let half = Map::from_fn(g, |_| 0.5);
    let zero = Map::from_fn(g, |_| 0.0);
    let on_line = LensMaps {
        kappa: half.clone(),
        gamma1: half,
        gamma2: zero.clone(),
        alpha_x: zero.clone(),
        alpha_y: zero,
    };
    assert_eq!(
        on_line.magnification(1.0).data,
        vec![MAGNIFICATION_CLAMP; 4]
    );
    let (lt, lr) = on_line.eigen_maps(1.0);
    assert_eq!(
        (lt.at(0, 0), lr.at(0, 0)),
        (0.0, 1.0),
        "lambda_t = 1 - k - g, lambda_r = 1 - k + g"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn contours_through_pixel_centres_saddles_and_borders() {
    // 1" pixels, centres at half-integers.
    let g = MapGeometry::centered(20.0, 20);
    // A straight line through a column of pixel centres: one open curve, no duplicate points,
    // both ends on the border, positive side (x > 0.5) on the left, i.e. running down (-y).
    let line = zero_contours(&Map::from_fn(g, |p| p.x - 0.5));
    assert_eq!(line.len(), 1);
    assert!(!line[0].closed);
    let pts = &line[0].points;
    assert!(
        pts.windows(2).all(|w| w[0] != w[1]),
        "duplicate consecutive points"
    );
    assert!(
        pts.iter().all(|p| (p.x - 0.5).abs() < 1e-12),
        "vertices on x = 0.5"
    );
    assert_eq!(
        (pts[0].y, pts[pts.len() - 1].y),
        (9.5, -9.5),
        "from top to bottom border"
    );
    // x y + c: a saddle at the centre; either sign of c gives two disjoint open branches.
    for c in [0.01, -0.01] {
        let branches = zero_contours(&Map::from_fn(g, |p| p.x * p.y + c));
        assert_eq!(branches.len(), 2, "c = {c}");
        for b in &branches {
            assert!(!b.closed && b.points.iter().all(|p| (p.x * p.y + c).abs() < 0.3));
        }
    }
    // A circle about a pixel centre touches 4 pixel centres exactly.
    let ring = zero_contours(&Map::from_fn(g, |p| (p - DVec2::splat(0.5)).length() - 4.0));
    assert_eq!(ring.len(), 1);
    assert!(ring[0].closed);
    assert_closed_clean(&ring[0].points, g.pixel_arcsec());
    // Too small or malformed maps have no contours (and do not panic).
    assert!(zero_contours(&Map::from_fn(MapGeometry::centered(1.0, 1), |_| -1.0)).is_empty());
}

fn plane() -> LensPlane {
    LensPlane::new(Cosmology::default(), 0.3).expect("plane")
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn radial_profile_of_a_uniform_sheet_is_exact() {
    // Exact pixel/annulus overlaps: only rounding error.
    const RTOL: f64 = 1e-10;
    let plane = plane();
    let sheet = Map::from_fn(TEST_MAP, |_| 0.3);
    let center = DVec2::new(2.3, -1.1);
    let bins = RadialBins::Log {
        r_min_arcsec: 0.1,
        r_max_arcsec: 25.0,
        count: 17,
    };
    let prof = radial_profile(&sheet, center, &bins, &plane).expect("profile");
    assert_eq!((prof.kappa.len(), prof.r_edges_arcsec.len()), (17, 18));
    for k in &prof.kappa {
        assert_rel("sheet kappa", *k, 0.3, RTOL);
    }
    for (r, m) in prof.r_edges_arcsec.iter().zip(&prof.enclosed_mass_msun) {
        let expected = 0.3 * std::f64::consts::PI * r * r * plane.sigma_cr_ref_msun_per_arcsec2;
        assert_rel("sheet enclosed mass", *m, expected, RTOL);
    }
    assert_rel(
        "log-bin centre",
        prof.r_arcsec[0],
        (0.1f64 * prof.r_edges_arcsec[1]).sqrt(),
        1e-12,
    );
    assert_rel(
        "pixel inside a disc",
        rect_disc_area(-1.0, 1.0, -1.0, 1.0, 1.0),
        4.0 - (4.0 - std::f64::consts::PI),
        1e-12,
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn radial_profile_of_an_sis() {
    // kappa is sampled at pixel centres (0.5"), which under-samples the central cusp.
    // The annulus mean of theta_E/(2r) matches theta_E/(r1 + r2) to 0.5% beyond 3".
    const KAPPA_RTOL: f64 = 5e-3;
    // The enclosed mass pi theta_E R Sigma_cr misses a fixed amount from the central pixels
    // (measured: pi theta_E Sigma_cr x 0.129", i.e. the mass of a 0.26-pixel-wide ring):
    // allow 0.3 pixel (0.15") of equivalent radius, and 0.1% on annulus masses beyond 5".
    const CUSP_DEFICIT_ARCSEC: f64 = 0.15;
    const ANNULUS_RTOL: f64 = 1e-3;
    let plane = plane();
    let maps = LensMaps::from_lens(&sis(), TEST_MAP);
    let bins = RadialBins::Linear {
        r_min_arcsec: 0.0,
        r_max_arcsec: 30.0,
        count: 30,
    };
    let prof = radial_profile(&maps.kappa, DVec2::ZERO, &bins, &plane).expect("profile");
    let e = &prof.r_edges_arcsec;
    for (k, kappa) in prof.kappa.iter().enumerate().filter(|(k, _)| e[*k] >= 3.0) {
        assert_rel(
            "SIS annulus kappa",
            *kappa,
            THETA_E_ARCSEC / (e[k] + e[k + 1]),
            KAPPA_RTOL,
        );
    }
    let unit = std::f64::consts::PI * THETA_E_ARCSEC * plane.sigma_cr_ref_msun_per_arcsec2;
    let m = &prof.enclosed_mass_msun;
    for k in 1..e.len() {
        assert_abs(
            "SIS M(<R) / (pi theta_E Sigma_cr)",
            m[k] / unit,
            e[k],
            CUSP_DEFICIT_ARCSEC,
        );
        if e[k - 1] >= 5.0 {
            assert_rel(
                "SIS annulus mass",
                m[k] - m[k - 1],
                unit * (e[k] - e[k - 1]),
                ANNULUS_RTOL,
            );
        }
    }
    let json = serde_json::to_string(&prof).expect("serialise");
    assert!(json.contains("enclosed_mass_msun"));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn radial_profile_rejects_bad_requests() {
    let plane = plane();
    let sheet = Map::from_fn(TEST_MAP, |_| 1.0);
    let bins = RadialBins::Linear {
        r_min_arcsec: 0.0,
        r_max_arcsec: 40.0,
        count: 4,
    };
    let err = radial_profile(&sheet, DVec2::ZERO, &bins, &plane).unwrap_err();
    assert_eq!(
        err,
        RadialError::BeyondMap {
            r_max_arcsec: 40.0,
            limit_arcsec: 32.0
        }
    );
    let log0 = RadialBins::Log {
        r_min_arcsec: 0.0,
        r_max_arcsec: 10.0,
        count: 4,
    };
    assert!(matches!(
        log0.edges_arcsec(),
        Err(RadialError::BadFieldValue(ref e)) if e.field == "radial_bins.r_min_arcsec"
    ));
    let unsorted = RadialBins::Edges(vec![0.0, 2.0, 1.0]);
    assert!(matches!(
        unsorted.edges_arcsec(),
        Err(RadialError::BadFieldValue(ref e)) if e.field == "radial_bins.edges"
    ));
    let mut holed = sheet.clone();
    holed.data[64 * 128 + 64] = f64::INFINITY;
    let bins = RadialBins::Edges(vec![1.0, 2.0]);
    let err = radial_profile(&holed, DVec2::ZERO, &bins, &plane).unwrap_err();
    assert_eq!(
        err,
        RadialError::NotFinite {
            i: 64,
            j: 64,
            value: f64::INFINITY
        }
    );
}

/// The lens plane of the Einstein-radius tests (z = 0.3).
fn einstein_plane() -> LensPlane {
    LensPlane::new(Cosmology::default(), 0.3).expect("plane")
}

/// Products of `lens` on [`einstein_plane`] (sources at z = 2 by default) on a square map of
/// side `size_arcsec` and `pixels` per side, centred on the origin.
fn products_at_z2(lens: &dyn MassComponent, size_arcsec: f64, pixels: usize) -> wslap::Products {
    let opts = wslap::ProductOptions {
        size_arcsec,
        pixels,
        ..wslap::ProductOptions::default()
    };
    wslap::Products::from_lens(lens, einstein_plane(), None, &opts).expect("products")
}

/// When the tangential curve leaves the products' map, the Einstein radius is measured on a
/// wider map (and said so); when it leaves every map tried, the summary says it is a lower
/// bound. Before, such a lens reported 0.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn an_einstein_curve_larger_than_the_map_is_measured_on_a_wider_one() {
    use wslap::EINSTEIN_MAP_WIDENING;
    let r_true = einstein_plane().distance_ratio(2.0).expect("f") * THETA_E_ARCSEC;
    let products_of = |lens: &dyn MassComponent, size: f64| products_at_z2(lens, size, 128);
    let products = |size_arcsec: f64| products_of(&sis(), size_arcsec);
    // The map holds the circle: measured on it.
    let inside = products(3.0 * r_true);
    assert_eq!(inside.einstein_radius_map_arcsec, Some(3.0 * r_true));
    assert_abs(
        "radius, map holds it",
        inside.curves.einstein_radius_arcsec,
        r_true,
        0.05,
    );
    // The map is narrower than the circle: measured on the first wider map that holds it.
    let narrow = products(1.5 * r_true);
    assert!(narrow.curves.tangential_leaves_map);
    let side = narrow
        .einstein_radius_map_arcsec
        .expect("a wider map holds the curve");
    assert_abs(
        "wider map",
        side,
        EINSTEIN_MAP_WIDENING[0] * 1.5 * r_true,
        1e-9,
    );
    let wide_pixel = side / 128.0;
    assert_abs(
        "radius on the wider map",
        narrow.curves.einstein_radius_arcsec,
        r_true,
        0.1 * wide_pixel,
    );
    assert!(narrow
        .summary()
        .einstein_radius_text()
        .contains("measured on a"));
    // No map tried holds it: a lower bound, said so.
    let tiny = products(0.4 * r_true);
    assert_eq!(tiny.einstein_radius_map_arcsec, None);
    let text = tiny.summary().einstein_radius_text();
    assert!(text.starts_with("at least"), "{text}");
    // No tangential curve at all (SGAS J1152's catalogue at z_s = 2): not "0.00 arcsec".
    let faint = Sis::from_theta_e(DVec2::ZERO, 1e-3).expect("faint SIS");
    let none = products_of(&wslap::Lens::new(vec![Box::new(faint)]), 3.0 * r_true).summary();
    assert_eq!(none.tangential_curves, 0);
    let text = none.einstein_radius_text();
    assert!(
        text.starts_with("none (no tangential critical curve"),
        "{text}"
    );
    // A small lens cut by the border of a map that holds the main curve: its few pixels do
    // not make the main curve "leave" the map.
    let size = 3.0 * r_true;
    let small = Sis::from_theta_e(DVec2::new(0.5 * size, 0.0), 1.0).expect("small SIS");
    let lens = wslap::Lens::new(vec![Box::new(sis()), Box::new(small)]);
    let with_small = products_of(&lens, size);
    assert!(!with_small.curves.tangential_leaves_map);
    assert_eq!(with_small.einstein_radius_map_arcsec, Some(size));
    // The main curve leaves through a narrow gap: the circle crosses the top row of pixel
    // centres along 3 pixels (0.6% of the border, under TANGENTIAL_BORDER_SHARE), yet the
    // open curve bounds nearly the whole disc, so the radius is measured on the wider map.
    let pixel = size / 128.0;
    let top_row = 0.5 * size - 0.5 * pixel;
    let half_chord = 1.5 * pixel;
    let centre_y = top_row + half_chord * half_chord / (2.0 * r_true) - r_true;
    let gap = Sis::from_theta_e(DVec2::new(0.0, centre_y), THETA_E_ARCSEC).expect("SIS");
    let through_gap = products_of(&gap, size);
    assert!(through_gap.curves.tangential_leaves_map);
    assert_eq!(
        through_gap.einstein_radius_map_arcsec,
        Some(EINSTEIN_MAP_WIDENING[0] * size)
    );
    assert_abs(
        "radius through a gap",
        through_gap.curves.einstein_radius_arcsec,
        r_true,
        0.1 * EINSTEIN_MAP_WIDENING[0] * pixel,
    );
}

/// The Einstein radius is the lens's at the map's centre: another structure whose curve lies
/// wholly beyond half the map's side (a group in a corner, as beside Abell 2744 in its CATS
/// model) neither counts nor, cut by the border, sends the measurement to a wider map where it
/// would be counted whole (41" instead of 22.8" for that model).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_second_structure_beyond_half_the_map_is_not_the_lens() {
    use wslap::{critical_curves_about, LensRegion};
    let f = einstein_plane().distance_ratio(2.0).expect("f");
    let r_true = f * THETA_E_ARCSEC;
    let products = |lens: &dyn MassComponent, size: f64| products_at_z2(lens, size, 256);
    // sqrt(area / pi) of the tangential loop around the centre, by the shoelace formula.
    let central = |curves: &[Polyline]| {
        let around = |c: &Polyline| (c.iter().copied().sum::<DVec2>() / c.len() as f64).length();
        let c = curves
            .iter()
            .min_by(|a, b| around(a).total_cmp(&around(b)))
            .expect("a curve");
        let twice: f64 = (0..c.len())
            .map(|k| c[k].perp_dot(c[(k + 1) % c.len()]))
            .sum();
        (0.5 * twice.abs() / std::f64::consts::PI).sqrt()
    };
    let group = |at: DVec2, theta_e: f64| {
        let g = Sis::from_theta_e(at, theta_e).expect("group SIS");
        wslap::Lens::new(vec![Box::new(sis()), Box::new(g)])
    };
    let everything = LensRegion {
        center: DVec2::ZERO,
        radius_arcsec: 10.0 * r_true,
    };
    // A group in the corner of an 8 r_E map, its curve (radius about 0.6 r_E) 4.5 - 5.7 r_E
    // from the centre and cut by the border: the map holds the lens's curve, no wider map.
    let size = 8.0 * r_true;
    let lens = group(DVec2::splat(0.45 * size), 0.6 * THETA_E_ARCSEC);
    let p = products(&lens, size);
    assert!(
        p.curves.tangential.len() >= 2,
        "the group's curve is traced"
    );
    assert!(!p.curves.tangential_leaves_map);
    assert_eq!(p.einstein_radius_map_arcsec, Some(size));
    let r = p.curves.einstein_radius_arcsec;
    assert_abs(
        "the lens's loop only",
        r,
        central(&p.curves.tangential),
        1e-9,
    );
    assert_rel("near the lone SIS's radius", r, r_true, 0.1);
    let whole_map = MapGeometry {
        pixels: 256,
        size_arcsec: size,
        center: DVec2::ZERO,
    };
    let maps = LensMaps::from_lens(&lens, whole_map);
    let with_group = critical_curves_about(&maps, f, 2.0, None, everything);
    assert!(with_group.tangential_leaves_map, "the group's curve leaves");
    // The lens's curve leaves a 1.9 r_E map; on the 3.8 r_E map that holds it a group's closed
    // loop (about 2.1 r_E from the centre, beyond the first map's 0.95 r_E) does not count.
    let lens = group(DVec2::splat(1.5 * r_true), 0.1 * THETA_E_ARCSEC);
    let narrow = products(&lens, 1.9 * r_true);
    assert!(narrow.curves.tangential_leaves_map);
    assert_eq!(narrow.einstein_radius_map_arcsec, Some(3.8 * r_true));
    let wide = MapGeometry {
        pixels: 256,
        size_arcsec: 3.8 * r_true,
        center: DVec2::ZERO,
    };
    let all = critical_curves_about(&LensMaps::from_lens(&lens, wide), f, 2.0, None, everything);
    assert_eq!(all.tangential.len(), 2, "the lens's loop and the group's");
    let r_lens = central(&all.tangential);
    assert!(all.einstein_radius_arcsec > 1.01 * r_lens, "both count");
    assert_abs(
        "the lens's loop only, on the wider map",
        narrow.curves.einstein_radius_arcsec,
        r_lens,
        1e-9,
    );
    // The main curve's radius is that loop's alone wherever the group's counts too.
    assert_abs(
        "main curve with the group counted",
        all.main_curve_radius_arcsec,
        r_lens,
        1e-9,
    );
    assert_abs(
        "main curve, measured on the wider map",
        narrow.curves.main_curve_radius_arcsec,
        r_lens,
        1e-9,
    );
    // A heavier group within the lens's half of the map (MACS J1149's to its north in the
    // CATS model): the text gives the main curve's radius beside the one that counts both.
    let lens = group(DVec2::splat(1.8 * r_true), 0.3 * THETA_E_ARCSEC);
    let s = products(&lens, 6.0 * r_true).summary();
    assert_eq!(s.tangential_curves, 2);
    let main = s.einstein_radius_main_curve_arcsec;
    assert!(main < 0.95 * s.einstein_radius_arcsec, "{s:?}");
    assert_rel("the main curve is the lens's", main, r_true, 0.1);
    let text = s.einstein_radius_text();
    assert!(
        text.ends_with(&format!("; the main curve alone {main:.2} arcsec")),
        "{text}"
    );
    // The app's caption gives it from the same rule.
    assert_eq!(s.main_curve_apart_arcsec(), Some(main));
    // A lone lens: nothing more to say.
    let alone = products(&sis(), 3.0 * r_true).summary();
    let text = alone.einstein_radius_text();
    assert!(!text.contains("main curve"), "{text}");
    assert_eq!(alone.main_curve_apart_arcsec(), None);
}
