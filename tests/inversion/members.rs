//! Member galaxies ([method §3]): masses from magnitudes, truncated-NFW halos, layer
//! splits, and members outside the field.
//!
//! [method §3]: wslap::method#3-the-linear-system

use crate::common::{assert_abs, assert_rel};
use crate::fixtures::{member, members, plane};
use glam::DVec2;
use wslap::{build_member_layers, CellGrid, Layer, LayerSplit, MemberConfig};
use wslap::{MassComponent, TruncatedNfw};
use wslap::{Member, MemberCatalog};

/// Member halo rebuilt from its M200, c200 (the concentration is found by bisection to
/// double precision; the TNFW total-mass formula rounds at ~1e-13).
const TNFW_MASS_RTOL: f64 = 1e-10;

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
        profile: wslap::HaloProfile::Nfw,
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

    // A `.par` galaxy whose mass the `.par` leaves free has a layer of its own, first, and
    // the split groups the others (the BCG is then the brightest of those). Member 3 shares
    // its name (a `.par` names potentials `1`, `2`, ... as catalogues number their rows):
    // it is not that galaxy, and stays with the others.
    let free_id = cat.members[2].id.clone();
    let mut freed = MemberCatalog {
        free_mass_galaxies: vec![2],
        mass_galaxies: vec![2],
        ..members()
    };
    freed.members[3].id = free_id.clone();
    for (split, expected) in [
        ("single", vec![vec![2], vec![0, 1, 3, 4, 5]]),
        ("bcg", vec![vec![2], vec![0], vec![1, 3, 4, 5]]),
        (
            "brightest:2",
            vec![vec![2], vec![0], vec![5], vec![1, 3, 4]],
        ),
    ] {
        let config = MemberConfig {
            layers: split.parse().unwrap(),
            mag_star: Some(19.0),
            ..MemberConfig::default()
        };
        let layers = build_member_layers(&freed, &config, &plane, &grid)
            .unwrap()
            .layers;
        let got: Vec<Vec<usize>> = layers.iter().map(|l| l.members.clone()).collect();
        assert_eq!(got, expected, "{split}");
        assert_eq!(
            layers[0].name,
            format!("galaxy {free_id} (mass free in the .par)")
        );
        let total: DVec2 = layers.iter().map(|l| l.deflection(p)).sum();
        assert_abs("freed sum x", total.x, single[0].deflection(p).x, 1e-13);
    }
    let none = MemberConfig {
        layers: LayerSplit::None,
        ..MemberConfig::default()
    };
    let no_layers = build_member_layers(&freed, &none, &plane, &grid).unwrap();
    assert!(no_layers.layers.is_empty());
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
    // Several members outside: one warning naming their lines.
    for (id, x, y, line) in [("far2", -200.0, 50.0, 20), ("far3", 0.0, -90.0, 21)] {
        cat.members.push(Member {
            line,
            ..member(id, x, y, 18.0)
        });
    }
    let model = build_member_layers(&cat, &config, &plane(), &grid).unwrap();
    assert_eq!(model.halos.len(), 7);
    assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
    let expected = "members.cat: 3 members lie outside the field (grid of 60.0 arcsec plus \
                    6.0 arcsec margin) and are not used: lines 3, 20, 21";
    assert_eq!(model.warnings[0], expected);
}
