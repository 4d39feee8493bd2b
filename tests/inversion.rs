//! The inversion between catalogues and solver (METHOD.md sections 3 and 4): cell grid and its
//! refinement, member masses and layers, constraint pixels and weights, the linear system and
//! its normal equations, the NumPy export, and bad settings.

mod common;

use common::{assert_abs, assert_rel};
use glam::DVec2;
use wslap::catalog::{Image, ImageCatalog, ImageSystem, Member, MemberCatalog};
use wslap::inversion::{
    build_constraints, build_member_layers, cell_unit_deflection, ellipse_pixels, npy_header,
    parse_arcs, CellGrid, ColumnInfo, ConstraintConfig, ConstraintError, ConstraintMode,
    ConstraintSet, ConstraintSource, Exclusion, GridConfig, GridError, GridMass, Layer, LayerSplit,
    LinearSystem, MemberConfig, MembersError, RowBlock, SystemConfig, SystemError, Weighting,
};
use wslap::profiles::{gaussian_unit_deflection, MassComponent, Nfw, TruncatedNfw};
use wslap::sky::SkyReference;
use wslap::solver::gram_weighted;
use wslap::{Cosmology, LensPlane};

/// The fast cell kernel vs the reference Gaussian deflection (both accurate to a few ulp).
const KERNEL_RTOL: f64 = 1e-13;
/// Row-by-row `Gamma X` vs the lens equation with the reconstructed lens: the same sums in a
/// different order (arcsec, for deflections of tens of arcsec).
const GAMMA_X_ATOL_ARCSEC: f64 = 1e-10;
/// Normal equations from blocks vs from the whole `Gamma`: different summation order only.
const NORMAL_RTOL: f64 = 1e-12;
/// Ellipse pixel count vs `pi a b / pixel^2` (lattice-point count error ~ perimeter / pixel).
const ELLIPSE_COUNT_RTOL: f64 = 0.1;
/// Member halo rebuilt from its M200, c200 (the concentration is found by bisection to
/// double precision; the TNFW total-mass formula rounds at ~1e-13).
const TNFW_MASS_RTOL: f64 = 1e-10;
/// Least-squares solutions for two frame shifts: a 24-unknown dense solve of a poorly
/// conditioned system (measured 4e-9 on values of ~6).
const SHIFT_ATOL: f64 = 1e-6;

fn plane() -> LensPlane {
    LensPlane::new(Cosmology::default(), 0.3).unwrap()
}

fn image(id: &str, x: f64, y: f64, a: f64, b: f64, theta: f64) -> Image {
    Image {
        id: id.to_string(),
        position: DVec2::new(x, y),
        a_arcsec: a,
        b_arcsec: b,
        theta_deg: theta,
        mag: 0.0,
        line: 1,
    }
}

fn system(id: &str, z: Option<f64>, images: Vec<Image>) -> ImageSystem {
    ImageSystem {
        id: id.to_string(),
        z,
        images,
    }
}

fn catalog(systems: Vec<ImageSystem>) -> ImageCatalog {
    ImageCatalog {
        source_name: "test.cat".to_string(),
        reference: None,
        systems,
    }
}

/// Three systems around an Einstein ring of ~20 arcsec, with ellipses.
fn three_systems() -> ImageCatalog {
    catalog(vec![
        system(
            "1",
            Some(2.0),
            vec![
                image("1.1", 18.0, 4.0, 1.0, 0.4, 10.0),
                image("1.2", -17.0, -6.0, 0.8, 0.5, 100.0),
                image("1.3", 3.0, 21.0, 0.6, 0.6, 0.0),
            ],
        ),
        system(
            "2",
            Some(3.5),
            vec![
                image("2.1", -5.0, 19.0, 1.2, 0.3, 45.0),
                image("2.2", 6.0, -20.0, 0.7, 0.4, -30.0),
            ],
        ),
        system(
            "3",
            Some(1.2),
            vec![
                image("3.1", 12.0, -12.0, 0.5, 0.5, 0.0),
                image("3.2", -14.0, 10.0, 0.5, 0.3, 80.0),
            ],
        ),
    ])
}

fn member(id: &str, x: f64, y: f64, mag: f64) -> Member {
    Member {
        id: id.to_string(),
        position: DVec2::new(x, y),
        a_arcsec: 1.0,
        b_arcsec: 1.0,
        theta_deg: 0.0,
        mag,
        lum: 1.0,
        line: 3,
    }
}

fn members() -> MemberCatalog {
    MemberCatalog {
        source_name: "members.cat".to_string(),
        reference: None,
        members: vec![
            member("a", 0.0, 0.0, 17.0),
            member("b", 10.0, 5.0, 19.5),
            member("c", -8.0, 12.0, 18.2),
            member("d", 15.0, -15.0, 20.1),
            member("e", -20.0, -3.0, 19.0),
            member("f", 3.0, -9.0, 18.9),
        ],
    }
}

/// A small deterministic generator in [0, 1) (no RNG dependency in the tests).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn grid_geometry_and_auto_field() {
    let g = CellGrid::regular(DVec2::new(10.0, -5.0), 40.0, 4, 0.75).unwrap();
    assert_eq!(g.len(), 16);
    assert_abs("cell 0 x", g.cells[0].center.x, -5.0, 1e-12);
    assert_abs("cell 0 y", g.cells[0].center.y, -20.0, 1e-12);
    // j = row * n + column: cell 6 is column 2, row 1.
    assert_abs("cell 6 x", g.cells[6].center.x, 15.0, 1e-12);
    assert_abs("cell 6 y", g.cells[6].center.y, -10.0, 1e-12);
    assert_abs("sigma", g.cells[5].sigma_arcsec, 7.5, 1e-12);
    assert!(g.contains(DVec2::new(29.9, 14.9), 0.0));
    assert!(!g.contains(DVec2::new(30.5, 0.0), 0.0));
    assert!(g.contains(DVec2::new(30.5, 0.0), 1.0));

    let config = GridConfig {
        cells: 8,
        ..GridConfig::default()
    };
    let wide = [DVec2::new(-40.0, 0.0), DVec2::new(60.0, 10.0)];
    let g = CellGrid::from_config(&config, &wide).unwrap();
    assert_abs("auto centre x", g.center.x, 10.0, 1e-12);
    assert_abs("auto width", g.width_arcsec, 130.0, 1e-9);
    let compact = [DVec2::new(-5.0, 0.0), DVec2::new(5.0, 2.0)];
    let g = CellGrid::from_config(&config, &compact).unwrap();
    assert_abs("minimum width", g.width_arcsec, 60.0, 1e-12);
    assert_eq!(
        CellGrid::from_config(&config, &[]).unwrap_err(),
        GridError::NoPositions
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn grid_refinement_splits_the_densest_cells() {
    let g = CellGrid::regular(DVec2::ZERO, 40.0, 4, 0.75).unwrap();
    let masses: Vec<f64> = (0..16)
        .map(|j| {
            if [5, 6, 9, 10].contains(&j) {
                10.0
            } else {
                1.0
            }
        })
        .collect();
    let r = g.refine(&masses, 0.25).unwrap();
    assert_eq!(r.len(), 12 + 16);
    let area: f64 = r.cells.iter().map(|c| c.size_arcsec * c.size_arcsec).sum();
    assert_rel("area kept", area, 1600.0, 1e-12);
    for c in &r.cells {
        let parent = &g.cells[c.parent];
        if [5, 6, 9, 10].contains(&c.parent) {
            assert_eq!(c.level, 1);
            assert_abs("child size", c.size_arcsec, 5.0, 1e-12);
            assert_abs("child sigma", c.sigma_arcsec, 3.75, 1e-12);
            assert_abs("offset x", (c.center.x - parent.center.x).abs(), 2.5, 1e-12);
            assert_abs("offset y", (c.center.y - parent.center.y).abs(), 2.5, 1e-12);
        } else {
            assert_eq!(
                c,
                &wslap::inversion::Cell {
                    parent: c.parent,
                    ..*parent
                }
            );
        }
    }
    assert!(matches!(
        g.refine(&masses[1..], 0.25),
        Err(GridError::MassCount { .. })
    ));
    assert!(matches!(
        g.refine(&masses, 0.0),
        Err(GridError::BadParameter { .. })
    ));
}

/// The default width 0.75 cell is smooth: relative ripple of the convergence of equal masses
/// in the middle of a 16 x 16 grid below 1e-3, while 0.5 cell ripples by more than 1%.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn default_cell_width_is_smooth() {
    let ripple = |factor: f64| {
        let g = CellGrid::regular(DVec2::ZERO, 16.0, 16, factor).unwrap();
        let mass = GridMass::new(&g, vec![1.0; g.len()]).unwrap();
        let k: Vec<f64> = (0..=20)
            .flat_map(|i| (0..=20).map(move |j| DVec2::new(i as f64 * 0.1, j as f64 * 0.1)))
            .map(|p| mass.kappa(p))
            .collect();
        let (lo, hi) = k
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        hi / lo - 1.0
    };
    let default = GridConfig::default().cell_sigma_factor;
    assert!(ripple(default) < 1e-3, "ripple {}", ripple(default));
    assert!(ripple(0.5) > 1e-2, "ripple {}", ripple(0.5));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn cell_kernel_matches_gaussian_deflection() {
    let sigma = 1.7;
    let inv = 0.5 / (sigma * sigma);
    for &(dx, dy) in &[
        (0.0, 0.0),
        (1e-9, -2e-9),
        (0.3, 0.1),
        (-1.2, 2.0),
        (5.0, -3.0),
        (14.0, 0.5),
        (-300.0, 200.0),
    ] {
        let (ax, ay) = cell_unit_deflection(dx, dy, inv);
        let (rx, ry) = gaussian_unit_deflection(dx, dy, sigma);
        let scale = rx.hypot(ry).max(1e-300);
        assert_abs("ax", ax / scale, rx / scale, KERNEL_RTOL);
        assert_abs("ay", ay / scale, ry / scale, KERNEL_RTOL);
    }
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn member_masses_follow_magnitudes() {
    let plane = plane();
    let config = MemberConfig {
        mag_star: Some(19.0),
        ..MemberConfig::default()
    };
    assert_rel("L* mass", config.mass_msun(19.0, 19.0), 1.0e12, 1e-14);
    assert_rel(
        "1 mag brighter",
        config.mass_msun(18.0, 19.0),
        1.0e12 * 10f64.powf(0.4),
        1e-14,
    );
    // Default mag* from the distance modulus: D_L = (1 + z)^2 D_l.
    let d_lum_mpc = 1.69 * plane.d_l_mpc;
    let expected = -21.5 + 5.0 * (d_lum_mpc * 1e6 / 10.0).log10();
    assert_rel(
        "mag*",
        MemberConfig::default().mag_star_on(&plane),
        expected,
        1e-12,
    );

    let grid = CellGrid::regular(DVec2::ZERO, 80.0, 4, 0.75).unwrap();
    let cat = MemberCatalog {
        members: vec![
            member("lstar", 5.0, 5.0, 19.0),
            member("bright", -5.0, 0.0, 18.0),
        ],
        ..members()
    };
    let model = build_member_layers(&cat, &config, &plane, &grid).unwrap();
    assert_rel("halo mass", model.halos[0].mass_msun, 1e12, 1e-14);
    assert_rel(
        "L/L*",
        model.halos[1].luminosity_lstar,
        10f64.powf(0.4),
        1e-14,
    );
    let kpc_per_arcsec = plane.mpc_per_arcsec * 1e3;
    let r_t = model.halos[0].r_trunc_arcsec.unwrap() * kpc_per_arcsec;
    assert_rel("r_t of L* (kpc)", r_t, 40.0, 1e-12);
    assert_rel(
        "r_s of L* (kpc)",
        model.halos[0].r_s_arcsec * kpc_per_arcsec,
        10.0,
        1e-12,
    );
    // Sizes grow as M^(1/3): 10^0.4 in mass is 10^(0.4/3) in radius.
    let r_t_bright = model.halos[1].r_trunc_arcsec.unwrap() * kpc_per_arcsec;
    assert_rel(
        "r_t of the brighter",
        r_t_bright,
        40.0 * 10f64.powf(0.4 / 3.0),
        1e-12,
    );
    // The truncated halo's total mass is the catalogue mass.
    for h in &model.halos {
        let t = TruncatedNfw::new(
            h.position,
            h.m200_msun,
            h.c200,
            h.r_trunc_arcsec.unwrap(),
            &plane,
        )
        .unwrap();
        assert_rel(
            "TNFW total mass",
            t.total_mass_msun(),
            h.mass_msun,
            TNFW_MASS_RTOL,
        );
        assert_rel("TNFW r_s", t.r_s_arcsec(), h.r_s_arcsec, TNFW_MASS_RTOL);
    }
    // An L* halo deflects at 5 kpc as an SIS of 200 km/s does (module documentation).
    let lstar = Layer::from_components(
        "L*",
        vec![Box::new(
            TruncatedNfw::new(
                DVec2::ZERO,
                model.halos[0].m200_msun,
                model.halos[0].c200,
                r_t / kpc_per_arcsec,
                &plane,
            )
            .unwrap(),
        )],
    );
    let sis_200 = 4.0 * std::f64::consts::PI * (200.0f64 / 299_792.458).powi(2) * 206_264.806;
    let alpha_5kpc = lstar.deflection(DVec2::new(5.0 / kpc_per_arcsec, 0.0)).x;
    assert_rel("L* deflection at 5 kpc", alpha_5kpc, sis_200, 0.1);
    // One layer holding both; its deflection is the sum of the halos'.
    assert_eq!(model.layers.len(), 1);
    let p = DVec2::new(7.0, -3.0);
    let sum: DVec2 = model
        .halos
        .iter()
        .map(|h| {
            TruncatedNfw::new(
                h.position,
                h.m200_msun,
                h.c200,
                h.r_trunc_arcsec.unwrap(),
                &plane,
            )
            .unwrap()
            .deflection(p)
        })
        .sum();
    assert_abs("layer x", model.layers[0].deflection(p).x, sum.x, 1e-14);
    assert_abs("layer y", model.layers[0].deflection(p).y, sum.y, 1e-14);

    let nfw_config = MemberConfig {
        profile: wslap::inversion::HaloProfile::Nfw,
        ..config
    };
    let model = build_member_layers(&cat, &nfw_config, &plane, &grid).unwrap();
    assert_rel("NFW M200 = mass", model.halos[0].m200_msun, 1e12, 1e-14);
    assert!(model.halos[0].r_trunc_arcsec.is_none());
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn layer_splits_partition_the_members() {
    let plane = plane();
    let grid = CellGrid::regular(DVec2::ZERO, 60.0, 4, 0.75).unwrap();
    let cat = members();
    let layers_of = |split: &str| {
        let config = MemberConfig {
            layers: split.parse().unwrap(),
            mag_star: Some(19.0),
            ..MemberConfig::default()
        };
        build_member_layers(&cat, &config, &plane, &grid)
            .unwrap()
            .layers
    };
    let p = DVec2::new(4.0, 7.0);
    let single = layers_of("single");
    assert_eq!(single.len(), 1);
    assert_eq!(single[0].members, vec![0, 1, 2, 3, 4, 5]);
    for (split, expected) in [
        ("bcg", vec![vec![0], vec![1, 2, 3, 4, 5]]),
        (
            "brightest:3",
            vec![vec![0], vec![2], vec![5], vec![1, 3, 4]],
        ),
        (
            "brightest:10",
            vec![vec![0], vec![2], vec![5], vec![4], vec![1], vec![3]],
        ),
    ] {
        let layers = layers_of(split);
        let got: Vec<Vec<usize>> = layers.iter().map(|l| l.members.clone()).collect();
        assert_eq!(got, expected, "{split}");
        let total: DVec2 = layers.iter().map(|l| l.deflection(p)).sum();
        assert_abs("split sum x", total.x, single[0].deflection(p).x, 1e-13);
        assert_abs("split sum y", total.y, single[0].deflection(p).y, 1e-13);
    }
    assert_eq!(layers_of("bcg")[0].name, "bcg");
    assert!(layers_of("none").is_empty());
    let json = serde_json::to_string(&LayerSplit::Brightest(3)).unwrap();
    assert_eq!(json, "\"brightest:3\"");
    assert_eq!(
        serde_json::from_str::<LayerSplit>(&json).unwrap(),
        LayerSplit::Brightest(3)
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn members_outside_the_field_are_warned_and_left_out() {
    let grid = CellGrid::regular(DVec2::ZERO, 60.0, 4, 0.75).unwrap();
    let mut cat = members();
    cat.members.push(member("far", 300.0, 0.0, 18.0));
    cat.members.push(member("edge", 33.0, 0.0, 18.0)); // inside the 6 arcsec margin
    let config = MemberConfig {
        mag_star: Some(19.0),
        ..MemberConfig::default()
    };
    let model = build_member_layers(&cat, &config, &plane(), &grid).unwrap();
    assert_eq!(model.halos.len(), 7);
    assert_eq!(model.warnings.len(), 1);
    assert!(model.warnings[0].contains("member far") && model.warnings[0].contains("members.cat"));
    assert!(!model.layers[0].members.contains(&6));
    assert!(model.layers[0].members.contains(&7));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn ellipse_pixels_fill_the_ellipse() {
    let (a, b, theta, pix) = (2.0, 1.0, 30.0, 0.1);
    let c = DVec2::new(3.0, -4.0);
    let pixels = ellipse_pixels(c, a, b, theta, pix);
    let expected = std::f64::consts::PI * a * b / (pix * pix);
    assert_rel(
        "pixel count",
        pixels.len() as f64,
        expected,
        ELLIPSE_COUNT_RTOL,
    );
    let (s, co) = theta.to_radians().sin_cos();
    for p in &pixels {
        let d = *p - c;
        let (u, v) = (d.x * co + d.y * s, -d.x * s + d.y * co);
        assert!((u / a).powi(2) + (v / b).powi(2) <= 1.0 + 1e-12);
    }
    // The far end of the major axis is reached along theta.
    let reach = pixels
        .iter()
        .map(|p| (*p - c).dot(DVec2::new(co, s)))
        .fold(0.0, f64::max);
    assert!(reach > a - 2.0 * pix, "{reach}");
    assert_eq!(ellipse_pixels(c, 0.01, 0.01, 0.0, 0.2), vec![c]);
    assert_eq!(ellipse_pixels(c, 0.0, 0.0, 0.0, 0.2), vec![c]);
}

fn weight_sums(set: &ConstraintSet) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut per_system = vec![0.0; set.systems.len()];
    let mut per_image: Vec<Vec<f64>> = set
        .systems
        .iter()
        .map(|s| vec![0.0; s.images.len()])
        .collect();
    for p in &set.pixels {
        per_system[p.system] += p.weight;
        per_image[p.system][p.image] += p.weight;
    }
    (per_system, per_image)
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn weights_per_image_system_and_pixel() {
    let cat = three_systems();
    let sigma = 0.5;
    let inv_var = 1.0 / (sigma * sigma);
    for weighting in [
        Weighting::EqualPerImage,
        Weighting::EqualPerSystem,
        Weighting::EqualPerPixel,
    ] {
        let config = ConstraintConfig {
            weighting,
            sigma_pos_arcsec: sigma,
            ..ConstraintConfig::default()
        };
        let set = build_constraints(ConstraintSource::Catalog(&cat), &config, &[]).unwrap();
        assert_eq!(set.systems.len(), 3);
        assert!(set.pixels.len() > 100, "{}", set.pixels.len());
        let (per_system, per_image) = weight_sums(&set);
        for (s, sys) in set.systems.iter().enumerate() {
            let n: usize = set.pixels.iter().filter(|p| p.system == s).count();
            assert_eq!(n, sys.n_pixels);
            match weighting {
                Weighting::EqualPerImage => {
                    for w in &per_image[s] {
                        assert_rel("image weight", *w, inv_var, 1e-12);
                    }
                }
                Weighting::EqualPerSystem => {
                    assert_rel("system weight", per_system[s], inv_var, 1e-12)
                }
                Weighting::EqualPerPixel => {
                    assert_rel("pixel weights", per_system[s], n as f64 * inv_var, 1e-12)
                }
            }
        }
    }
    let point = ConstraintConfig {
        mode: ConstraintMode::Point,
        ..ConstraintConfig::default()
    };
    let set = build_constraints(ConstraintSource::Catalog(&cat), &point, &[]).unwrap();
    assert_eq!(set.pixels.len(), 7);
    assert!(set.pixels.iter().all(|p| (p.weight - 4.0).abs() < 1e-12));
    assert_eq!(set.pixels[3].position, DVec2::new(-5.0, 19.0));
    assert_eq!((set.pixels[3].system, set.pixels[3].image), (1, 0));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn systems_are_excluded_for_redshift_single_image_and_hold_out() {
    let mut cat = three_systems();
    cat.systems[1].z = None;
    cat.systems.push(system(
        "4",
        Some(2.0),
        vec![image("4.1", 1.0, 1.0, 0.5, 0.5, 0.0)],
    ));
    let config = ConstraintConfig::default();
    let set =
        build_constraints(ConstraintSource::Catalog(&cat), &config, &["3".to_string()]).unwrap();
    let ids: Vec<&str> = set.systems.iter().map(|s| s.id.as_str()).collect();
    assert_eq!(ids, ["1"]);
    let excluded: Vec<(&str, Exclusion)> = set
        .excluded
        .iter()
        .map(|e| (e.id.as_str(), e.reason))
        .collect();
    assert_eq!(
        excluded,
        [
            ("2", Exclusion::UnknownRedshift),
            ("3", Exclusion::HeldOut),
            ("4", Exclusion::SingleImage)
        ]
    );
    assert_eq!(
        set.warnings,
        [
            "test.cat: system 2 has no redshift and no default_z is set: not used",
            "test.cat: system 4 has a single image: not used"
        ]
    );
    let with_default = ConstraintConfig {
        default_z: Some(2.5),
        ..config.clone()
    };
    let set = build_constraints(ConstraintSource::Catalog(&cat), &with_default, &[]).unwrap();
    assert_eq!(set.systems[1].z, 2.5);
    assert!(set.systems[1].z_assumed && !set.systems[0].z_assumed);
    assert_eq!(
        set.warnings[0],
        "test.cat: system 2 has no redshift: default_z = 2.5 assumed"
    );
    let err = build_constraints(ConstraintSource::Catalog(&cat), &config, &["9".to_string()])
        .unwrap_err();
    assert!(
        matches!(err, ConstraintError::UnknownHoldOut { ref id, .. } if id == "9"),
        "{err}"
    );
    let all: Vec<String> = ["1", "2", "3", "4"].iter().map(|s| s.to_string()).collect();
    let err = build_constraints(ConstraintSource::Catalog(&cat), &config, &all).unwrap_err();
    assert!(matches!(err, ConstraintError::NoSystems { .. }), "{err}");
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn arc_files_parse_and_report_errors() {
    let text = r#"{"systems": [
        {"id": "1", "z": 2.1, "pixels": [[1.0, 2.0], [1.1, 2.0], [1.2, 2.0]]},
        {"id": 2, "images": [[[5.0, 5.0]], [[-5.0, -5.0], [-5.1, -5.0]]]}]}"#;
    let arcs = parse_arcs(text, "arcs.json").unwrap();
    assert_eq!(arcs.systems[1].id, "2");
    assert_eq!(arcs.systems[1].z, None);
    assert_eq!(arcs.systems[1].images.len(), 2);
    let config = ConstraintConfig {
        mode: ConstraintMode::Arcs,
        default_z: Some(3.0),
        ..ConstraintConfig::default()
    };
    let set = build_constraints(ConstraintSource::Arcs(&arcs), &config, &[]).unwrap();
    assert_eq!(set.pixels.len(), 6);
    let (per_system, _) = weight_sums(&set);
    assert_rel("flat arc = one image", per_system[0], 4.0, 1e-12);
    assert_rel("two images", per_system[1], 8.0, 1e-12);
    let err = build_constraints(
        ConstraintSource::Arcs(&arcs),
        &ConstraintConfig::default(),
        &[],
    )
    .unwrap_err();
    assert!(matches!(err, ConstraintError::ModeMismatch { .. }), "{err}");

    for (bad, needle) in [
        (
            r#"{"systems": [{"id": "7", "z": 2, "pixels": []}]}"#,
            "system 7",
        ),
        (
            r#"{"systems": [{"id": "7", "z": -1, "pixels": [[0, 0]]}]}"#,
            "z = -1",
        ),
        (
            r#"{"systems": [{"id": "7", "pixels": [[0, 0]], "images": [[[0, 0]]]}]}"#,
            "exactly one",
        ),
        (
            r#"{"systems": [{"id": "7", "pixels": [[0, 0]]}, {"id": "7", "pixels": [[0, 0]]}]}"#,
            "twice",
        ),
        (
            "{\"systems\": [\n{\"id\": \"7\", \"pixel\": []}]}",
            "line 2",
        ),
    ] {
        let err = parse_arcs(bad, "arcs.json").unwrap_err().to_string();
        assert!(err.contains("arcs.json") && err.contains(needle), "{err}");
    }
}

/// A 4 x 4 grid, one true layer (a truncated NFW and an NFW) and the member layers of
/// `split`, and the ellipse pixels of the three systems.
fn small_system(split: &str, config: &SystemConfig) -> LinearSystem {
    small_system_with_prior(split, config, None)
}

/// [`small_system`] with `c_prior_sigma` on the member layers (the true layer has none).
fn small_system_with_prior(
    split: &str,
    config: &SystemConfig,
    c_prior_sigma: Option<f64>,
) -> LinearSystem {
    let plane = plane();
    let constraints = build_constraints(
        ConstraintSource::Catalog(&three_systems()),
        &ConstraintConfig {
            pixel_arcsec: 0.25,
            ..ConstraintConfig::default()
        },
        &[],
    )
    .unwrap();
    let positions: Vec<DVec2> = constraints.pixels.iter().map(|p| p.position).collect();
    let grid = CellGrid::from_config(
        &GridConfig {
            cells: 4,
            ..GridConfig::default()
        },
        &positions,
    )
    .unwrap();
    let truth = Layer::from_components(
        "truth",
        vec![
            Box::new(TruncatedNfw::new(DVec2::new(2.0, 3.0), 3e12, 8.0, 8.0, &plane).unwrap()),
            Box::new(Nfw::new(DVec2::new(-10.0, 5.0), 2e13, 6.0, &plane).unwrap()),
        ],
    );
    let member_config = MemberConfig {
        layers: split.parse().unwrap(),
        mag_star: Some(19.0),
        c_prior_sigma,
        ..MemberConfig::default()
    };
    let mut layers = vec![truth];
    layers.extend(
        build_member_layers(&members(), &member_config, &plane, &grid)
            .unwrap()
            .layers,
    );
    LinearSystem::build(&grid, &layers, &constraints, &plane, config).unwrap()
}

fn random_x(sys: &LinearSystem, seed: u64) -> Vec<f64> {
    let mut state = seed;
    let mut x: Vec<f64> = (0..sys.n_columns())
        .map(|_| 0.1 + 2.0 * lcg(&mut state))
        .collect();
    for c in sys.layer_columns() {
        x[c] = 1.0;
    }
    for c in sys.beta_x_columns().chain(sys.beta_y_columns()) {
        x[c] = sys.theta_shift_arcsec + 20.0 * (lcg(&mut state) - 0.5);
    }
    x
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn gamma_x_is_the_lens_equation_of_the_reconstructed_lens() {
    let sys = small_system("bcg", &SystemConfig::default());
    let n_pix = sys.constraints.pixels.len();
    assert_eq!(sys.n_rows, 2 * n_pix);
    assert_eq!(sys.n_columns(), 16 + 3 + 2 * 3);
    let x = random_x(&sys, 7);
    let lens = sys.reconstructed_lens(&x).unwrap();
    let betas = sys.betas_arcsec(&x).unwrap();
    let mut block = RowBlock::default();
    sys.rows(0..n_pix, &mut block).unwrap();
    let n = sys.n_columns();
    let mut max_alpha: f64 = 0.0;
    for (i, pixel) in sys.constraints.pixels.iter().enumerate() {
        let f = sys.distance_ratios[pixel.system];
        let alpha = lens.deflection(pixel.position);
        max_alpha = max_alpha.max(alpha.length());
        // Lens equation: theta + S = f alpha(theta) + beta + S.
        let model = f * alpha + betas[pixel.system] + DVec2::splat(sys.theta_shift_arcsec);
        for (axis, model_axis) in [(0, model.x), (1, model.y)] {
            let row = &block.gamma[(2 * i + axis) * n..(2 * i + axis + 1) * n];
            let gx: f64 = row.iter().zip(&x).map(|(g, v)| g * v).sum();
            assert_abs("Gamma X", gx, model_axis, GAMMA_X_ATOL_ARCSEC);
        }
        assert_eq!(
            block.theta[2 * i],
            pixel.position.x + sys.theta_shift_arcsec
        );
        assert_eq!(block.weights[2 * i + 1], pixel.weight);
    }
    assert!(max_alpha > 5.0, "the test lens must deflect: {max_alpha}");
    // Cell masses in Msun and the beta shift round trip.
    let masses = sys.cell_masses_msun(&x).unwrap();
    assert_rel("cell mass", masses[3], x[3] * 1e12, 1e-15);
    assert_abs(
        "beta_y",
        betas[2].y,
        x[sys.beta_y_columns().start + 2] - sys.theta_shift_arcsec,
        1e-12,
    );
    assert!(matches!(
        sys.reconstructed_lens(&x[1..]),
        Err(SystemError::Length { .. })
    ));
    // The column list says what each unknown is.
    assert!(matches!(sys.columns[0], ColumnInfo::Cell { index: 0, .. }));
    assert!(matches!(&sys.columns[17], ColumnInfo::Layer { name, .. } if name == "bcg"));
    assert!(matches!(&sys.columns[19], ColumnInfo::BetaX { id, .. } if id == "1"));
    assert!(matches!(&sys.columns[24], ColumnInfo::BetaY { id, .. } if id == "3"));
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn normal_equations_from_blocks_equal_the_whole_gamma() {
    let whole = small_system("single", &SystemConfig::default());
    let tiny = SystemConfig {
        block_mbytes: 0.002,
        threads: 3,
        ..SystemConfig::default()
    };
    let blocked = small_system("single", &tiny);
    assert!(blocked.pixels_per_block() < 10 && whole.pixels_per_block() > whole.n_rows);
    let n = whole.n_columns();
    let mut block = RowBlock::default();
    whole
        .rows(0..whole.constraints.pixels.len(), &mut block)
        .unwrap();
    let mut other = RowBlock::default();
    blocked
        .rows(0..blocked.constraints.pixels.len(), &mut other)
        .unwrap();
    assert_eq!(block, other, "rows do not depend on threads or blocks");
    let (a, b) =
        gram_weighted(&block.gamma, whole.n_rows, n, &block.weights, &block.theta).unwrap();
    for (name, sys) in [("whole", &whole), ("blocked", &blocked)] {
        for i in 0..n {
            let scale_b =
                (a[i * n + i] * block.theta.iter().map(|t| t * t).fold(0.0, f64::max)).sqrt();
            assert_abs(name, sys.b[i] / scale_b, b[i] / scale_b, NORMAL_RTOL);
            for j in 0..n {
                let scale = (a[i * n + i] * a[j * n + j]).sqrt();
                assert_abs(
                    name,
                    sys.a[i * n + j] / scale,
                    a[i * n + j] / scale,
                    NORMAL_RTOL,
                );
            }
        }
    }
    let twt: f64 = block
        .theta
        .iter()
        .zip(&block.weights)
        .map(|(t, w)| w * t * t)
        .sum();
    assert_rel("theta W theta", blocked.theta_w_theta, twt, NORMAL_RTOL);
}

/// Dense least squares `A x = -b` by Gaussian elimination with partial pivoting.
fn solve_dense(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut m: Vec<f64> = a.to_vec();
    let mut r: Vec<f64> = b.iter().map(|v| -v).collect();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| m[i * n + k].abs().total_cmp(&m[j * n + k].abs()))
            .unwrap();
        for c in 0..n {
            m.swap(k * n + c, p * n + c);
        }
        r.swap(k, p);
        for i in k + 1..n {
            let f = m[i * n + k] / m[k * n + k];
            for c in k..n {
                m[i * n + c] -= f * m[k * n + c];
            }
            r[i] -= f * r[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|c| m[k * n + c] * x[c]).sum();
        x[k] = (r[k] - s) / m[k * n + k];
    }
    x
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn frame_shift_round_trips_through_the_solution() {
    let auto = small_system("single", &SystemConfig::default());
    let reach = auto
        .constraints
        .pixels
        .iter()
        .map(|p| p.position.abs().max_element())
        .fold(0.0, f64::max);
    assert_eq!(
        auto.theta_shift_arcsec,
        (reach + auto.grid.width_arcsec).ceil()
    );
    let shifted = small_system(
        "single",
        &SystemConfig {
            theta_shift_arcsec: Some(auto.theta_shift_arcsec + 37.0),
            ..SystemConfig::default()
        },
    );
    let n = auto.n_columns();
    assert_eq!(auto.a, shifted.a, "A does not depend on the shift");
    let x1 = solve_dense(&auto.a, &auto.b, n);
    let x2 = solve_dense(&shifted.a, &shifted.b, n);
    for c in auto.cell_columns().chain(auto.layer_columns()) {
        assert_abs("mass or C", x2[c], x1[c], SHIFT_ATOL);
    }
    for (b1, b2) in auto
        .betas_arcsec(&x1)
        .unwrap()
        .iter()
        .zip(shifted.betas_arcsec(&x2).unwrap())
    {
        assert_abs("beta x", b2.x, b1.x, SHIFT_ATOL);
        assert_abs("beta y", b2.y, b1.y, SHIFT_ATOL);
    }
    let raw = x2[shifted.beta_x_columns().start] - x1[auto.beta_x_columns().start];
    assert_abs("raw beta moves by the shift", raw, 37.0, SHIFT_ATOL);
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_settings_give_their_errors() {
    let field_of = |e: &GridError| match e {
        GridError::BadParameter { field, .. } => *field,
        _ => "",
    };
    for (config, field) in [
        (
            GridConfig {
                cells: 0,
                ..GridConfig::default()
            },
            "cells",
        ),
        (
            GridConfig {
                cell_sigma_factor: 5.0,
                ..GridConfig::default()
            },
            "cell_sigma_factor",
        ),
        (
            GridConfig {
                width_arcsec: Some(-1.0),
                ..GridConfig::default()
            },
            "width_arcsec",
        ),
        (
            GridConfig {
                refine_fraction: 1.5,
                ..GridConfig::default()
            },
            "refine_fraction",
        ),
        (
            GridConfig {
                margin_factor: f64::NAN,
                ..GridConfig::default()
            },
            "margin_factor",
        ),
    ] {
        assert_eq!(field_of(&config.validate().unwrap_err()), field);
    }
    let err = MemberConfig {
        mass_to_light: -1.0,
        ..MemberConfig::default()
    }
    .validate()
    .unwrap_err();
    assert!(err.to_string().contains("mass_to_light = -1"), "{err}");
    for sigma in [0.0, -0.5, f64::NAN, 1e3] {
        let err = MemberConfig {
            c_prior_sigma: Some(sigma),
            ..MemberConfig::default()
        }
        .validate()
        .unwrap_err();
        assert!(err.to_string().contains("c_prior_sigma"), "{err}");
    }
    for bad in ["brightest:0", "brightest", "all", "brightest:x"] {
        assert!(
            matches!(
                bad.parse::<LayerSplit>(),
                Err(MembersError::BadLayers { .. })
            ),
            "{bad}"
        );
    }
    let err = serde_json::from_str::<MemberConfig>(r#"{"layers": "three"}"#).unwrap_err();
    assert!(err.to_string().contains("three"), "{err}");
    let err = serde_json::from_str::<GridConfig>(r#"{"cels": 3}"#).unwrap_err();
    assert!(err.to_string().contains("cels"), "{err}");
    let config: GridConfig = serde_json::from_str(r#"{"cells": 16}"#).unwrap();
    assert_eq!(
        config,
        GridConfig {
            cells: 16,
            ..GridConfig::default()
        }
    );

    let err = ConstraintConfig {
        pixel_arcsec: 0.0,
        ..ConstraintConfig::default()
    }
    .validate()
    .unwrap_err();
    assert!(err.to_string().contains("pixel_arcsec"), "{err}");
    let err = SystemConfig {
        mass_unit_msun: 0.0,
        ..SystemConfig::default()
    }
    .validate()
    .unwrap_err();
    assert!(err.to_string().contains("mass_unit_msun"), "{err}");

    // A member too bright for any halo, and a member with a non-finite magnitude.
    let grid = CellGrid::regular(DVec2::ZERO, 60.0, 4, 0.75).unwrap();
    let config = MemberConfig {
        mag_star: Some(19.0),
        ..MemberConfig::default()
    };
    for (mag, needle) in [(f64::NAN, "mag = NaN"), (5.0, "m200")] {
        let cat = MemberCatalog {
            members: vec![member("x1", 0.0, 0.0, mag)],
            ..members()
        };
        let err = build_member_layers(&cat, &config, &plane(), &grid)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("members.cat") && err.contains("member x1") && err.contains(needle),
            "{err}"
        );
    }
    // A huge ellipse, a non-finite image field.
    let mut cat = three_systems();
    cat.systems[0].images[0].a_arcsec = 1000.0;
    let err = build_constraints(
        ConstraintSource::Catalog(&cat),
        &ConstraintConfig::default(),
        &[],
    )
    .unwrap_err();
    assert!(
        matches!(err, ConstraintError::TooManyPixels { ref id, .. } if id == "1.1"),
        "{err}"
    );
    cat.systems[0].images[0].a_arcsec = f64::INFINITY;
    let err = build_constraints(
        ConstraintSource::Catalog(&cat),
        &ConstraintConfig::default(),
        &[],
    )
    .unwrap_err();
    assert!(err.to_string().contains("image 1.1: a = inf"), "{err}");

    // A source in front of the lens.
    let mut cat = three_systems();
    cat.systems[2].z = Some(0.2);
    let constraints = build_constraints(
        ConstraintSource::Catalog(&cat),
        &ConstraintConfig::default(),
        &[],
    )
    .unwrap();
    let err = LinearSystem::build(&grid, &[], &constraints, &plane(), &SystemConfig::default())
        .unwrap_err();
    assert!(
        matches!(err, SystemError::Redshift { ref system, .. } if system == "3"),
        "{err}"
    );
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn npy_header_is_valid() {
    for shape in [vec![3usize, 25], vec![7], vec![123_456, 4_200]] {
        let h = npy_header(&shape);
        assert_eq!(&h[..8], b"\x93NUMPY\x01\x00");
        assert_eq!(h.len() % 64, 0);
        let len = u16::from_le_bytes([h[8], h[9]]) as usize;
        assert_eq!(len + 10, h.len());
        assert_eq!(*h.last().unwrap(), b'\n');
        let dict = std::str::from_utf8(&h[10..]).unwrap();
        let dims = if shape.len() == 1 {
            format!("({},)", shape[0])
        } else {
            format!("({}, {})", shape[0], shape[1])
        };
        assert!(
            dict.starts_with(&format!(
                "{{'descr': '<f8', 'fortran_order': False, 'shape': {dims}, }}"
            )),
            "{dict}"
        );
    }
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn export_writes_gamma_theta_weights_and_columns() {
    let sys = small_system(
        "bcg",
        &SystemConfig {
            block_mbytes: 0.005,
            ..SystemConfig::default()
        },
    );
    let dir = std::env::temp_dir().join(format!("wslap-export-{}", std::process::id()));
    wslap::inversion::export_system(&sys, &dir).unwrap();
    let n = sys.n_columns();
    let gamma = std::fs::read(dir.join("gamma.npy")).unwrap();
    let header = npy_header(&[sys.n_rows, n]);
    assert_eq!(&gamma[..header.len()], &header[..]);
    assert_eq!(gamma.len(), header.len() + sys.n_rows * n * 8);
    let mut block = RowBlock::default();
    sys.rows(0..sys.constraints.pixels.len(), &mut block)
        .unwrap();
    let values: Vec<f64> = gamma[header.len()..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(values, block.gamma);
    let theta = std::fs::read(dir.join("theta.npy")).unwrap();
    let h1 = npy_header(&[sys.n_rows]).len();
    let first = f64::from_le_bytes(theta[h1..h1 + 8].try_into().unwrap());
    assert_eq!(first, block.theta[0]);
    assert_eq!(theta.len(), h1 + sys.n_rows * 8);
    assert_eq!(
        std::fs::read(dir.join("weights.npy")).unwrap().len(),
        h1 + sys.n_rows * 8
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("columns.json")).unwrap()).unwrap();
    assert_eq!(json["columns"].as_array().unwrap().len(), n);
    assert_eq!(json["columns"][0]["kind"], "cell");
    assert_eq!(json["columns"][17]["name"], "bcg");
    assert_eq!(json["columns"][24]["kind"], "beta_y");
    assert_eq!(json["mass_unit_msun"], 1e12);
    assert_eq!(json["theta_shift_arcsec"], sys.theta_shift_arcsec);
    assert_eq!(json["systems"][1]["id"], "2");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `chi^2(X) = X^T A X + 2 b^T X + Theta^T W Theta` from the normal equations.
fn chi2(sys: &LinearSystem, x: &[f64]) -> f64 {
    let n = sys.n_columns();
    let quad: f64 = (0..n)
        .map(|i| x[i] * (0..n).map(|j| sys.a[i * n + j] * x[j]).sum::<f64>())
        .sum();
    let lin: f64 = sys.b.iter().zip(x).map(|(b, x)| b * x).sum();
    quad + 2.0 * lin + sys.theta_w_theta
}

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_prior_on_c_adds_one_row_per_member_layer() {
    let sigma = 0.2;
    let w = 1.0 / (sigma * sigma);
    let free = small_system("bcg", &SystemConfig::default());
    let held = small_system_with_prior("bcg", &SystemConfig::default(), Some(sigma));
    let n = free.n_columns();
    // Columns: the true layer (no prior), then "bcg" and "rest".
    let member_columns: Vec<usize> = held.layer_columns().skip(1).collect();
    assert_eq!(member_columns.len(), 2);
    assert_eq!(held.n_rows, free.n_rows + 2);
    let prior = held.prior_rows();
    assert_eq!(prior.weights, vec![w, w]);
    assert_eq!(prior.theta, vec![1.0, 1.0]);
    for (k, &c) in member_columns.iter().enumerate() {
        let row = &prior.gamma[k * n..(k + 1) * n];
        assert!(row
            .iter()
            .enumerate()
            .all(|(j, &v)| v == if j == c { 1.0 } else { 0.0 }));
    }
    // The normal equations change on the prior columns' diagonal and in b, nowhere else.
    for i in 0..n {
        let on = member_columns.contains(&i);
        for j in 0..n {
            let want = if on && i == j { w } else { 0.0 };
            let d = held.a[i * n + j] - free.a[i * n + j];
            assert!(
                (d - want).abs() <= 1e-9 * (1.0 + free.a[i * n + j].abs()),
                "A[{i},{j}]"
            );
        }
        let want = if on { -w } else { 0.0 };
        let d = held.b[i] - free.b[i];
        assert!((d - want).abs() <= 1e-9 * (1.0 + free.b[i].abs()), "b[{i}]");
    }
    // chi^2 grows by ((C - 1) / sigma)^2 per member layer.
    let mut x = random_x(&held, 5);
    let (c_bcg, c_rest) = (1.5, 0.7);
    x[member_columns[0]] = c_bcg;
    x[member_columns[1]] = c_rest;
    let added = ((c_bcg - 1.0f64) / sigma).powi(2) + ((c_rest - 1.0f64) / sigma).powi(2);
    let d = chi2(&held, &x) - chi2(&free, &x);
    assert!(
        (d - added).abs() <= 1e-6 * chi2(&free, &x),
        "{d} vs {added}"
    );
}

#[cfg(not(target_arch = "wasm32"))]
#[test]
fn export_ends_with_the_prior_rows() {
    let sys = small_system_with_prior("single", &SystemConfig::default(), Some(0.5));
    let dir = std::env::temp_dir().join(format!("wslap-export-prior-{}", std::process::id()));
    wslap::inversion::export_system(&sys, &dir).unwrap();
    let n = sys.n_columns();
    let read = |name: &str| -> Vec<f64> {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let header = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
        bytes[header..]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let (gamma, theta, weights) = (read("gamma.npy"), read("theta.npy"), read("weights.npy"));
    assert_eq!(sys.n_rows, 2 * sys.constraints.pixels.len() + 1);
    assert_eq!(gamma.len(), sys.n_rows * n);
    let last = &gamma[(sys.n_rows - 1) * n..];
    let c = sys.layer_columns().last().unwrap();
    assert!(last
        .iter()
        .enumerate()
        .all(|(j, &v)| v == if j == c { 1.0 } else { 0.0 }));
    assert_eq!(theta.last(), Some(&1.0));
    assert_eq!(weights.last(), Some(&4.0));
    assert_eq!(theta.len(), sys.n_rows);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// RA, Dec (degrees, 9 decimals: 4 microarcsec) of the offset `p` (arcsec) from `sky`.
fn fk5(sky: SkyReference, p: DVec2) -> String {
    let (ra, dec) = sky.offset_to_radec(p);
    format!("{ra:.9},{dec:.9}")
}

/// DS9 regions as arcs: each shape gives the lattice points inside it (as many as its area
/// holds), labels group images into systems, an excluded region cuts pixels out, and a point is
/// one pixel at its position.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn region_files_become_arc_pixels() {
    let sky = SkyReference::new(150.0, 2.2).unwrap();
    let at = |x: f64, y: f64| fk5(sky, DVec2::new(x, y));
    let text = format!(
        "# Region file format: DS9 version 4.1\n\
         global color=green\n\
         fk5\n\
         circle({c},1.5\") # text={{1.1 z=2.5}}\n\
         ellipse({e},2\",0.5\",30) # text={{1.2}}\n\
         polygon({p0},{p1},{p2}) # text={{2.1 z=1.8}}\n\
         box({b},3\",1\",0) # text={{2.2}} color=red\n\
         box({b2},3\",1\",0) # text={{2.2}}\n\
         point({pt}) # point=x text={{2.3}}\n\
         -circle({c},0.5\")\n",
        c = at(10.0, 5.0),
        e = at(-8.0, 3.0),
        // Off the lattice: a triangle with edges along lattice lines holds their points too.
        p0 = at(0.033, -9.967),
        p1 = at(4.033, -9.967),
        p2 = at(0.033, -6.967),
        b = at(-5.0, -5.0),
        b2 = at(-4.0, -5.0),
        pt = at(7.3, -2.1),
    );
    let pixel = 0.1;
    let r = wslap::inversion::arcs_from_regions(&text, "arcs.reg", Some(sky), pixel, &|_| None)
        .unwrap();
    assert!(!r.reference_from_regions);
    let a = &r.arcs;
    assert_eq!(a.systems.len(), 2);
    let (s1, s2) = (&a.systems[0], &a.systems[1]);
    assert_eq!((s1.id.as_str(), s1.z), ("1", Some(2.5)));
    assert_eq!((s2.id.as_str(), s2.z), ("2", Some(1.8)));
    assert_eq!((s1.images.len(), s2.images.len()), (2, 3));
    assert_eq!(s1.image_ids, ["1.1", "1.2"]);
    assert_eq!(s2.image_ids, ["2.1", "2.2", "2.3"]);
    let area = |n: usize| n as f64 * pixel * pixel;
    let pi = std::f64::consts::PI;
    // The circle (r = 1.5) less the excluded one (r = 0.5) about the same centre.
    let ring = &s1.images[0];
    assert_rel(
        "ring area",
        area(ring.len()),
        pi * (1.5f64.powi(2) - 0.25),
        0.03,
    );
    for p in ring {
        let d = p.distance(DVec2::new(10.0, 5.0));
        assert!(
            (0.5 - 1e-6..=1.5 + 1e-6).contains(&d),
            "ring pixel at {d} arcsec"
        );
    }
    assert_rel(
        "ellipse area",
        area(s1.images[1].len()),
        pi * 2.0 * 0.5,
        0.05,
    );
    assert_rel(
        "triangle area",
        area(s2.images[0].len()),
        0.5 * 4.0 * 3.0,
        0.05,
    );
    // Two 3 x 1 boxes 1 arcsec apart: their union is 4 x 1, each pixel once.
    assert_rel("union of the boxes", area(s2.images[1].len()), 4.0, 0.05);
    assert_eq!(s2.images[2].len(), 1);
    assert!(
        s2.images[2][0].distance(DVec2::new(7.3, -2.1)) < 1e-5,
        "{:?}",
        s2.images[2]
    );
    // Lattice points lie on multiples of the pixel.
    for p in &s1.images[1] {
        let off = (*p / pixel - (*p / pixel).round()).abs();
        assert!(off.max_element() < 1e-9, "{p}");
    }

    // Without a reference the frame is the regions' mean position.
    let r2 =
        wslap::inversion::arcs_from_regions(&text, "arcs.reg", None, pixel, &|_| None).unwrap();
    assert!(r2.reference_from_regions);
    let shift = sky.to_offset_arcsec(r2.reference.ra_deg, r2.reference.dec_deg);
    let centres = [
        (10.0, 5.0),
        (-8.0, 3.0),
        (4.0 / 3.0 + 0.033, -9.0 + 0.033),
        (-5.0, -5.0),
        (-4.0, -5.0),
        (7.3, -2.1),
    ];
    let mean = centres
        .iter()
        .map(|&(x, y)| DVec2::new(x, y))
        .sum::<DVec2>()
        / 6.0;
    assert!(
        shift.distance(mean) < 1e-3,
        "frame origin {shift} vs mean {mean}"
    );
    // A polygon across RA = 0 is averaged there, not at RA 180.
    let across = "fk5\npolygon(359.999,0,0.001,0,0.001,0.001,359.999,0.001) # text={1.1 z=2}\n";
    let r3 = wslap::inversion::arcs_from_regions(across, "a.reg", None, pixel, &|_| None).unwrap();
    let (ra, dec) = (r3.reference.ra_deg, r3.reference.dec_deg);
    assert!(
        ra.min(360.0 - ra) < 1e-9 && (dec - 0.0005).abs() < 1e-9,
        "{ra}, {dec}"
    );
}

/// Redshifts: labels of one system must agree, and a system without one takes the lookup's.
/// Bad region files name their line.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn region_files_report_their_errors_by_line() {
    let sky = SkyReference::new(150.0, 2.2).unwrap();
    let c = |x: f64| fk5(sky, DVec2::new(x, 0.0));
    let read = |body: &str| {
        wslap::inversion::arcs_from_regions(
            &format!("fk5\n{body}"),
            "arcs.reg",
            Some(sky),
            0.2,
            &|id| (id == "7").then_some(3.3),
        )
    };
    let ok = read(&format!(
        "circle({},1\") # text={{7.1}}\ncircle({},1\") # text={{7.2}}\ncircle({},1\") # text={{8.1}}",
        c(0.0),
        c(10.0),
        c(20.0)
    ))
    .unwrap();
    assert_eq!(ok.arcs.systems[0].z, Some(3.3));
    assert_eq!(ok.arcs.systems[1].z, None);
    // Labels whose z agree within the tolerance: the system's z is their mean, as in a
    // Lenstool catalogue.
    let mean = read(&format!(
        "circle({},1\") # text={{1.1 z=2.000}}\ncircle({},1\") # text={{1.2 z=2.002}}",
        c(0.0),
        c(10.0)
    ))
    .unwrap();
    assert!((mean.arcs.systems[0].z.unwrap() - 2.001).abs() < 1e-12);

    let message = |body: String| read(&body).unwrap_err().to_string();
    let cases = [
        (
            format!(
                "circle({},1\") # text={{1.1 z=2}}\ncircle({},1\") # text={{1.2 z=2.5}}",
                c(0.0),
                c(5.0)
            ),
            "arcs.reg: line 3: image 1.2: z = 2.5, but line 2 gives system 1 z = 2",
        ),
        (
            // Each agrees with the first (tolerance 1e-3 (1 + z) = 0.003), but the last two
            // are 0.004 apart: one source cannot have both.
            format!(
                "circle({},1\") # text={{1.1 z=2.000}}\ncircle({},1\") # text={{1.2 z=2.002}}\n\
                 circle({},1\") # text={{1.3 z=1.998}}",
                c(0.0),
                c(5.0),
                c(10.0)
            ),
            "line 4: image 1.3: z = 1.998, but line 3 gives system 1 z = 2.002",
        ),
        (
            format!("circle({},1\")", c(0.0)),
            "line 2: a region without a label",
        ),
        (
            format!("circle({},1\") # text={{A}}", c(0.0)),
            "'A' is not an image id",
        ),
        (
            format!("circle({},1\") # text={{1.1 zz=2}}", c(0.0)),
            "'zz=2' is not z=VALUE",
        ),
        (
            format!("circle({},1\") # text={{1.1 z=25}}", c(0.0)),
            "z = 25 must be in (0, 20)",
        ),
        (
            format!("segment({},{}) # text={{1.1}}", c(0.0), c(1.0)),
            "line 2: an open line has no inside",
        ),
        (
            "image\ncircle(10,10,3) # text={1.1}".to_string(),
            "line 3: is in image pixels",
        ),
        (
            format!(
                "circle({},1\") # text={{1.1}}\n-circle({},2\")",
                c(0.0),
                c(0.0)
            ),
            "line 2: image 1.1: an excluded region covers all of its pixels",
        ),
        (
            format!("-circle({},1\")", c(0.0)),
            "arcs.reg: holds no region",
        ),
        (
            format!("circle({},2d) # text={{1.1}}", c(0.0)),
            "line 2: the regions up to here hold up to",
        ),
        (
            format!("circle({},1\" # text={{1.1}}", c(0.0)),
            "arcs.reg line 2",
        ),
    ];
    for (body, want) in cases {
        let got = message(body.clone());
        assert!(got.contains(want), "{body}\n  gave: {got}\n  want: {want}");
    }
}
