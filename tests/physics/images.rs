//! The lens equation solved forward (src/images.rs): analytic SIS and point-mass images and
//! an SIS Einstein ring; an elliptical NFW cluster against lenstronomy's LensEquationSolver
//! (tests/data/images_reference.py), its five images and the odd-number theorem, fold pairs
//! down to 3e-4 arcsec apart, the same images from coarse grids and from precomputed maps;
//! known images of a 100-component cluster recovered; the source-plane helpers; bad input.

use crate::common;

use common::{assert_abs, assert_rel};
use glam::DVec2;
use serde::Deserialize;
use wslap::{estimate_redshift, NfwEllipse, PointMass, Sis, TruncatedNfw};
use wslap::{
    find_images, source_position, source_scatter, FoundImage, ImageError, ImageKind, ImageSearch,
    Parity, SearchGrid,
};
use wslap::{Cosmology, Lens, LensPlane, MapGeometry, MassComponent};
use wslap::{LensMaps, MAGNIFICATION_CLAMP};

/// Image positions vs the analytic solutions, arcsec: Newton settles at |r| <= 1e-11 arcsec
/// in the source plane, and `|det A| >= 0.1` here, so positions are good to ~1e-10 arcsec.
const POSITION_ATOL_ARCSEC: f64 = 1e-6;
/// Magnifications vs the analytic `1/det A` (same evaluation of the exact Hessian).
const MAGNIFICATION_RTOL: f64 = 1e-6;
/// Lens vs precomputed maps, and fine vs coarse grids: every search refines on the exact lens
/// to |r| <= 1e-11 arcsec, which moves an image by up to ~|mu| r (|mu| ~ 2e3 at most here);
/// measured 2e-12 arcsec.
const MAPS_AGREE_ATOL_ARCSEC: f64 = 1e-7;
/// Position error allowed per unit |mu| for the fold images (Newton target 1e-11 arcsec, times
/// 100 for the rounding of `beta` near the critical line).
const FOLD_POSITION_PER_MU_ARCSEC: f64 = 1e-9;
/// Our images vs lenstronomy's LensEquationSolver (precision 1e-10 arcsec in the source plane,
/// |mu| < 50, and the two CSE sums agree to 3e-14): measured 1.5e-10 arcsec.
const LENSTRONOMY_ATOL_ARCSEC: f64 = 1e-8;
/// Magnifications vs lenstronomy (analytic Hessians of the same CSE sum; measured 2e-11).
const LENSTRONOMY_MU_RTOL: f64 = 1e-8;
/// Relative agreement of the magnifications between the two grids (same position to 1e-7).
const MAPS_AGREE_RTOL: f64 = 1e-6;

/// SIS Einstein radius for `D_ls/D_s = 1` in arcsec, and the distance ratio used with it.
const THETA_E_ARCSEC: f64 = 20.0;
const F_RATIO: f64 = 0.7;

fn plane(z_lens: f64) -> LensPlane {
    LensPlane::new(Cosmology::default(), z_lens).expect("valid lens plane")
}

/// 0.5 arcsec pixels over `size_arcsec`, centred on the origin.
fn grid(size_arcsec: f64) -> MapGeometry {
    MapGeometry::centered(size_arcsec, (2.0 * size_arcsec) as usize)
}

fn search(lens: &dyn MassComponent, g: MapGeometry, f: f64, beta: DVec2) -> Vec<FoundImage> {
    find_images(lens, SearchGrid::Lens(g), f, beta, &ImageSearch::default()).expect("valid search")
}

/// Every image maps back to `beta` within the tolerance, its parity, kind and sign of `mu`
/// agree, and no two are suspiciously close.
#[track_caller]
fn check_images(lens: &dyn MassComponent, f: f64, beta: DVec2, images: &[FoundImage]) {
    let tol = ImageSearch::default().tolerance_arcsec;
    for im in images {
        let back = source_position(lens, f, im.position);
        assert!(
            back.distance(beta) < tol,
            "image {im:?} maps to {back} not {beta}"
        );
        assert!(im.magnification.is_finite() && im.residual_arcsec < tol);
        assert_eq!(im.parity == Parity::Negative, im.kind == ImageKind::Saddle);
        assert_eq!(im.parity == Parity::Negative, im.magnification < 0.0);
    }
    for (k, a) in images.iter().enumerate() {
        for b in &images[k + 1..] {
            // Distinct images of one parity lie far apart on these smooth lenses; a fold pair
            // (opposite parities) may be as close as 3e-4 arcsec in these tests.
            let min_sep = if a.parity == b.parity { 0.01 } else { 1e-4 };
            let sep = a.position.distance(b.position);
            assert!(sep > min_sep, "duplicates {a:?} {b:?}");
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sis_two_images_inside_the_caustic() {
    let lens = Sis::from_theta_e(DVec2::ZERO, THETA_E_ARCSEC).expect("sis");
    let te = F_RATIO * THETA_E_ARCSEC;
    for beta in [
        DVec2::new(1.5, -2.0),
        DVec2::new(-9.0, 4.0),
        DVec2::new(0.0, 0.3),
    ] {
        let images = search(&lens, grid(80.0), F_RATIO, beta);
        check_images(&lens, F_RATIO, beta, &images);
        assert_eq!(images.len(), 2, "beta {beta}: {images:?}");
        let (b, u) = (beta.length(), beta.normalize());
        // Sorted by |mu|: the outer (positive) image first, then the inner saddle.
        let expected = [(te + b, 1.0), (te - b, -1.0)];
        for (im, (r, side)) in images.iter().zip(expected) {
            let where_ = format!("beta {beta}, image at r = {r}");
            let want = u * r * side;
            assert_abs(
                &where_,
                im.position.distance(want),
                0.0,
                POSITION_ATOL_ARCSEC,
            );
            // Signed: negative for the inner image, where r < f theta_E.
            let mu = 1.0 / (1.0 - te / r);
            assert_rel(&where_, im.magnification, mu, MAGNIFICATION_RTOL);
        }
        assert_eq!(images[0].kind, ImageKind::Minimum);
        assert_eq!(images[1].kind, ImageKind::Saddle);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sis_one_image_outside_the_caustic() {
    let lens = Sis::from_theta_e(DVec2::new(3.0, -1.0), THETA_E_ARCSEC).expect("sis");
    let te = F_RATIO * THETA_E_ARCSEC;
    let offset = DVec2::new(-12.0, 10.0); // |offset| = 15.6 > te = 14
    let beta = lens.center() + offset;
    let images = search(&lens, grid(100.0), F_RATIO, beta);
    check_images(&lens, F_RATIO, beta, &images);
    assert_eq!(images.len(), 1, "{images:?}");
    let r = offset.length() + te;
    let want = lens.center() + offset.normalize() * r;
    assert_abs(
        "position",
        images[0].position.distance(want),
        0.0,
        POSITION_ATOL_ARCSEC,
    );
    assert_rel(
        "mu",
        images[0].magnification,
        1.0 / (1.0 - te / r),
        MAGNIFICATION_RTOL,
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn point_mass_two_images() {
    let theta_e = 10.0;
    let lens = PointMass::from_theta_e(DVec2::ZERO, theta_e).expect("point");
    // Effective Einstein radius for this source: b^2 = f theta_E^2.
    let b2 = F_RATIO * theta_e * theta_e;
    for beta in [
        DVec2::new(2.0, 1.0),
        DVec2::new(-0.2, 0.1),
        DVec2::new(25.0, -3.0),
    ] {
        let images = search(&lens, grid(80.0), F_RATIO, beta);
        check_images(&lens, F_RATIO, beta, &images);
        assert_eq!(images.len(), 2, "beta {beta}: {images:?}");
        let (b, u) = (beta.length(), beta.normalize());
        let root = (b * b + 4.0 * b2).sqrt();
        for (im, x) in images.iter().zip([(b + root) / 2.0, (b - root) / 2.0]) {
            let where_ = format!("beta {beta}, image at x = {x}");
            assert_abs(
                &where_,
                im.position.distance(u * x),
                0.0,
                POSITION_ATOL_ARCSEC,
            );
            // det A = 1 - b^4 / r^4 for a point mass.
            let mu = 1.0 / (1.0 - (b2 / (x * x)).powi(2));
            assert_rel(&where_, im.magnification, mu, MAGNIFICATION_RTOL);
        }
    }
}

/// The elliptical NFW cluster of the tests: M200 = 1e15 Msun, c200 = 5, q = 0.7, PA 30 deg at
/// z_l = 0.3, and `f` for a source at z_s = 2.
fn cluster() -> (NfwEllipse, f64) {
    let lp = plane(0.3);
    let halo = NfwEllipse::new(DVec2::new(1.0, -2.0), 1e15, 5.0, 0.7, 30.0, &lp).expect("halo");
    (halo, lp.distance_ratio(2.0).expect("f"))
}

#[derive(Deserialize)]
struct Reference {
    f: f64,
    center: [f64; 2],
    m200_msun: f64,
    c200: f64,
    q: f64,
    pa_deg: f64,
    sources: Vec<ReferenceSource>,
}

#[derive(Deserialize)]
struct ReferenceSource {
    beta: [f64; 2],
    images: Vec<ReferenceImage>,
}

#[derive(Deserialize)]
struct ReferenceImage {
    x: f64,
    y: f64,
    magnification: f64,
}

/// The cluster's images for five sources (5, 5, 3, 3 and 1 images) against lenstronomy
/// (tests/data/images_reference.py): same count, positions and signed magnifications.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn elliptical_nfw_matches_lenstronomy() {
    let reference: Reference =
        serde_json::from_str(include_str!("../data/images.json")).expect("tests/data/images.json");
    let (halo, f) = cluster();
    assert_eq!(halo.center(), DVec2::from(reference.center));
    assert_eq!(
        (halo.m200_msun(), halo.c200(), halo.q(), halo.pa_deg()),
        (
            reference.m200_msun,
            reference.c200,
            reference.q,
            reference.pa_deg
        )
    );
    // Our distances match astropy's to ~1e-13 (tests/physics/physics.rs).
    assert_rel("f = D_ls/D_s", f, reference.f, 1e-9);
    for source in &reference.sources {
        let beta = DVec2::from(source.beta);
        let images = search(&halo, grid(120.0), f, beta);
        check_images(&halo, f, beta, &images);
        assert_eq!(images.len(), source.images.len(), "beta {beta}: {images:?}");
        for want in &source.images {
            let p = DVec2::new(want.x, want.y);
            let what = format!("beta {beta}, lenstronomy image at {p}");
            let got = images
                .iter()
                .min_by(|a, b| a.position.distance(p).total_cmp(&b.position.distance(p)));
            let got = got.expect("at least one image");
            assert_abs(
                &what,
                got.position.distance(p),
                0.0,
                LENSTRONOMY_ATOL_ARCSEC,
            );
            assert_rel(
                &what,
                got.magnification,
                want.magnification,
                LENSTRONOMY_MU_RTOL,
            );
        }
    }
}

/// The redshift of a system without one, estimated from lenstronomy's images of the cluster
/// (a source at z_s = 2) on the true lens: every source with two or more images gives z_s back
/// to within 0.01 in 1 + z, inside its 68% interval, and a narrow one for a 0.05" error.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn lenstronomy_images_give_back_their_redshift() {
    let reference: Reference =
        serde_json::from_str(include_str!("../data/images.json")).expect("tests/data/images.json");
    let (halo, _) = cluster();
    let lp = plane(0.3);
    let mut estimated = 0;
    for source in reference.sources.iter().filter(|s| s.images.len() >= 2) {
        let images: Vec<DVec2> = source.images.iter().map(|i| DVec2::new(i.x, i.y)).collect();
        let e = estimate_redshift(&halo, &lp, &images, [0.5, 8.0], 0.05, 10.0).expect("estimate");
        let what = format!(
            "source at {:?} ({} images): {e:?}",
            source.beta,
            images.len()
        );
        assert!((e.z - 2.0).abs() / 3.0 < 0.01, "{what}");
        assert!((e.z_median - 2.0).abs() / 3.0 < 0.01, "{what}");
        assert!(e.interval[0] <= 2.0 && 2.0 <= e.interval[1], "{what}");
        assert!(e.interval[1] - e.interval[0] < 0.3, "{what}");
        estimated += 1;
    }
    assert_eq!(estimated, 4);
    // One image says nothing about the redshift.
    let one = [DVec2::new(12.98, -15.5)];
    assert!(estimate_redshift(&halo, &lp, &one, [0.5, 8.0], 0.05, 10.0).is_none());
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn elliptical_nfw_five_images() {
    let (halo, f) = cluster();
    let beta = halo.center() + DVec2::new(0.8, 0.5);
    let images = search(&halo, grid(120.0), f, beta);
    check_images(&halo, f, beta, &images);
    let count = |k: ImageKind| images.iter().filter(|im| im.kind == k).count();
    assert_eq!(images.len(), 5, "{images:?}");
    // Odd-number theorem: minima + maxima - saddles = 1.
    assert_eq!(count(ImageKind::Minimum), 2);
    assert_eq!(count(ImageKind::Saddle), 2);
    assert_eq!(count(ImageKind::Maximum), 1);
}

/// A point just outside the tangential critical curve of the cluster, on the ray at `angle_deg`
/// from the halo centre, `delta_arcsec` beyond the curve (found by bisection of
/// `lambda_t = 1 - f (kappa + |gamma|)` on the exact Hessian).
fn beyond_tangential_curve(halo: &NfwEllipse, f: f64, angle_deg: f64, delta_arcsec: f64) -> DVec2 {
    let dir = DVec2::from_angle(angle_deg.to_radians());
    let lambda_t = |r: f64| {
        let [xx, xy, yy] = halo.hessian(halo.center() + dir * r);
        let g = (0.25 * (xx - yy).powi(2) + xy * xy).sqrt();
        1.0 - f * (0.5 * (xx + yy) + g)
    };
    let (mut lo, mut hi) = (5.0, 60.0);
    assert!(
        lambda_t(lo) < 0.0 && lambda_t(hi) > 0.0,
        "no tangential curve in [5, 60]"
    );
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if lambda_t(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    halo.center() + dir * (hi + delta_arcsec)
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn fold_pair_near_the_critical_curve() {
    let (halo, f) = cluster();
    // 0.05 to 1e-4 arcsec beyond the curve: pairs 0.17 to 3e-4 arcsec apart, |mu| 1e3 to 6e5,
    // both images inside one cell of a 2 arcsec grid.
    let g = MapGeometry::centered(120.0, 60);
    for (angle, delta) in [(10.0, 0.05), (75.0, 0.003), (200.0, 1e-4)] {
        let image = beyond_tangential_curve(&halo, f, angle, delta);
        let beta = source_position(&halo, f, image);
        let images = search(&halo, g, f, beta);
        check_images(&halo, f, beta, &images);
        let what = format!("ray {angle} deg, {delta} arcsec beyond the curve: {images:?}");
        // These sources lie outside the radial caustic: a fold pair and one far minimum.
        assert_eq!(images.len(), 3, "{what}");
        let (pair, far): (Vec<&FoundImage>, Vec<&FoundImage>) = images
            .iter()
            .partition(|im| im.position.distance(image) < 0.5);
        assert_eq!((pair.len(), far.len()), (2, 1), "{what}");
        let near = pair.iter().find(|im| im.kind == ImageKind::Minimum);
        let near = near.expect("the constructed image is a minimum");
        // Along the critical direction a residual r moves the image by ~|mu| r, r <= 1e-11.
        let atol = near.magnification.abs() * FOLD_POSITION_PER_MU_ARCSEC;
        assert_abs(&what, near.position.distance(image), 0.0, atol);
        assert!(pair.iter().any(|im| im.kind == ImageKind::Saddle), "{what}");
        for im in pair {
            // Near a fold |mu| ~ 1/(delta |d lambda_t / d r|): above 500 for these deltas.
            assert!(im.magnification.abs() > 500.0, "{what}");
        }
        assert_eq!(far[0].kind, ImageKind::Minimum, "{what}");
    }
}

/// The five images do not depend on the grid from 0.5 to 4 arcsec pixels (the central image of
/// the NFW cusp is lost on some sources from 8 arcsec on).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn coarse_grids_find_the_same_images() {
    let (halo, f) = cluster();
    let beta = halo.center() + DVec2::new(-1.2, 0.4);
    let fine = search(&halo, grid(120.0), f, beta);
    assert_eq!(fine.len(), 5, "{fine:?}");
    for pixels in [60, 30] {
        let coarse = search(&halo, MapGeometry::centered(120.0, pixels), f, beta);
        assert_eq!(coarse.len(), 5, "{pixels} pixels: {coarse:?}");
        for (a, b) in fine.iter().zip(&coarse) {
            let what = format!("{pixels} pixels: {a:?} vs {b:?}");
            assert_abs(
                &what,
                a.position.distance(b.position),
                0.0,
                MAPS_AGREE_ATOL_ARCSEC,
            );
            assert_eq!(a.kind, b.kind, "{what}");
        }
    }
}

/// Synthetic data: random image positions in a cluster of 100 components are mapped to their
/// sources, and the search on 1 arcsec maps finds each of them again among the source's images.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn rich_cluster_recovers_known_images() {
    let (lens, f) = rich_cluster();
    let maps = LensMaps::from_lens(&lens, MapGeometry::centered(80.0, 80));
    let mut uniform = lcg(2024);
    let mut multiple = 0;
    for _ in 0..20 {
        let theta = DVec2::new(uniform() - 0.5, uniform() - 0.5) * 40.0;
        let beta = source_position(&lens, f, theta);
        let opts = ImageSearch::default();
        let images = find_images(&lens, SearchGrid::Maps(&maps), f, beta, &opts).expect("search");
        check_images(&lens, f, beta, &images);
        let found = images.iter().find(|im| im.position.distance(theta) < 1e-6);
        assert!(found.is_some(), "theta {theta} not among {images:?}");
        multiple += usize::from(images.len() > 1);
    }
    // Most of these sources are multiply imaged (measured 17 of 20).
    assert!(multiple >= 10, "only {multiple} multiply imaged sources");
}

/// The same search with the first grid from precomputed maps finds the same images.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn maps_and_lens_agree() {
    let (halo, f) = cluster();
    let g = grid(120.0);
    let maps = LensMaps::from_lens(&halo, g);
    let fold_source = source_position(&halo, f, beyond_tangential_curve(&halo, f, 130.0, 0.03));
    for beta in [halo.center() + DVec2::new(0.8, 0.5), fold_source] {
        let opts = ImageSearch::default();
        let direct = find_images(&halo, SearchGrid::Lens(g), f, beta, &opts).expect("search");
        let mapped = find_images(&halo, SearchGrid::Maps(&maps), f, beta, &opts).expect("search");
        check_images(&halo, f, beta, &mapped);
        assert!(direct.len() >= 3, "beta {beta}: {direct:?}");
        assert_eq!(
            direct.len(),
            mapped.len(),
            "beta {beta}: {direct:?} vs {mapped:?}"
        );
        for (a, b) in direct.iter().zip(&mapped) {
            let what = format!("beta {beta}: {a:?} vs {b:?}");
            assert_abs(
                &what,
                a.position.distance(b.position),
                0.0,
                MAPS_AGREE_ATOL_ARCSEC,
            );
            assert_rel(&what, b.magnification, a.magnification, MAPS_AGREE_RTOL);
            assert_eq!(a.kind, b.kind, "{what}");
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn source_scatter_of_images() {
    let lens = Sis::from_theta_e(DVec2::ZERO, THETA_E_ARCSEC).expect("sis");
    let beta = DVec2::new(2.0, 3.0);
    let images = search(&lens, grid(80.0), F_RATIO, beta);
    let thetas: Vec<DVec2> = images.iter().map(|im| im.position).collect();
    let fit = source_scatter(&lens, F_RATIO, &thetas).expect("two images");
    // Exact images: the scatter is the Newton residual (< 1e-10 arcsec).
    assert_abs("scatter", fit.rms_arcsec, 0.0, 1e-10);
    assert_abs("beta", fit.beta.distance(beta), 0.0, 1e-10);
    // Two arbitrary points: rms and max distance to the mean are half their separation.
    let (a, b) = (DVec2::new(5.0, 1.0), DVec2::new(-30.0, 7.0));
    let (ba, bb) = (
        source_position(&lens, F_RATIO, a),
        source_position(&lens, F_RATIO, b),
    );
    let fit = source_scatter(&lens, F_RATIO, &[a, b]).expect("two points");
    assert_abs("mean", fit.beta.distance(0.5 * (ba + bb)), 0.0, 1e-12);
    assert_rel("rms", fit.rms_arcsec, 0.5 * ba.distance(bb), 1e-12);
    assert_rel("max", fit.max_arcsec, 0.5 * ba.distance(bb), 1e-12);
    assert!(source_scatter(&lens, F_RATIO, &[]).is_none());
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_input_is_an_error() {
    let lens = Sis::from_theta_e(DVec2::ZERO, THETA_E_ARCSEC).expect("sis");
    let g = grid(40.0);
    let ok = ImageSearch::default();
    let run = |g: MapGeometry, f: f64, beta: DVec2, opts: &ImageSearch| {
        find_images(&lens, SearchGrid::Lens(g), f, beta, opts)
    };
    for f in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            run(g, f, DVec2::ONE, &ok),
            Err(ImageError::BadDistanceRatio { .. })
        ));
    }
    let nan = DVec2::new(f64::NAN, 0.0);
    assert!(matches!(
        run(g, 0.5, nan, &ok),
        Err(ImageError::BadSource { .. })
    ));
    for bad in [
        MapGeometry::centered(40.0, 1),
        MapGeometry::centered(-1.0, 10),
    ] {
        assert!(matches!(
            run(bad, 0.5, DVec2::ONE, &ok),
            Err(ImageError::BadGrid { .. })
        ));
    }
    let settings = [
        (
            "tolerance_arcsec",
            ImageSearch {
                tolerance_arcsec: 0.0,
                ..ok
            },
        ),
        (
            "duplicate_arcsec",
            ImageSearch {
                duplicate_arcsec: f64::NAN,
                ..ok
            },
        ),
        (
            "min_abs_magnification",
            ImageSearch {
                min_abs_magnification: -1.0,
                ..ok
            },
        ),
        (
            "max_newton_iterations",
            ImageSearch {
                max_newton_iterations: 0,
                ..ok
            },
        ),
    ];
    for (field, opts) in settings {
        match run(g, 0.5, DVec2::ONE, &opts) {
            Err(ImageError::BadFieldValue(e)) => {
                assert_eq!(e.field, format!("image_search.{field}"))
            }
            other => panic!("{field}: expected BadFieldValue, got {other:?}"),
        }
    }
    let mut maps = LensMaps::from_lens(&lens, MapGeometry::centered(40.0, 8));
    maps.alpha_y.data.pop();
    let result = find_images(&lens, SearchGrid::Maps(&maps), 0.5, DVec2::ONE, &ok);
    assert!(
        matches!(result, Err(ImageError::BadMaps { map: "alpha_y", .. })),
        "{result:?}"
    );
}

/// Uniform numbers in [0, 1) from a 64-bit linear congruential generator with `seed`.
fn lcg(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A cluster of 100 components: the elliptical NFW halo and 99 truncated-NFW galaxies at
/// pseudo-random positions within 80 arcsec (fixed seed).
fn rich_cluster() -> (Lens, f64) {
    let lp = plane(0.3);
    let (halo, f) = cluster();
    let mut components: Vec<Box<dyn MassComponent>> = vec![Box::new(halo)];
    let mut seed = 12345_u64;
    let mut uniform = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..99 {
        let p = DVec2::new(uniform() - 0.5, uniform() - 0.5) * 160.0;
        let m = 10f64.powf(10.5 + 1.5 * uniform());
        let g = TruncatedNfw::new(p, m, 10.0, 15.0, &lp).expect("galaxy");
        components.push(Box::new(g));
    }
    (Lens::new(components), f)
}

/// A source exactly behind an SIS images into the Einstein ring `r = f theta_E`: the search
/// returns a sample of points on it, each at the magnification clamp.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn einstein_ring_is_sampled() {
    let lens = Sis::from_theta_e(DVec2::ZERO, THETA_E_ARCSEC).expect("sis");
    let images = search(&lens, grid(80.0), F_RATIO, DVec2::ZERO);
    // One or more points per grid cell crossed by the ring (measured 760).
    assert!(images.len() > 100, "{} images", images.len());
    for im in &images {
        let r = im.position.length();
        assert_abs(
            "ring radius",
            r,
            F_RATIO * THETA_E_ARCSEC,
            POSITION_ATOL_ARCSEC,
        );
        assert_eq!(im.magnification.abs(), MAGNIFICATION_CLAMP, "{im:?}");
    }
}
