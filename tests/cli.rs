//! The `wslap` command line: `wslap maps` end to end, in both input modes, and its errors.
#![cfg(not(target_arch = "wasm32"))]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use wslap::curves::CriticalCurves;
use wslap::demo::CLUSTER_MODEL_JSON;
use wslap::fits::read_image;

const PRODUCT_FILES: [&str; 10] = [
    "kappa.fits",
    "gamma1.fits",
    "gamma2.fits",
    "x-arcsec-deflect.fits",
    "y-arcsec-deflect.fits",
    "magnif.fits",
    "critical-curves.json",
    "critical-curves.reg",
    "kappa.png",
    "summary.json",
];

/// Einstein radius from published deflection maps vs from the exact model: finite differences
/// on a 1 arcsec grid smooth the cusp slightly, so allow 2%.
const DEFLECTION_MODE_EINSTEIN_RTOL: f64 = 0.02;

fn wslap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_wslap"))
        .args(args)
        .output()
        .expect("run wslap")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("wslap-cli-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&fs::read_to_string(dir.join("summary.json")).expect("summary"))
        .expect("summary is JSON")
}

#[test]
fn version_and_help() {
    let out = wslap(&["--version"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains(env!("CARGO_PKG_VERSION")));
    let out = wslap(&["maps", "--help"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("--z-source"));
}

#[test]
fn maps_of_a_model_file_writes_every_product() {
    let dir = temp_dir("model");
    let model = dir.join("model.json");
    fs::write(&model, CLUSTER_MODEL_JSON).unwrap();
    let out_dir = dir.join("out");
    let out = wslap(&[
        "maps",
        "--model",
        model.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--z-source",
        "2.0",
        "--size",
        "160",
        "--pixels",
        "200",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in PRODUCT_FILES {
        let len = fs::metadata(out_dir.join(name))
            .map(|m| m.len())
            .unwrap_or(0);
        assert!(len > 0, "{name} missing or empty");
    }
    let kappa = read_image(&fs::read(out_dir.join("kappa.fits")).unwrap(), "kappa.fits").unwrap();
    assert_eq!((kappa.width, kappa.height), (200, 200));
    let (geometry, reference) = kappa.geometry().unwrap();
    assert!((geometry.pixel_arcsec() - 0.8).abs() < 1e-9);
    let reference = reference.expect("the example has a sky reference");
    assert!((reference.ra_deg - 342.18322).abs() < 1e-9);
    let magnif = read_image(
        &fs::read(out_dir.join("magnif.fits")).unwrap(),
        "magnif.fits",
    )
    .unwrap();
    let zsource = magnif.card("ZSOURCE").expect("ZSOURCE card");
    assert_eq!(zsource.as_f64(), Some(2.0));
    let curves: CriticalCurves =
        serde_json::from_str(&fs::read_to_string(out_dir.join("critical-curves.json")).unwrap())
            .unwrap();
    assert!(!curves.tangential.is_empty() && !curves.radial.is_empty());
    assert_eq!(curves.caustics.tangential.len(), curves.tangential.len());
    let regions = fs::read_to_string(out_dir.join("critical-curves.reg")).unwrap();
    assert!(regions.starts_with("# Region file format: DS9"));
    assert!(regions.contains("fk5") && regions.contains("polygon("));
    let png = fs::read(out_dir.join("kappa.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let s = summary(&out_dir);
    let r_e = s["einstein_radius_arcsec"].as_f64().unwrap();
    assert!(r_e > 20.0 && r_e < 45.0, "Einstein radius {r_e}");
    assert_eq!(s["map_pixels"], 200);
}

#[test]
fn maps_of_deflection_fits_match_the_model() {
    let dir = temp_dir("deflection");
    let model = dir.join("model.json");
    fs::write(&model, CLUSTER_MODEL_JSON).unwrap();
    let from_model = dir.join("from-model");
    let args = ["--size", "160", "--pixels", "160", "--z-source", "3"];
    let mut a = vec![
        "maps",
        "--model",
        model.to_str().unwrap(),
        "--out",
        from_model.to_str().unwrap(),
    ];
    a.extend(args);
    assert!(wslap(&a).status.success());
    let from_fits = dir.join("from-fits");
    let x = from_model.join("x-arcsec-deflect.fits");
    let y = from_model.join("y-arcsec-deflect.fits");
    let out = wslap(&[
        "maps",
        "--deflection",
        x.to_str().unwrap(),
        y.to_str().unwrap(),
        "--z-lens",
        "0.35",
        "--out",
        from_fits.to_str().unwrap(),
        "--z-source",
        "3",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in PRODUCT_FILES {
        assert!(from_fits.join(name).exists(), "{name} missing");
    }
    let exact = summary(&from_model)["einstein_radius_arcsec"]
        .as_f64()
        .unwrap();
    let derived = summary(&from_fits)["einstein_radius_arcsec"]
        .as_f64()
        .unwrap();
    assert!(
        (derived - exact).abs() <= DEFLECTION_MODE_EINSTEIN_RTOL * exact,
        "Einstein radius from deflection maps {derived} vs model {exact}"
    );
}

#[test]
fn bad_inputs_give_clear_errors() {
    let dir = temp_dir("bad");
    let bad = dir.join("bad-model.json");
    fs::write(&bad, "{\"z_lens\": 0.3, \"components\": [{\"type\": \"sis\", \"x\": 0, \"y\": 0, \"sigma_v\": \"fast\"}]}").unwrap();
    let out = wslap(&[
        "maps",
        "--model",
        bad.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad-model.json") && err.contains("line 1"),
        "{err}"
    );

    let good = dir.join("model.json");
    fs::write(&good, CLUSTER_MODEL_JSON).unwrap();
    let out = wslap(&[
        "maps",
        "--model",
        good.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
        "--z-source",
        "0.2",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("z_s = 0.2") && err.contains("z_l = 0.35"),
        "{err}"
    );

    let out = wslap(&[
        "maps",
        "--model",
        dir.join("missing.json").to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.json"));

    let out = wslap(&[
        "maps",
        "--model",
        good.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
        "--pixels",
        "3",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("pixels = 3"));

    let not_fits = dir.join("x.fits");
    fs::write(&not_fits, b"SIMPLE  = nonsense").unwrap();
    let out = wslap(&[
        "maps",
        "--deflection",
        not_fits.to_str().unwrap(),
        not_fits.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("x.fits"));
    assert!(
        !dir.join("o").exists(),
        "nothing is written when the input is bad"
    );
}

fn shared(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(path)
        .display()
        .to_string()
}

#[test]
fn reconstruct_writes_every_product_and_marks_held_out_systems() {
    let dir = temp_dir("reconstruct");
    let config = dir.join("config.json");
    fs::write(
        &config,
        r#"{"grid": {"cells": 12}, "products": {"pixels": 64}}"#,
    )
    .unwrap();
    let out_dir = dir.join("out");
    let system_dir = dir.join("system");
    let out = wslap(&[
        "reconstruct",
        "--images",
        &shared("AS1063/lenstool_cats/cats_gold_mul_gold.cat"),
        "--members",
        &shared("AS1063/lenstool_cats/cats_gold_ref_potential_w_clumpNE.cat"),
        "--z-lens",
        "0.348",
        "--config",
        config.to_str().unwrap(),
        "--iterations",
        "300",
        "--holdout",
        "2,7",
        "--export-system",
        system_dir.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in PRODUCT_FILES
        .iter()
        .chain(&["sources.json", "convergence.json"])
    {
        assert!(out_dir.join(name).exists(), "{name} missing");
    }
    for name in ["gamma.npy", "theta.npy", "weights.npy", "columns.json"] {
        assert!(system_dir.join(name).exists(), "{name} missing");
    }
    let sources: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out_dir.join("sources.json")).unwrap()).unwrap();
    let held: Vec<&str> = sources
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["held_out"] == true)
        .map(|s| s["id"].as_str().unwrap())
        .collect();
    assert_eq!(held, ["2", "7"]);
    let s = summary(&out_dir);
    assert_eq!(s["systems_fitted"].as_array().unwrap().len(), 17);
    assert_eq!(s["c_per_layer"].as_array().unwrap().len(), 1);
    let convergence: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out_dir.join("convergence.json")).unwrap())
            .unwrap();
    assert_eq!(
        convergence.as_array().unwrap().last().unwrap()["iteration"],
        300
    );
}

#[test]
fn reconstruct_bad_inputs_name_the_problem() {
    let dir = temp_dir("reconstruct-bad");
    let images = shared("AS1063/lenstool_cats/cats_gold_mul_gold.cat");
    // A lens behind the sources.
    let out = wslap(&[
        "reconstruct",
        "--images",
        &images,
        "--z-lens",
        "1.5",
        "--out",
        dir.join("a").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    // The first system in front of the lens, named by file and line, with its redshift.
    assert!(
        err.contains("cats_gold_mul_gold.cat: line ")
            && err.contains("z_s = ")
            && err.contains("z_lens = 1.5"),
        "{err}"
    );
    // A malformed catalogue row.
    let bad = dir.join("bad.cat");
    fs::write(
        &bad,
        "1.1 342.19 -44.52 0.1 0.1 0 1.2 0\n1.2 342.19 nan 0.1 0.1 0 1.2 0\n",
    )
    .unwrap();
    let out = wslap(&[
        "reconstruct",
        "--images",
        bad.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--out",
        dir.join("b").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.cat") && err.contains("line 2"), "{err}");
    // A bad setting in the configuration.
    let config = dir.join("config.json");
    fs::write(&config, r#"{"solver": {"start_c": 0}}"#).unwrap();
    let out = wslap(&[
        "reconstruct",
        "--images",
        &images,
        "--z-lens",
        "0.348",
        "--config",
        config.to_str().unwrap(),
        "--out",
        dir.join("c").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("start_c"));
    // An unknown hold-out id.
    let out = wslap(&[
        "reconstruct",
        "--images",
        &images,
        "--z-lens",
        "0.348",
        "--holdout",
        "999",
        "--out",
        dir.join("d").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("999"));
}

#[test]
fn reconstruct_from_arc_pixels() {
    let dir = temp_dir("arcs");
    let arcs = dir.join("arcs.json");
    fs::write(
        &arcs,
        r#"{"systems": [
            {"id": "a", "z": 2.0, "images": [[[20.0, 1.0], [20.1, 1.5], [20.0, 2.0]], [[-18.0, -2.0], [-18.1, -2.4]]]},
            {"id": "b", "z": 3.0, "images": [[[3.0, 24.0], [3.5, 24.1]], [[-2.0, -22.0], [-2.4, -22.1]], [[0.5, 0.8]]]}
        ]}"#,
    )
    .unwrap();
    let out_dir = dir.join("out");
    let out = wslap(&[
        "reconstruct",
        "--arcs",
        arcs.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--iterations",
        "100",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = summary(&out_dir);
    assert_eq!(s["constraint_pixels"], 10);
    assert_eq!(s["settings"]["constraints"]["mode"], "arcs");
    // Images and arcs together are refused: one source of constraints at a time.
    let out = wslap(&[
        "reconstruct",
        "--arcs",
        arcs.to_str().unwrap(),
        "--images",
        arcs.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
}
