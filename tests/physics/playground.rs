//! The playground's scene: its format, its truth model, and that what it shows is the core's
//! lensing (an SIS's Einstein ring, images that trace back to their source, member galaxies
//! that are the inversion's own halos).

use glam::DVec2;
use wslap::playground::{ContourKind, Playground, Scene, SceneError, SceneLens, SourceSpec};
use wslap::{
    build_member_layers, CellGrid, LensPlane, MassComponent, Member, MemberCatalog, MemberConfig,
};

use crate::common::{assert_abs, assert_rel};

const SCENE: &str = r#"{"v": 1, "z_lens": 0.3, "fov": 40,
 "lenses": [{"type": "sis", "x": 0, "y": 0, "sigma_v": 700},
            {"type": "member", "x": 6, "y": -4, "mag": 19.0}],
 "sources": [{"type": "sersic", "x": 0.5, "y": 0.2, "z": 2.0, "r_eff": 0.6, "n": 1.5},
             {"type": "point", "x": 1.0, "y": -0.5, "z": 2.0},
             {"type": "gaussian", "x": -1, "y": 1, "z": 1.0, "sigma": 0.4, "q": 0.5, "pa": 30}]}"#;

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn scene_round_trips_and_its_truth_is_its_lens() {
    let scene = Scene::from_json_str(SCENE).expect("valid scene");
    let again = Scene::from_json_str(&scene.to_json_string()).expect("written scene reads");
    assert_eq!(again, scene);
    let built = scene.build().expect("builds");
    let truth = scene
        .truth_model()
        .expect("truth")
        .build_lens()
        .expect("lens");
    for p in [DVec2::new(3.0, 1.0), DVec2::new(-7.0, 5.5)] {
        let d = built.lens.deflection(p) - truth.deflection(p);
        assert_abs("truth deflection", d.length(), 0.0, 1e-12);
    }
    assert_eq!(built.planes.len(), 2, "two source redshifts");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn member_galaxies_are_the_inversions_halos() {
    let scene = Scene::from_json_str(SCENE).expect("valid scene");
    let plane = LensPlane::new(scene.cosmology, scene.z_lens).expect("plane");
    let catalog = MemberCatalog {
        source_name: "members".into(),
        reference: None,
        members: vec![Member {
            id: "1".into(),
            position: DVec2::new(6.0, -4.0),
            a_arcsec: 1.0,
            b_arcsec: 1.0,
            theta_deg: 0.0,
            mag: 19.0,
            lum: 0.0,
            line: 1,
        }],
        commented: Vec::new(),
        fitted_bcgs: None,
        par_galaxies: Vec::new(),
        par_source: None,
        free_mass_galaxies: Vec::new(),
        mass_galaxies: Vec::new(),
    };
    let grid = CellGrid::regular(DVec2::ZERO, 40.0, 8, 1.0).expect("grid");
    let members =
        build_member_layers(&catalog, &MemberConfig::default(), &plane, &grid).expect("members");
    let components = scene.components(&plane).expect("components");
    let halo = components[1].build(&plane).expect("halo");
    for p in [DVec2::new(7.0, -4.5), DVec2::new(-3.0, 2.0)] {
        let d = halo.deflection(p) - members.layers[0].deflection(p);
        assert_abs("member deflection at C = 1", d.length(), 0.0, 1e-12);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn sis_scene_shows_its_einstein_ring_and_images_trace_back() {
    let text = r#"{"v": 1, "z_lens": 0.3, "fov": 40,
        "lenses": [{"type": "sis", "x": 0, "y": 0, "sigma_v": 700}],
        "sources": [{"type": "point", "x": 1.0, "y": 0.0, "z": 2.0}]}"#;
    let pg = Playground::new(Scene::from_json_str(text).expect("scene")).expect("playground");
    let f = pg.built().source_f[0];
    let theta_e = wslap::sis_theta_e_arcsec(700.0) * f;
    let frame = pg.frame(256);
    assert_eq!(frame.image_rgba.len(), 256 * 256 * 4);
    assert_rel(
        "Einstein radius",
        frame.curves[0].einstein_radius_arcsec,
        theta_e,
        0.01,
    );
    let images = &frame.points[0].images;
    assert_eq!(
        images.len(),
        2,
        "an SIS makes two images of an off-centre point"
    );
    for im in images {
        let landing = &pg.ray(DVec2::new(im.x, im.y))[0];
        assert_abs("beta_x", landing.x, 1.0, 1e-3);
        assert_abs("beta_y", landing.y, 0.0, 1e-3);
        // SIS images at theta_E +- beta on the axis: mu = theta / (theta - theta_E) there.
        let r = im.x.abs();
        assert_rel("magnification", im.magnification, r / (r - theta_e), 1e-3);
    }
    // The image nearer the lens (the saddle) arrives last.
    let saddle = images.iter().find(|i| i.kind == "saddle").expect("saddle");
    assert!(saddle.delay_days > 0.0, "{images:?}");
    let again = pg.images_of(DVec2::new(1.0, 0.0), 2.0);
    assert_eq!(again.len(), 2);
    let levels = pg.contours(ContourKind::Kappa, 64, 2.0, DVec2::ZERO);
    assert!(levels.iter().any(|c| c.level == 1.0), "kappa = 1 contour");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_scenes_say_what_is_wrong() {
    let e = Scene::from_json_str(&SCENE.replace("\"v\": 1", "\"v\": 2")).unwrap_err();
    assert!(matches!(e, SceneError::Version { found: 2 }), "{e}");
    let e = Scene::from_json_str(&SCENE.replace("\"z\": 1.0", "\"z\": 0.1")).unwrap_err();
    assert!(e.to_string().contains("z_s = 0.1"), "{e}");
    let e =
        Scene::from_json_str(&SCENE.replace("\"sigma_v\": 700", "\"sigma_v\": -7")).unwrap_err();
    assert!(matches!(e, SceneError::Lens { index: 0, .. }), "{e}");
    assert!(e.to_string().contains("sigma_v"), "{e}");
    let e = Scene::from_json_str(&SCENE.replace("\"n\": 1.5", "\"n\": 50")).unwrap_err();
    assert!(e.to_string().contains("sources[0].n"), "{e}");
    assert!(matches!(
        Scene::from_json_str(SCENE).unwrap().sources[2],
        SourceSpec::Gaussian { q, .. } if q == 0.5
    ));
}

/// The arrival-time contours of the time-delay lesson's scene: one runs exactly through each
/// saddle image (where the contour crosses itself) and some pass near every image, so the
/// drawing shows where the images sit on the arrival-time surface.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arrival_time_contours_run_through_the_saddle_images() {
    let scene = Scene::from_json_str(
        r#"{"v": 1, "z_lens": 0.3, "fov": 40,
            "lenses": [{"type": "sie", "x": 0, "y": 0, "sigma_v": 800, "q": 0.75, "pa": 30}],
            "sources": [{"type": "point", "x": 2.0, "y": 1.0, "z": 2}]}"#,
    )
    .expect("valid scene");
    let pg = Playground::new(scene).expect("builds");
    let beta = DVec2::new(2.0, 1.0);
    let images = pg.images_of(beta, 2.0);
    let lines = pg.contours(ContourKind::ArrivalTime, 256, 2.0, beta);
    let pixel = 40.0 / 256.0;
    let nearest = |p: DVec2| {
        lines
            .iter()
            .flat_map(|l| l.points.iter())
            .map(|q| q.distance(p))
            .fold(f64::INFINITY, f64::min)
    };
    let saddles: Vec<_> = images.iter().filter(|i| i.kind == "saddle").collect();
    assert!(!saddles.is_empty(), "{images:?}");
    for im in &images {
        let d = nearest(DVec2::new(im.x, im.y));
        let limit = if im.kind == "saddle" {
            2.0 * pixel
        } else {
            3.0
        };
        assert!(
            d <= limit,
            "{} image at ({:.2}, {:.2}): nearest contour {d:.2}″",
            im.kind,
            im.x,
            im.y
        );
    }
}

/// The page's default scene (www/playground/scene.js): an SIE, a member galaxy and shear;
/// sources at three redshifts.
const PAGE_SCENE: &str = r#"{"v": 1, "z_lens": 0.3, "fov": 40,
 "lenses": [{"type": "sie", "x": 0, "y": 0, "sigma_v": 850, "q": 0.75, "pa": 20},
            {"type": "member", "x": 7, "y": -5, "mag": 19},
            {"type": "shear", "gamma1": 0.03, "gamma2": 0.02}],
 "sources": [{"type": "sersic", "x": 1.2, "y": 0.8, "z": 2, "r_eff": 0.6, "n": 1, "q": 0.7, "pa": 30},
             {"type": "gaussian", "x": -1.5, "y": -1.0, "z": 1.2, "sigma": 0.35, "q": 1, "pa": 0},
             {"type": "point", "x": 0.6, "y": -0.4, "z": 3}]}"#;

/// Largest distance (arcsec) from a vertex of `a` to the nearest segment of `b`.
fn farthest_vertex(a: &[Vec<DVec2>], b: &[Vec<DVec2>]) -> f64 {
    let to_segment = |p: DVec2, s: DVec2, e: DVec2| {
        let d = e - s;
        let t = ((p - s).dot(d) / d.length_squared().max(1e-300)).clamp(0.0, 1.0);
        p.distance(s + t * d)
    };
    a.iter()
        .flatten()
        .map(|&p| {
            b.iter()
                .flat_map(|line| line.windows(2).map(move |w| to_segment(p, w[0], w[1])))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn full_frame_curves_from_the_coarser_grid_lie_within_a_pixel_of_the_fine_ones() {
    use wslap::{critical_curves, LensMaps, MapGeometry};
    let pg = Playground::new(Scene::from_json_str(PAGE_SCENE).expect("scene")).expect("pg");
    let frame = pg.frame(512);
    let geometry = MapGeometry::centered(40.0, 512);
    let fine_maps = LensMaps::from_lens(&pg.built().lens, geometry);
    assert_eq!(frame.curves.len(), 3);
    for (coarse, plane) in frame.curves.iter().zip(&pg.built().planes) {
        let fine = critical_curves(&fine_maps, plane.f, plane.z, Some(&pg.built().lens));
        assert_rel(
            "Einstein radius",
            coarse.einstein_radius_arcsec,
            fine.einstein_radius_arcsec,
            0.002,
        );
        for (c, f) in [
            (&coarse.tangential, &fine.tangential),
            (&coarse.radial, &fine.radial),
        ] {
            assert_eq!(c.is_empty(), f.is_empty(), "z = {}", plane.z);
            let pixel = geometry.pixel_arcsec();
            let (there, back) = (farthest_vertex(c, f), farthest_vertex(f, c));
            assert!(
                there < pixel && back < pixel,
                "z = {}: curves {there} and {back} arcsec apart, pixel {pixel}",
                plane.z
            );
        }
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_frame_with_kept_lens_results_is_the_frame_computed_afresh() {
    let scene = Scene::from_json_str(PAGE_SCENE).expect("scene");
    let mut pg = Playground::new(scene.clone()).expect("pg");
    let first = pg.frame(256);
    // Only a source moves: the deflections and curves are kept.
    let mut moved = scene.clone();
    if let SourceSpec::Sersic { x, .. } = &mut moved.sources[0] {
        *x += 0.4;
    }
    pg.set_scene(moved.clone()).expect("scene");
    let kept = pg.frame(256);
    let fresh = Playground::new(moved).expect("pg").frame(256);
    assert_ne!(kept.image_rgba, first.image_rgba, "the arcs moved");
    assert_eq!(kept.image_rgba, fresh.image_rgba, "the same lensed image");
    assert_eq!(kept.source_rgba, fresh.source_rgba);
    // A lens that moves is evaluated again, and moving it back gives the first frame.
    let mut lens_moved = scene.clone();
    if let SceneLens::Member(m) = &mut lens_moved.lenses[1] {
        m.x += 1.0;
    }
    pg.set_scene(lens_moved.clone()).expect("scene");
    let other = pg.frame(256);
    let fresh = Playground::new(lens_moved).expect("pg").frame(256);
    assert_eq!(other.image_rgba, fresh.image_rgba);
    assert_ne!(other.image_rgba, kept.image_rgba, "the member moved");
    for (a, b) in other.curves.iter().zip(&fresh.curves) {
        assert_eq!(a.tangential, b.tangential);
        assert_eq!(a.radial_caustics, b.radial_caustics);
    }
    pg.set_scene(scene).expect("scene");
    assert_eq!(pg.frame(256).image_rgba, first.image_rgba);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_critical_curve_that_leaves_the_view_still_gives_whole_caustics() {
    use wslap::{critical_curves, LensMaps, MapGeometry};
    // An SIE whose tangential curve (major axis ~37″) leaves the 40″ view.
    let text = r#"{"v": 1, "z_lens": 0.3, "fov": 40,
        "lenses": [{"type": "sie", "x": 0, "y": 0, "sigma_v": 1200, "q": 0.6, "pa": 15}],
        "sources": [{"type": "point", "x": 1.0, "y": 0.5, "z": 2.0}]}"#;
    let pg = Playground::new(Scene::from_json_str(text).expect("scene")).expect("playground");
    let lens = &pg.built().lens;
    let plane = &pg.built().planes[0];
    let view = critical_curves(
        &LensMaps::from_lens(lens, MapGeometry::centered(40.0, 256)),
        plane.f,
        plane.z,
        Some(lens),
    );
    assert!(
        view.tangential_leaves_map,
        "the scene's curve must leave the view"
    );
    // Independently: the same lens on a field four times as wide, as fine as the view.
    let whole_geometry = MapGeometry::centered(160.0, 1024);
    let whole = critical_curves(
        &LensMaps::from_lens(lens, whole_geometry),
        plane.f,
        plane.z,
        Some(lens),
    );
    assert!(!whole.tangential_leaves_map);
    let frame = pg.frame(512);
    let c = &frame.curves[0];
    // The image plane keeps the view's curves, cut at its border.
    assert_eq!(c.tangential, view.tangential);
    // The caustic is whole: one loop, the same as on the wide field, drawn closed.
    assert_eq!(c.tangential_caustics.len(), whole.caustics.tangential.len());
    for line in &c.tangential_caustics {
        assert_eq!(line.first(), line.last(), "a loop ends where it starts");
    }
    let pixel = whole_geometry.pixel_arcsec();
    let (there, back) = (
        farthest_vertex(&c.tangential_caustics, &whole.caustics.tangential),
        farthest_vertex(&whole.caustics.tangential, &c.tangential_caustics),
    );
    assert!(
        there < pixel && back < pixel,
        "{there} and {back} arcsec apart"
    );
    assert_rel(
        "Einstein radius",
        c.einstein_radius_arcsec,
        whole.einstein_radius_arcsec,
        0.005,
    );
    assert!(
        c.einstein_radius_arcsec > 20.0,
        "{}",
        c.einstein_radius_arcsec
    );
}
