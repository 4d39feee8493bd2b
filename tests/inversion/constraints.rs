//! Constraint pixels and weights ([method §4]): ellipse pixels, the three weightings,
//! systems left out (redshift, single image, hold-out), and arcs files.
//!
//! [method §4]: wslap::method#4-member-galaxies

use crate::common::assert_rel;
use crate::fixtures::{image, system, three_systems};
use glam::DVec2;
use wslap::parse_arcs;
use wslap::{
    build_constraints, ellipse_pixels, ConstraintConfig, ConstraintError, ConstraintMode,
    ConstraintSet, ConstraintSource, Exclusion, RedshiftPrior, Weighting,
};

/// Ellipse pixel count vs `pi a b / pixel^2` (lattice-point count error ~ perimeter / pixel).
const ELLIPSE_COUNT_RTOL: f64 = 0.1;

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

/// Each system left out of `set`, by id, and why.
fn exclusions(set: &ConstraintSet) -> Vec<(&str, Exclusion)> {
    set.excluded
        .iter()
        .map(|e| (e.id.as_str(), e.reason))
        .collect()
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
    // Without estimated redshifts (the default estimates them: below).
    let config = ConstraintConfig {
        free_z_prior: None,
        ..ConstraintConfig::default()
    };
    let set =
        build_constraints(ConstraintSource::Catalog(&cat), &config, &["3".to_string()]).unwrap();
    let ids: Vec<&str> = set.systems.iter().map(|s| s.id.as_str()).collect();
    assert_eq!(ids, ["1"]);
    assert_eq!(
        exclusions(&set),
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
    // The default: system 2's redshift is to be estimated, and so is system 1's when named;
    // once estimated, both are fitted at the estimate, not assumed.
    let free = ConstraintConfig {
        free_z_systems: vec!["1".to_string()],
        ..ConstraintConfig::default()
    };
    let set = build_constraints(ConstraintSource::Catalog(&cat), &free, &[]).unwrap();
    assert_eq!(
        exclusions(&set),
        [
            ("1", Exclusion::FreeRedshift),
            ("2", Exclusion::FreeRedshift),
            ("4", Exclusion::SingleImage)
        ]
    );
    let estimated = ConstraintConfig {
        z_estimates: vec![("1".to_string(), 1.7), ("2".to_string(), 3.1)],
        ..free.clone()
    };
    let set = build_constraints(ConstraintSource::Catalog(&cat), &estimated, &[]).unwrap();
    let zs: Vec<(&str, f64, bool)> = set
        .systems
        .iter()
        .map(|s| (s.id.as_str(), s.z, s.z_assumed))
        .collect();
    assert_eq!(
        zs,
        [("1", 1.7, false), ("2", 3.1, false), ("3", 1.2, false)]
    );
    // The image-plane error an estimated redshift's uncertainty adds joins the position
    // error in quadrature: each of system 2's images weighs 1 / (0.5^2 + 1.2^2), the others'
    // 1 / 0.5^2.
    let uncertain = ConstraintConfig {
        z_estimate_errors: vec![("2".to_string(), 1.2)],
        ..estimated.clone()
    };
    let set = build_constraints(ConstraintSource::Catalog(&cat), &uncertain, &[]).unwrap();
    let (_, per_image) = weight_sums(&set);
    let sigma2 = free.sigma_pos_arcsec.powi(2);
    for (s, images) in set.systems.iter().zip(&per_image) {
        let want = match s.id.as_str() {
            "2" => 1.0 / (sigma2 + 1.2 * 1.2),
            _ => 1.0 / sigma2,
        };
        for &w in images {
            assert_rel("image weight", w, want, 1e-12);
        }
    }
    let unknown = ConstraintConfig {
        free_z_systems: vec!["8".to_string()],
        ..ConstraintConfig::default()
    };
    let err = build_constraints(ConstraintSource::Catalog(&cat), &unknown, &[]).unwrap_err();
    assert_eq!(
        err.to_string(),
        "constraints: free_z_systems: system \"8\" is not in test.cat"
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

/// A system's own redshift prior (`z_priors`, a `.par`'s `z_m_limit`) overrides its catalogue
/// redshift as Lenstool does: fixed, it is fitted at that redshift; a range or a normal makes
/// it estimated, catalogue redshift or none. Bad priors and unknown systems are named.
#[cfg_attr(not(target_arch = "wasm32"), test)]
#[cfg_attr(target_arch = "wasm32", wasm_bindgen_test::wasm_bindgen_test)]
fn a_system_s_own_redshift_prior_overrides_the_catalogue() {
    let mut cat = three_systems();
    cat.systems[1].z = None;
    let priors = |list: &[(&str, RedshiftPrior)]| ConstraintConfig {
        z_priors: list.iter().map(|(id, p)| (id.to_string(), *p)).collect(),
        ..ConstraintConfig::default()
    };
    let config = priors(&[
        ("1", RedshiftPrior::Range([2.0, 3.0])),
        ("2", RedshiftPrior::Fixed(2.7)),
        ("3", RedshiftPrior::Normal([1.2, 0.1])),
    ]);
    let set = build_constraints(ConstraintSource::Catalog(&cat), &config, &[]).unwrap();
    let zs: Vec<(&str, f64, bool)> = set
        .systems
        .iter()
        .map(|s| (s.id.as_str(), s.z, s.z_assumed))
        .collect();
    assert_eq!(zs, [("2", 2.7, false)]);
    assert_eq!(
        exclusions(&set),
        [
            ("1", Exclusion::FreeRedshift),
            ("3", Exclusion::FreeRedshift)
        ]
    );
    assert!(set.warnings.is_empty(), "{:?}", set.warnings);
    // Once estimated, they are fitted at the estimates.
    let estimated = ConstraintConfig {
        z_estimates: vec![("1".to_string(), 2.4), ("3".to_string(), 1.25)],
        ..config.clone()
    };
    let set = build_constraints(ConstraintSource::Catalog(&cat), &estimated, &[]).unwrap();
    let zs: Vec<(&str, f64)> = set.systems.iter().map(|s| (s.id.as_str(), s.z)).collect();
    assert_eq!(zs, [("1", 2.4), ("2", 2.7), ("3", 1.25)]);
    // With estimation switched off, a system's own range or normal still has it estimated
    // (the system without a redshift and without a prior is left out); a fixed prior wins
    // over `free_z_systems`, and says so.
    let mut off = priors(&[
        ("1", RedshiftPrior::Range([2.0, 3.0])),
        ("3", RedshiftPrior::Fixed(1.1)),
    ]);
    off.free_z_prior = None;
    off.free_z_systems = vec!["3".to_string()];
    let set = build_constraints(ConstraintSource::Catalog(&cat), &off, &[]).unwrap();
    let zs: Vec<(&str, f64)> = set.systems.iter().map(|s| (s.id.as_str(), s.z)).collect();
    assert_eq!(zs, [("3", 1.1)]);
    assert_eq!(
        exclusions(&set),
        [
            ("1", Exclusion::FreeRedshift),
            ("2", Exclusion::UnknownRedshift)
        ]
    );
    assert_eq!(
        set.warnings,
        [
            "test.cat: system 3 is named to have its redshift estimated, but its own prior \
             fixes it at z = 1.1: fitted at 1.1",
            "test.cat: system 2 has no redshift and no default_z is set: not used"
        ]
    );
    for (prior, field, message) in [
        (
            RedshiftPrior::Range([3.0, 2.0]),
            "2",
            "a range [low, high] with 0 < low < high < 20",
        ),
        (
            RedshiftPrior::Normal([2.0, 0.0]),
            "0",
            "a normal [mean, sigma] with 0 < mean < 20 and sigma > 0",
        ),
        (
            RedshiftPrior::Fixed(-1.0),
            "-1",
            "a source redshift in (0, 20)",
        ),
    ] {
        let err = build_constraints(
            ConstraintSource::Catalog(&cat),
            &priors(&[("2", prior)]),
            &[],
        )
        .unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("constraints.z_priors.2")
                && text.contains(field)
                && text.contains(message),
            "{text}"
        );
    }
    let err = build_constraints(
        ConstraintSource::Catalog(&cat),
        &priors(&[("8", RedshiftPrior::Fixed(2.0))]),
        &[],
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "constraints: z_priors: system \"8\" is not in test.cat"
    );
    // From a settings file.
    let read: ConstraintConfig = serde_json::from_str(
        r#"{"z_priors": {"1": {"range": [2, 3]}, "2": {"normal": [2.9, 0.3]}, "3": {"fixed": 1.1}}}"#,
    )
    .unwrap();
    assert_eq!(
        read.z_priors.into_iter().collect::<Vec<_>>(),
        [
            ("1".to_string(), RedshiftPrior::Range([2.0, 3.0])),
            ("2".to_string(), RedshiftPrior::Normal([2.9, 0.3])),
            ("3".to_string(), RedshiftPrior::Fixed(1.1))
        ]
    );
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
