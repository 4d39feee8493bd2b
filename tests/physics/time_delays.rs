//! The lensing potential and time delays (src/potential.rs) against lenstronomy's
//! `LensModel.potential` and `arrival_time` (tests/data/time_delays_reference.py) on an SIS, an
//! NFW, an elliptical NFW and a mixed model (elliptical NFW, SIS galaxy, external shear): at
//! lenstronomy's images and at the images our own solver finds; and the potential map of the
//! products against the line integral.

use crate::common;

use common::assert_rel;
use glam::DVec2;
use serde::Deserialize;
use wslap::{
    arrival_time_days, find_images, potential_at, potential_difference, potential_map,
    time_delay_distance_mpc, Cosmology, ExternalShear, ImageSearch, Lens, LensMaps, LensPlane,
    MapGeometry, MassComponent, Nfw, NfwEllipse, SearchGrid, Sis,
};

/// Potential differences between images vs lenstronomy (the same deflections integrated to
/// 1e-10 here; lenstronomy's potentials are analytic): measured 4.8e-12.
const PSI_RTOL: f64 = 1e-9;
/// Time delays vs lenstronomy, measured 5.2e-10 (the bar is 1e-4): the potentials and
/// D_dt agree far better, so this is the two codes' constants (Mpc, day) in the 10th digit.
const DELAY_RTOL: f64 = 1e-8;
/// D_dt vs astropy: measured 2.6e-14.
const DISTANCE_RTOL: f64 = 1e-12;
/// psi.fits (320 pixels over 80 arcsec) vs the line integral off the pixel centres: measured
/// 1.6e-7.
const MAP_RTOL: f64 = 1e-6;
/// Our images vs lenstronomy's, arcsec (see tests/physics/images.rs).
const POSITION_ATOL_ARCSEC: f64 = 1e-6;

#[derive(Deserialize)]
struct Reference {
    z_lens: f64,
    z_source: f64,
    f: f64,
    time_delay_distance_mpc: f64,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    sources: Vec<Source>,
}

#[derive(Deserialize)]
struct Source {
    beta: [f64; 2],
    images: Vec<Image>,
}

#[derive(Deserialize)]
struct Image {
    x: f64,
    y: f64,
    psi: f64,
    arrival_days: f64,
}

fn reference() -> Reference {
    serde_json::from_str(include_str!("../data/time_delays.json"))
        .expect("tests/data/time_delays.json")
}

fn lens(name: &str, plane: &LensPlane) -> Lens {
    let ellipse = || -> Box<dyn MassComponent> {
        Box::new(NfwEllipse::new(DVec2::new(1.0, -2.0), 1e15, 5.0, 0.7, 30.0, plane).unwrap())
    };
    let components: Vec<Box<dyn MassComponent>> = match name {
        "sis" => vec![Box::new(
            Sis::from_theta_e(DVec2::new(1.0, -2.0), 25.0).unwrap(),
        )],
        "nfw" => vec![Box::new(Nfw::new(DVec2::ZERO, 1e15, 5.0, plane).unwrap())],
        "nfw_ellipse" => vec![ellipse()],
        "mixed" => vec![
            ellipse(),
            Box::new(Sis::from_theta_e(DVec2::new(12.0, 6.0), 3.0).unwrap()),
            Box::new(ExternalShear::new(DVec2::ZERO, 0.05, 20.0).unwrap()),
        ],
        other => panic!("unknown case {other}"),
    };
    Lens::new(components)
}

fn plane(r: &Reference) -> LensPlane {
    LensPlane::new(Cosmology::default(), r.z_lens).unwrap()
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn time_delay_distance_matches_astropy() {
    let r = reference();
    let d = time_delay_distance_mpc(&plane(&r), r.z_source).unwrap();
    assert_rel("D_dt", d, r.time_delay_distance_mpc, DISTANCE_RTOL);
}

/// At lenstronomy's images: our potential differences (times f) and delays, relative to the
/// first image (lenstronomy sorts them by arrival time).
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn potentials_and_delays_match_lenstronomy() {
    let r = reference();
    let pl = plane(&r);
    for case in &r.cases {
        let lens = lens(&case.name, &pl);
        for s in &case.sources {
            let beta = DVec2::from(s.beta);
            let first = &s.images[0];
            let p0 = DVec2::new(first.x, first.y);
            let t0 = arrival_time_days(&pl, r.z_source, p0, beta, 0.0).unwrap();
            for im in &s.images[1..] {
                let p = DVec2::new(im.x, im.y);
                let what = format!("{} beta {beta} image at {p}", case.name);
                let dpsi = potential_difference(&lens, p0, p);
                assert_rel(
                    &format!("{what}: psi"),
                    r.f * dpsi,
                    im.psi - first.psi,
                    PSI_RTOL,
                );
                let delay = arrival_time_days(&pl, r.z_source, p, beta, dpsi).unwrap() - t0;
                let want = im.arrival_days - first.arrival_days;
                assert_rel(&format!("{what}: delay"), delay, want, DELAY_RTOL);
            }
        }
    }
}

/// The images our solver finds for the same sources, with their delays, in lenstronomy's order.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn our_images_have_lenstronomy_delays() {
    let r = reference();
    let pl = plane(&r);
    let geometry = MapGeometry::centered(80.0, 160);
    for case in &r.cases {
        let lens = lens(&case.name, &pl);
        for s in &case.sources {
            let beta = DVec2::from(s.beta);
            let found = find_images(
                &lens,
                SearchGrid::Lens(geometry),
                r.f,
                beta,
                &ImageSearch::default(),
            )
            .unwrap();
            assert_eq!(found.len(), s.images.len(), "{} beta {beta}", case.name);
            let p0 = DVec2::new(s.images[0].x, s.images[0].y);
            let mine = |p: DVec2| {
                let psi = potential_difference(&lens, p0, p);
                arrival_time_days(&pl, r.z_source, p, beta, psi).unwrap()
            };
            for im in &s.images {
                let want = DVec2::new(im.x, im.y);
                let ours = found
                    .iter()
                    .map(|f| f.position)
                    .min_by(|a, b| a.distance(want).total_cmp(&b.distance(want)))
                    .unwrap();
                assert!(
                    ours.distance(want) < POSITION_ATOL_ARCSEC,
                    "{} beta {beta}: image {want} found at {ours}",
                    case.name
                );
                let delay = mine(ours) - mine(p0);
                let expected = im.arrival_days - s.images[0].arrival_days;
                if expected != 0.0 {
                    assert_rel(
                        &format!("{} delay at {want}", case.name),
                        delay,
                        expected,
                        DELAY_RTOL,
                    );
                }
            }
        }
    }
}

/// `psi.fits` of the products: the potential map of the mixed model against the line integral,
/// at points off the pixel centres.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn potential_map_matches_line_integrals() {
    let r = reference();
    let pl = plane(&r);
    let lens = lens("mixed", &pl);
    let geometry = MapGeometry::centered(80.0, 320);
    let maps = LensMaps::from_lens(&lens, geometry);
    let psi = potential_map(&maps);
    let origin = geometry.pixel_center(160, 160);
    assert_eq!(psi.at(160, 160), 0.0);
    for p in [
        DVec2::new(14.63, -20.09),
        DVec2::new(-8.92, 12.43),
        DVec2::new(30.1, 31.7),
        DVec2::new(-35.0, -2.2),
    ] {
        let want = potential_difference(&lens, origin, p);
        let got = potential_at(&psi, &maps, p).expect("inside the map");
        assert_rel(&format!("psi map at {p}"), got, want, MAP_RTOL);
    }
}
