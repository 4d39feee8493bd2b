//! Bad settings of the inversion (grid, members, constraints, system) give their errors.

use crate::fixtures::{member, members, plane, three_systems};
use glam::DVec2;
use wslap::MemberCatalog;
use wslap::{
    build_constraints, build_member_layers, CellGrid, ConstraintConfig, ConstraintError,
    ConstraintSource, GridConfig, GridError, LayerSplit, LinearSystem, MemberConfig, MembersError,
    SystemConfig, SystemError,
};

#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn bad_settings_give_their_errors() {
    let field_of = |e: &GridError| match e {
        GridError::BadFieldValue(e) => e.field.strip_prefix("grid.").unwrap_or("").to_string(),
        _ => String::new(),
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
