//! Observing scenes: analytic image positions, arcs only where a source is lensed, members
//! that rebuild the scene's halos, and files the app's own readers read.

use glam::DVec2;

use super::*;
use crate::arcs::parse_arcs;
use crate::catalog::{parse_image_catalog, parse_member_catalog};
use crate::inversion::member_halo;
use crate::model::{ComponentSpec, ModelFile};
use crate::profiles::sis_theta_e_arcsec;

/// Position errors allowed on top of the jitter: the image finder's tolerance is 1e-4 arcsec.
const FINDER_TOL_ARCSEC: f64 = 1e-3;
/// A jittered position lies within this many jitter rms of the truth (per image, 2-D).
const JITTER_SIGMAS: f64 = 5.0;

fn scene(text: &str) -> Scene {
    Scene::from_json_str(text).expect("scene")
}

const SIS_POINT: &str = r#"{"v": 1, "z_lens": 0.3, "fov": 40,
  "lenses": [{"type": "sis", "x": 0, "y": 0, "sigma_v": 700}],
  "sources": [{"type": "point", "x": 1.5, "y": 0.0, "z": 2.0}]}"#;

#[test]
fn a_lensed_sis_point_source_gives_two_images_at_the_analytic_positions() {
    let s = scene(SIS_POINT);
    let options = ObserveOptions::default();
    let obs = observe(&s, &options).expect("observe");
    let f = s.build().expect("build").source_f[0];
    let theta_e = f * sis_theta_e_arcsec(700.0);
    let beta = 1.5;
    // theta = beta +- theta_E on the line through the lens and the source.
    let truth = [beta + theta_e, beta - theta_e];
    let text = obs.images_cat.as_deref().expect("a catalogue");
    let (cat, _) = parse_image_catalog(text, "images.cat", None).expect("parses");
    assert_eq!(cat.systems.len(), 1);
    let sys = &cat.systems[0];
    assert_eq!(sys.id, "1");
    assert_eq!(sys.z, Some(2.0));
    assert_eq!(sys.images.len(), 2, "{text}");
    let tol = JITTER_SIGMAS * options.position_sigma_arcsec() + FINDER_TOL_ARCSEC;
    for x in truth {
        let near = sys
            .images
            .iter()
            .map(|im| im.position.distance(DVec2::new(x, 0.0)))
            .fold(f64::INFINITY, f64::min);
        assert!(near < tol, "image at x = {x}: nearest {near} > {tol}");
    }
    // Jittered, not copied: a position error of exactly zero would mean no noise.
    assert!(sys.images.iter().all(|im| im.position.y != 0.0));
    assert_eq!(
        obs.setting("reconstruct.constraints.mode").unwrap(),
        "point"
    );
    assert!(obs.arcs_json.is_none() && obs.members_cat.is_none());
    assert!(obs.notes.is_empty(), "{:?}", obs.notes);
}

#[test]
fn the_same_seed_gives_the_same_data_and_another_seed_other_data() {
    let s = scene(SIS_POINT);
    let a = observe(&s, &ObserveOptions::default()).unwrap();
    let b = observe(&s, &ObserveOptions::default()).unwrap();
    let c = observe(
        &s,
        &ObserveOptions {
            seed: 2,
            ..ObserveOptions::default()
        },
    )
    .unwrap();
    assert_eq!(a, b);
    assert_ne!(a.images_cat, c.images_cat);
}

#[test]
fn a_source_far_from_the_caustics_is_dropped_with_a_note() {
    let s = scene(
        r#"{"v": 1, "z_lens": 0.3, "fov": 40,
        "lenses": [{"type": "sis", "x": 0, "y": 0, "sigma_v": 700}],
        "sources": [{"type": "point", "x": 15, "y": 0.0, "z": 2.0},
                    {"type": "gaussian", "x": -12, "y": 3, "z": 1.5, "sigma": 0.3}]}"#,
    );
    let obs = observe(&s, &ObserveOptions::default()).unwrap();
    assert!(obs.systems.is_empty());
    assert!(obs.images_cat.is_none() && obs.arcs_json.is_none());
    assert!(
        obs.notes.iter().any(|n| n.contains("system 1")),
        "{:?}",
        obs.notes
    );
    assert!(
        obs.notes.iter().any(|n| n.contains("system 2")),
        "{:?}",
        obs.notes
    );
}

const SIE_ARCS: &str = r#"{"v": 1, "z_lens": 0.3, "fov": 40,
  "lenses": [{"type": "sie", "x": 0, "y": 0, "sigma_v": 800, "q": 0.75, "pa": 20},
             {"type": "member", "x": 7, "y": -5, "mag": 19}],
  "sources": [{"type": "sersic", "x": 0.8, "y": 0.4, "z": 2.0, "r_eff": 0.4, "n": 1, "q": 0.7, "pa": 30},
              {"type": "point", "x": -0.5, "y": 0.6, "z": 3.0}]}"#;

#[test]
fn arcs_are_detected_only_where_the_source_is_lensed() {
    let s = scene(SIE_ARCS);
    let options = ObserveOptions::default();
    let obs = observe(&s, &options).expect("observe");
    let text = obs.arcs_json.as_deref().expect("arcs");
    let arcs = parse_arcs(text, "arcs.json").expect("parses");
    let built = s.build().unwrap();
    let f = built.source_f[0];
    let extended = arcs.systems.iter().find(|a| a.id == "1").expect("system 1");
    assert!(
        extended.images.len() >= 2,
        "{} images",
        extended.images.len()
    );
    // Every detected pixel maps back near the source: within the blur and a few r_eff.
    let reach = 4.0 * 0.4 + 2.0 * options.psf_fwhm_arcsec;
    for p in extended.images.iter().flatten() {
        let (alpha, _) = crate::profiles::MassComponent::deflection_hessian(&built.lens, *p);
        let beta = *p - f * alpha;
        let d = beta.distance(DVec2::new(0.8, 0.4));
        assert!(
            d < reach,
            "pixel {p} maps to {beta}, {d} arcsec from the source"
        );
    }
    // The point source rides along as one-pixel images, so one mode fits both.
    let point = arcs.systems.iter().find(|a| a.id == "2").expect("system 2");
    assert!(point.images.iter().all(|im| im.len() == 1));
    assert_eq!(obs.setting("reconstruct.constraints.mode").unwrap(), "arcs");
    assert_eq!(obs.setting("reconstruct.products.z_source").unwrap(), 3.0);
    assert!(obs.images_cat.is_some());
}

#[test]
fn members_round_trip_into_the_scene_halos() {
    let s = scene(SIE_ARCS);
    let obs = observe(&s, &ObserveOptions::default()).unwrap();
    let text = obs.members_cat.as_deref().expect("members");
    let (cat, warnings) = parse_member_catalog(text, "members.cat", None).expect("parses");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(cat.members.len(), 1);
    let m = &cat.members[0];
    assert!((m.position - DVec2::new(7.0, -5.0)).length() < 1e-4);
    assert_eq!(m.mag, 19.0);
    // The inversion's member scaling gives back the truth's halo (C = 1).
    let plane = s.build().unwrap().plane;
    let config = MemberConfig::default();
    let mass = config.mass_msun(m.mag, config.mag_star_on(&plane));
    let (_, m200, c200, r_trunc) = member_halo(&config, m.position, mass, &plane).unwrap();
    let truth = ModelFile::from_json_str(&obs.model_json, "model.json").expect("model");
    let halo = truth
        .components
        .iter()
        .find_map(|c| match *c {
            ComponentSpec::Tnfw {
                m200,
                c200,
                r_trunc,
                ..
            } => Some((m200, c200, r_trunc)),
            _ => None,
        })
        .expect("the member's halo");
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    assert!(rel(m200, halo.0) < 1e-6 && rel(c200, halo.1) < 1e-6);
    assert!(rel(r_trunc.unwrap_or(f64::INFINITY), halo.2) < 1e-6);
}

#[test]
fn bad_options_name_the_field() {
    let s = scene(SIS_POINT);
    for (options, field) in [
        (
            ObserveOptions {
                pixel_arcsec: 0.0,
                ..ObserveOptions::default()
            },
            "pixel_arcsec",
        ),
        (
            ObserveOptions {
                pixel_arcsec: 0.01,
                ..ObserveOptions::default()
            },
            "pixel_arcsec",
        ),
        (
            ObserveOptions {
                noise: 0.0,
                ..ObserveOptions::default()
            },
            "noise",
        ),
        (
            ObserveOptions {
                threshold_sigma: 60.0,
                ..ObserveOptions::default()
            },
            "threshold_sigma",
        ),
    ] {
        let e = observe(&s, &options).unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
}

#[test]
fn blur_keeps_the_flux_and_groups_are_eight_connected() {
    let n = 21;
    let mut image = vec![0.0; n * n];
    image[10 * n + 10] = 1.0;
    blur(&mut image, n, 1.5);
    let total: f64 = image.iter().sum();
    assert!((total - 1.0).abs() < 1e-9, "{total}");
    let mut mask = vec![false; 16];
    for k in [0, 5, 10, 3] {
        mask[k] = true;
    }
    // 0-5-10 touch by corners on a 4 x 4 grid; 3 stands alone.
    assert_eq!(groups(&mask, 4), vec![vec![0, 5, 10], vec![3]]);
}
