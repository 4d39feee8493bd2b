//! The `wslap` command line: `wslap maps` end to end, in both input modes, and its errors.
#![cfg(not(target_arch = "wasm32"))]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use wslap::read_image;
use wslap::CriticalCurves;
use wslap::CLUSTER_MODEL_JSON;

const PRODUCT_FILES: [&str; 11] = [
    "kappa.fits",
    "gamma1.fits",
    "gamma2.fits",
    "x-arcsec-deflect.fits",
    "y-arcsec-deflect.fits",
    "magnif.fits",
    "psi.fits",
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

/// A fresh directory for one test's files, removed when the test ends (each run used to leave
/// ~27 MB in the temporary directory).
fn temp_dir(name: &str) -> TempDir {
    let dir = std::env::temp_dir().join(format!("wslap-cli-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("temp dir");
    TempDir(dir)
}

/// A directory of [`temp_dir`]: a path that removes its directory when dropped.
struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

/// A quick CONFIG.json in `dir`: 16 x 16 cells, 64-pixel maps 60 arcsec wide.
fn quick_config(dir: &Path) -> PathBuf {
    let config = dir.join("config.json");
    fs::write(
        &config,
        r#"{"grid": {"cells": 16}, "products": {"pixels": 64, "size_arcsec": 60}}"#,
    )
    .unwrap();
    config
}

/// The teaching catalogue (the app's built-in example: four systems behind a known model)
/// written to `dir`/images.cat.
fn teaching_images(dir: &Path) -> PathBuf {
    let images = dir.join("images.cat");
    fs::write(
        &images,
        wslap::app::examples::teaching_image_catalog().unwrap(),
    )
    .unwrap();
    images
}

/// A CONFIG.json in `dir` with a fixed regularisation strength ("auto" would run its
/// candidates, tested in tests/inversion/objective.rs): 16 x 16 cells, 64-pixel maps.
fn fixed_strength_config(dir: &Path, strength: f64) -> PathBuf {
    let config = dir.join("fixed.json");
    let text = format!(
        r#"{{"grid": {{"cells": 16}}, "objective": {{"strength": {strength}}}, "products": {{"pixels": 64}}}}"#
    );
    fs::write(&config, text).unwrap();
    config
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
    assert!(String::from_utf8_lossy(&out.stderr).contains("--pixels = 3 is not allowed"));
    // A negative width is the option's value (not an unknown flag), refused by its name.
    let out = wslap(&[
        "maps",
        "--model",
        good.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
        "--size",
        "-1",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--size = -1 is not allowed"));

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
        // The paper's QADP, whose iteration count --iterations sets (checked below).
        r#"{"grid": {"cells": 12}, "products": {"pixels": 64}, "solver": {"method": "qadp"},
            "objective": {"regulariser": "none", "strength": 0, "image_plane_iterations": 0}}"#,
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
        .chain(&["sources.json", "images.reg", "convergence.json"])
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
    // The verdict judges the map by them, and says so.
    let written = summary(&out_dir);
    assert_eq!(written["verdict"]["holdout_from"], "held_out_systems");
    assert!(written["verdict"]["holdout_offset_median_arcsec"].as_f64() > Some(0.0));
    // images.reg: a green circle on each catalogue image, at its RA and Dec (the catalogue is
    // in absolute degrees), and a dashed magenta one on each predicted image.
    let regions = wslap::read_regions(
        &fs::read_to_string(out_dir.join("images.reg")).unwrap(),
        "images.reg",
    )
    .unwrap();
    let catalogue =
        fs::read_to_string(shared("AS1063/lenstool_cats/cats_gold_mul_gold.cat")).unwrap();
    let rows: Vec<Vec<&str>> = catalogue
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>())
        .filter(|f| f.len() >= 3 && !f[0].starts_with('#'))
        .collect();
    let observed: Vec<_> = regions
        .iter()
        .filter(|r| r.color.as_deref() == Some("green"))
        .collect();
    assert_eq!(observed.len(), rows.len());
    for r in &observed {
        let label = r.text.as_deref().unwrap();
        let id = label.trim_end_matches(" (held out)");
        assert_eq!(
            label.ends_with("(held out)"),
            id.starts_with("2.") || id.starts_with("7.")
        );
        let row = rows.iter().find(|f| f[0] == id).expect(label);
        let wslap::Shape::Circle { center, radius } = r.shape else {
            panic!("{r:?}")
        };
        let (ra, dec): (f64, f64) = (row[1].parse().unwrap(), row[2].parse().unwrap());
        assert!(
            (center.x - ra).abs() < 1e-7 && (center.y - dec).abs() < 1e-7,
            "{id}: {center} vs {ra}, {dec}"
        );
        assert_eq!(radius, 0.5);
    }
    let predicted = sources
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["predicted"].as_array().unwrap())
        .filter(|p| p["magnification"].as_f64().unwrap().abs() >= 0.1)
        .count();
    assert!(predicted > 0);
    assert_eq!(regions.len(), observed.len() + predicted);
    // Every system's delays count from its first predicted image: one is 0, none is negative,
    // and the observed images have theirs on the same zero.
    for s in sources.as_array().unwrap() {
        let delays: Vec<f64> = s["predicted"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| {
                p["delay_days"]
                    .as_f64()
                    .expect("a delay per predicted image")
            })
            .collect();
        assert!(
            delays.contains(&0.0) && delays.iter().all(|&d| d >= 0.0),
            "{s}"
        );
        assert!(s["observed"]
            .as_array()
            .unwrap()
            .iter()
            .all(|o| o["delay_days"].is_f64()));
    }
    assert!(regions
        .iter()
        .filter(|r| r.color.as_deref() == Some("magenta"))
        .all(|r| r.text.as_deref().unwrap().contains(": predicted, mu=")));
    let s = summary(&out_dir);
    assert_eq!(s["systems_fitted"].as_array().unwrap().len(), 17);
    // Left out, and why, in words.
    assert_eq!(
        s["systems_excluded"],
        serde_json::json!(["2 (held out)", "7 (held out)"])
    );
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
    // A `.par` that does not read is named with its line, before any run (an unknown
    // profile here), and no output directory is made.
    let par = dir.join("bad.par");
    fs::write(
        &par,
        "runmode\n\treference 3 342.18322 -44.530889\n\tend\npotentiel O1\n\tprofil 7\n\t\
         z_lens 0.348\n\tend\nfini\n",
    )
    .unwrap();
    let out = wslap(&[
        "reconstruct",
        "--images",
        &images,
        "--z-lens",
        "0.348",
        "--par",
        par.to_str().unwrap(),
        "--out",
        dir.join("e").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.par") && err.contains("profil 7"), "{err}");
    assert!(!dir.join("e").exists());
}

/// `--par` gives the reconstruction the redshift priors of the model's `image` block: a
/// `z_m_limit` range that leaves out the truth (system 2 of the teaching catalogue is at
/// z = 2.5) bounds the estimate, a fixed one (flag 0) replaces the catalogue's redshift; the
/// run says both, `sources.json` marks each system with its prior, and `summary.json` keeps
/// them with the settings.
#[test]
fn reconstruct_takes_the_redshift_priors_of_a_par() {
    let dir = temp_dir("z-priors");
    let images = teaching_images(&dir);
    let par = dir.join("model.par");
    fs::write(
        &par,
        "runmode\n\treference 3 150.0 2.2\n\tend\nimage\n\tmultfile 1 images.cat\n\
         \tz_m_limit 1 2 1 2.0 2.3 0.1\n\tz_m_limit 2 4.0 0 2.2 0.0 0.0\n\tend\n\
         potentiel O1\n\tprofil 81\n\tx_centre 0\n\ty_centre 0\n\tellipticite 0.2\n\
         \tangle_pos 0\n\tcore_radius_kpc 50\n\tcut_radius_kpc 1000\n\tv_disp 1000\n\
         \tz_lens 0.3\n\tend\ncosmologie\n\tH0 70\n\tomegaM 0.3\n\tomegaX 0.7\n\tend\n\
         chi2: 1.5\nfini\n",
    )
    .unwrap();
    let config = fixed_strength_config(&dir, 0.01);
    // A run of the teaching catalogue with the .par and the settings `config`, into `out`:
    // its stderr and its sources.json.
    let run = |config: &Path, out: &Path| {
        let done = wslap(&[
            "reconstruct",
            "--images",
            images.to_str().unwrap(),
            "--par",
            par.to_str().unwrap(),
            "--z-lens",
            "0.3",
            "--config",
            config.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&done.stderr).to_string();
        assert!(done.status.success(), "{stderr}");
        let sources: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(out.join("sources.json")).unwrap()).unwrap();
        (stderr, sources)
    };
    let out_dir = dir.join("out");
    let (stderr, sources) = run(&config, &out_dir);
    for said in [
        "model.par: line 6: system 2's redshift is estimated under the model's prior, uniform 2 - 2.3",
        "model.par: line 7: system 4's redshift is taken as 2.2",
        "system 2: redshift estimated z = ",
        "under its own prior (uniform 2 - 2.3)",
        "model.par:25: `chi2:` is not a Lenstool block: skipped",
    ] {
        assert!(stderr.contains(said), "{said}: {stderr}");
    }
    let system = |sources: &serde_json::Value, id: &str| {
        sources
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["id"] == id)
            .unwrap()
            .clone()
    };
    let two = system(&sources, "2");
    let z = two["z_estimate"].as_f64().unwrap();
    assert!((2.0..=2.3).contains(&z), "{two}");
    let [lo, hi] = [0, 1].map(|i| two["z_interval"][i].as_f64().unwrap());
    assert!(lo >= 2.0 && hi <= 2.3 && lo <= z && z <= hi, "{two}");
    assert!(z > 2.2, "the end nearer the truth, 2.5: {two}");
    // An interval that reaches the top of its range is said to be open above.
    assert_eq!(
        stderr.contains("2.30, open above: 2.30 is the top of the range searched)"),
        hi >= 2.3 - 0.005,
        "{two}: {stderr}"
    );
    assert_eq!(two["z_open_above"], hi >= 2.3 - 0.005, "{two}");
    let four = system(&sources, "4");
    assert_eq!(four["z"], 2.2);
    assert!(four["z_estimate"].is_null(), "{four}");
    assert_eq!(two["z_prior"], serde_json::json!({"range": [2.0, 2.3]}));
    assert_eq!(four["z_prior"], serde_json::json!({"fixed": 2.2}));
    assert!(system(&sources, "1")["z_prior"].is_null());
    let s = summary(&out_dir);
    assert_eq!(
        s["settings"]["constraints"]["z_priors"],
        serde_json::json!({"2": {"range": [2.0, 2.3]}, "4": {"fixed": 2.2}})
    );
    // With estimation switched off, the range still has system 2 estimated, within it.
    let off = dir.join("off.json");
    let mut settings: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&config).unwrap()).unwrap();
    settings["constraints"] = serde_json::json!({"free_z_prior": null});
    fs::write(&off, settings.to_string()).unwrap();
    let (_, sources) = run(&off, &dir.join("off"));
    let two = system(&sources, "2");
    let z = two["z_estimate"].as_f64().unwrap();
    assert!((2.0..=2.3).contains(&z), "{two}");
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
    let config = fixed_strength_config(&dir, 0.1);
    let out_dir = dir.join("out");
    let out = wslap(&[
        "reconstruct",
        "--arcs",
        arcs.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--config",
        config.to_str().unwrap(),
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
    // With a catalogue too, the mode chooses (the rule itself: `reconstruct::Dataset`'s tests):
    // the default fits the catalogue and says that the arcs are not fitted.
    let images = teaching_images(&dir);
    let out = wslap(&[
        "reconstruct",
        "--arcs",
        arcs.to_str().unwrap(),
        "--images",
        images.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--config",
        config.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("its arc pixels are not fitted"), "{stderr}");
    assert_ne!(summary(&out_dir)["settings"]["constraints"]["mode"], "arcs");
}

/// `--folds K` also writes crossval.json: K hold-out runs, every fitted system predicted once
/// (library: tests/inversion/crossval.rs). More folds than systems give one per system, said; a
/// number of folds that cannot work is refused before the first run, naming the count of systems.
#[test]
fn reconstruct_folds_writes_crossval_json() {
    let dir = temp_dir("folds");
    let images = teaching_images(&dir);
    let config = quick_config(&dir);
    let out_dir = dir.join("out");
    let args = [
        "--images",
        images.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--config",
        config.to_str().unwrap(),
        "--iterations",
        "200",
    ];
    let mut all = vec!["reconstruct"];
    all.extend(args);
    all.extend(["--folds", "2", "--out", out_dir.to_str().unwrap()]);
    let out = wslap(&all);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("2 folds: held-out images median"),
        "{stdout}"
    );
    assert!(
        stdout.contains("the folds' kappa spread: median"),
        "{stdout}"
    );
    // The choice and the folds say they run (they are silent for minutes otherwise).
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.starts_with("choosing the regulariser, its strength and the grid: "),
        "{stderr}"
    );
    assert!(
        stderr.contains("cross-validating over 2 folds, side by side"),
        "{stderr}"
    );
    for fold in ["fold 1/2: fitting", "fold 2/2: fitting"] {
        assert_eq!(stderr.matches(fold).count(), 1, "{stderr}");
    }
    assert!(out_dir.join("summary.json").exists());
    let cv: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out_dir.join("crossval.json")).unwrap()).unwrap();
    assert_eq!(cv["folds"], 2);
    assert_eq!(cv["status"], "Completed");
    assert_eq!(cv["runs"].as_array().unwrap().len(), 2);
    let mut predicted: Vec<&str> = cv["systems"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["id"].as_str().unwrap())
        .collect();
    predicted.sort();
    assert_eq!(predicted, ["1", "2", "3", "4"]);
    let held = cv["holdout_image_offset_median_arcsec"].as_f64().unwrap();
    assert!(held > 0.0);
    // summary.json has the totals, and its verdict counts the held-out images as held out
    // (the run itself holds none out).
    let summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out_dir.join("summary.json")).unwrap()).unwrap();
    assert!(summary["holdout_image_offset_median_arcsec"].is_null());
    for field in [
        "folds",
        "status",
        "holdout_images",
        "holdout_images_unmatched",
        "holdout_image_offset_median_arcsec",
        "holdout_image_plane_rms_arcsec",
        "fit_image_offset_median_arcsec",
    ] {
        assert_eq!(summary["crossval"][field], cv[field], "{field}");
    }
    assert_eq!(
        summary["verdict"]["holdout_offset_median_arcsec"].as_f64(),
        Some(held)
    );
    assert_eq!(summary["verdict"]["holdout_from"], "crossval");
    // The folds' convergence, on the pixels of kappa.fits.
    let read = |file: &str| {
        let path = out_dir.join(file);
        read_image(&fs::read(&path).unwrap(), file).unwrap()
    };
    let kappa = read("kappa.fits");
    for file in ["crossval-kappa-mean.fits", "crossval-kappa-spread.fits"] {
        let map = read(file);
        assert_eq!(
            (map.width, map.height),
            (kappa.width, kappa.height),
            "{file}"
        );
        assert_eq!(map.geometry().unwrap(), kappa.geometry().unwrap(), "{file}");
        assert_eq!(map.card("NFOLDS").unwrap().as_f64(), Some(2.0), "{file}");
        assert_eq!(map.non_finite_count(), 0, "{file}");
    }
    let spread = read("crossval-kappa-spread.fits");
    assert!(spread.data.iter().all(|&v| v >= 0.0));
    assert!(spread.data.iter().any(|&v| v > 0.0), "the two folds differ");
    let png = fs::read(out_dir.join("crossval-kappa-spread.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    // More folds than systems: one per system, said (SGAS J1152's 2 systems with `--folds 5`
    // were refused).
    let out9 = dir.join("out9");
    let mut all = vec!["reconstruct"];
    all.extend(args);
    all.extend(["--folds", "9", "--out", out9.to_str().unwrap()]);
    let out = wslap(&all);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("note: --folds 9: 4 systems can be held out"),
        "{stderr}"
    );
    let cv: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out9.join("crossval.json")).unwrap()).unwrap();
    assert_eq!(cv["folds"], 4);
    // Fewer than two folds cannot work: refused before the first run.
    let mut all = args.to_vec();
    all.extend(["--folds", "1"]);
    let err = refused(&dir, "reconstruct", &all);
    assert!(
        err.contains("folds = 1: ") && err.contains("use folds from 2 to 4"),
        "{err}"
    );
}

#[test]
fn shear_inputs_are_checked_before_the_run() {
    let dir = temp_dir("shear-bad");
    let images = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/weak_lensing/images.cat"
    );
    // An arclet without a redshift: the file, line, column and value.
    let bad = dir.join("arclets.cat");
    fs::write(
        &bad,
        "#REFERENCE 3 342.1832 -44.5309\n1 60 10 0.5 0.3 20 1.5\n2 70 -5 0.5 0.3 20 0\n",
    )
    .unwrap();
    let bad = bad.to_str().unwrap();
    let args = ["--images", images, "--shear", bad, "--z-lens", "0.32"];
    let err = refused(&dir, "reconstruct", &args);
    assert!(
        err.contains("arclets.cat: line 3, column 7 (z): '0' is 0 (unknown)"),
        "{err}"
    );
    // A shape noise out of range names the option.
    let args = [
        "--images",
        images,
        "--shear",
        bad,
        "--shape-noise",
        "0",
        "--z-lens",
        "0.32",
    ];
    let err = refused(&dir, "reconstruct", &args);
    assert!(err.contains("--shape-noise: shear.shape_noise"), "{err}");
    // --shape-noise needs --shear.
    let args = [
        "--images",
        images,
        "--shape-noise",
        "0.2",
        "--z-lens",
        "0.32",
    ];
    let err = refused(&dir, "reconstruct", &args);
    assert!(err.contains("--shear"), "{err}");
}

/// Runs `wslap <command>` with `args` (plus `--out`), expects failure and no output folder,
/// returns stderr.
fn refused(dir: &Path, command: &str, args: &[&str]) -> String {
    let out_dir = dir.join("never-written");
    let mut all = vec![command];
    all.extend(args);
    all.extend(["--out", out_dir.to_str().unwrap()]);
    let out = wslap(&all);
    assert!(!out.status.success(), "{all:?} must fail");
    assert!(
        !out_dir.exists(),
        "nothing is written when the input is bad"
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A negative value is the option's value, refused by the option's name (clap read `-70` as an
/// unknown flag); a lens behind the maps' source redshift names --z-lens; an option `maps`
/// would not use is refused, not ignored.
#[test]
fn negative_values_and_unused_options_name_the_option() {
    let dir = temp_dir("negative");
    let images = teaching_images(&dir);
    let reconstruct = |extra: &[&str]| {
        let mut args = vec!["--images", images.to_str().unwrap()];
        args.extend(extra);
        refused(&dir, "reconstruct", &args)
    };
    for (extra, expected) in [
        (
            &["--z-lens", "0.3", "--h0", "-70"][..],
            "error: --h0: cosmology.h0 = -70 is not allowed",
        ),
        (
            &["--z-lens", "0.3", "--omega-m", "-0.3"],
            "error: --omega-m: cosmology.omega_m = -0.3 is not allowed",
        ),
        (
            &["--z-lens", "-0.3"],
            "error: --z-lens: cosmology.z_lens = -0.3 is not allowed",
        ),
        (
            &["--z-lens", "0.3", "--default-z", "-2"],
            "error: --default-z: constraints.default_z = -2 is not allowed",
        ),
        (
            &["--z-lens", "0.3", "--z-prior", "-1", "8"],
            "error: --z-prior: constraints.free_z_prior[0] = -1 is not allowed",
        ),
        (
            &["--z-lens", "3"],
            "error: --z-lens 3: the default settings: products.z_source = 2 is not allowed",
        ),
    ] {
        let err = reconstruct(extra);
        assert!(err.starts_with(expected), "{extra:?}: {err}");
    }
    let model = dir.join("model.json");
    fs::write(&model, CLUSTER_MODEL_JSON).unwrap();
    for flag in ["--z-lens", "--h0", "--omega-m"] {
        let err = refused(
            &dir,
            "maps",
            &["--model", model.to_str().unwrap(), flag, "1"],
        );
        assert!(
            err.starts_with(&format!("error: {flag} is for --deflection maps only")),
            "{err}"
        );
    }
}

#[test]
fn config_errors_say_file_line_and_column_once() {
    let dir = temp_dir("config-once");
    let images = shared("AS1063/lenstool_cats/cats_gold_mul_gold.cat");
    let config = dir.join("config.json");
    let with_config = |text: &str| {
        fs::write(&config, text).unwrap();
        let path = config.to_str().unwrap();
        let args = ["--images", &images, "--z-lens", "0.348", "--config", path];
        refused(&dir, "reconstruct", &args)
    };
    let err = with_config("{\n  \"grid\": {\"cells\": 12,}\n}");
    let expected = format!(
        "error: {}: line 2, column 24: a comma before a closing bracket or brace (JSON allows \
         none there)\n",
        config.display()
    );
    assert_eq!(err, expected);
    // A number beyond f64 (JSON has no NaN or inf).
    let err = with_config("{\"products\": {\"z_source\": 1e999}}");
    assert!(
        err.contains("config.json: line 1, column 31: a number too large for a computer"),
        "{err}"
    );
    assert_eq!(err.matches("line").count(), 1, "{err}");
    // The model file of `wslap maps` likewise.
    let model = dir.join("model.json");
    fs::write(&model, "{\"z_lens\": 0.3,\n \"components\": [}").unwrap();
    let err = refused(&dir, "maps", &["--model", model.to_str().unwrap()]);
    assert!(err.contains("model.json: line 2, column 17: "), "{err}");
    assert_eq!(err.matches("line").count(), 1, "{err}");
}

/// Files saved with a byte-order mark (as Windows editors do) read as without one; the forms
/// of `--z-prior` that the help gives are taken, a third is refused in words; an option's error
/// names the option.
#[test]
fn byte_order_marks_and_option_forms_as_people_write_them() {
    let dir = temp_dir("bom");
    let images = shared("AS1063/lenstool_cats/cats_gold_mul_gold.cat");
    let config = dir.join("config.json");
    // Past the mark, the file is read: the error is about its value, not its first byte.
    fs::write(&config, "\u{feff}{\"grid\": {\"cells\": 0}}").unwrap();
    let path = config.to_str().unwrap();
    let err = refused(
        &dir,
        "reconstruct",
        &["--images", &images, "--z-lens", "0.348", "--config", path],
    );
    assert!(err.contains("grid.cells = 0 is not allowed"), "{err}");
    fs::write(
        &config,
        r#"{"objective": {"strength": 0.1}, "products": {"pixels": 32}}"#,
    )
    .unwrap();
    for prior in [&["0.5,7"][..], &["0.5", "7"][..]] {
        let out = dir.join("out");
        let mut args = vec!["reconstruct", "--images", &images, "--z-lens", "0.348"];
        args.extend([
            "--config",
            path,
            "--out",
            out.to_str().unwrap(),
            "--z-prior",
        ]);
        args.extend(prior);
        let run = wslap(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let s = summary(&out);
        let given = s["settings"]["constraints"]["free_z_prior"].clone();
        assert_eq!(given, serde_json::json!([0.5, 7.0]), "{prior:?}");
    }
    // A hold-out system that is not in the catalogue blames the option, not the settings file.
    let err = refused(
        &dir,
        "reconstruct",
        &[
            "--images",
            &images,
            "--z-lens",
            "0.348",
            "--config",
            path,
            "--holdout",
            "999",
        ],
    );
    assert!(
        err.starts_with("error: --holdout: constraints: hold-out system \"999\""),
        "{err}"
    );
    // So does --free-z (it had no prefix).
    let err = refused(
        &dir,
        "reconstruct",
        &[
            "--images", &images, "--z-lens", "0.348", "--config", path, "--free-z", "999",
        ],
    );
    assert!(
        err.starts_with("error: --free-z: constraints: free_z_systems: system \"999\""),
        "{err}"
    );
    for prior in [&["1,2", "3,4"][..], &["1"][..]] {
        let mut args = vec!["--images", &images, "--z-lens", "0.348", "--z-prior"];
        args.extend(prior);
        let err = refused(&dir, "reconstruct", &args);
        assert!(
            err.contains("--z-prior needs two redshifts, LOW,HIGH (e.g. --z-prior 0.5,8)"),
            "{err}"
        );
    }
}

/// Settings that cannot run are refused before any work, naming the file (or the option) and
/// the field: a source in front of the lens, an iteration count past the bound, a grid no
/// memory holds. Each run would otherwise take minutes at least (10^6 QADP iterations).
#[test]
fn settings_that_cannot_run_are_refused_before_the_solve() {
    let dir = temp_dir("settings-early");
    let images = shared("AS1063/lenstool_cats/cats_gold_mul_gold.cat");
    let config = dir.join("config.json");
    let name = config.display().to_string();
    let with_config = |text: &str, more: &[&str]| {
        fs::write(&config, text).unwrap();
        let path = config.to_str().unwrap();
        let mut args = vec!["--images", &images, "--z-lens", "0.348", "--config", path];
        args.extend(more);
        let t = std::time::Instant::now();
        let err = refused(&dir, "reconstruct", &args);
        (err, t.elapsed().as_secs_f64())
    };
    let slow = "\"solver\": {\"method\": \"qadp\", \"iterations\": 1000000}, \
                \"objective\": {\"regulariser\": \"none\", \"strength\": 0, \
                \"image_plane_iterations\": 0}";
    let (err, seconds) = with_config(
        &format!("{{{slow}, \"products\": {{\"z_source\": 0.2}}}}"),
        &[],
    );
    assert_eq!(
        err,
        format!(
            "error: {name}: products.z_source = 0.2 is not allowed (a source must be behind the \
             lens: z_s > z_lens = 0.348)\n"
        )
    );
    assert!(seconds < 30.0, "refused after {seconds} s");
    let (err, _) = with_config(&format!("{{{slow}}}"), &["--default-z", "0.3"]);
    assert!(
        err.starts_with("error: --default-z: constraints.default_z = 0.3 is not allowed (a source must be behind the lens"),
        "{err}"
    );
    let (err, _) = with_config("{\"solver\": {\"iterations\": 1000000000000000}}", &[]);
    assert!(
        err.starts_with(&format!(
            "error: {name}: solver.iterations = 1e15 is not allowed (at most 10^6"
        )),
        "{err}"
    );
    let (err, _) = with_config(&format!("{{{slow}}}"), &["--iterations", "2000000"]);
    assert!(
        err.starts_with("error: --iterations: solver.iterations = 2000000 is not allowed"),
        "{err}"
    );
    // 256^2 cells refined four times over: a matrix of petabytes.
    let (err, seconds) = with_config(
        &format!(
            "{{{slow}, \"grid\": {{\"cells\": 256, \"refinements\": 4, \
             \"refine_fraction\": 1}}}}"
        ),
        &[],
    );
    assert!(
        err.starts_with(&format!("error: {name}: this run would need about ")),
        "{err}"
    );
    assert!(
        err.contains("(16777216 cells after refinement)") && err.contains("; lower grid.cells"),
        "{err}"
    );
    assert!(seconds < 30.0, "refused after {seconds} s");
}

#[test]
fn huge_files_are_refused_before_reading() {
    let dir = temp_dir("huge");
    // Sparse files: their size is in the metadata, no disk is used.
    let cat = dir.join("huge.cat");
    fs::File::create(&cat)
        .unwrap()
        .set_len(2 << 30)
        .expect("sparse file");
    let err = refused(
        &dir,
        "reconstruct",
        &["--images", cat.to_str().unwrap(), "--z-lens", "0.3"],
    );
    assert_eq!(
        err,
        format!(
            "error: {}: 2147483648 bytes is more than the limit of {} bytes for a catalogue\n",
            cat.display(),
            wslap::MAX_CATALOG_BYTES
        )
    );
    let fits = dir.join("huge.fits");
    fs::File::create(&fits)
        .unwrap()
        .set_len(wslap::MAX_FITS_BYTES + 1)
        .expect("sparse file");
    let err = refused(
        &dir,
        "maps",
        &[
            "--deflection",
            fits.to_str().unwrap(),
            fits.to_str().unwrap(),
            "--z-lens",
            "0.3",
        ],
    );
    assert!(
        err.contains("huge.fits: 1073741825 bytes is more than the limit of 1073741824 bytes for a FITS file"),
        "{err}"
    );
}

#[test]
fn catalogue_units_nan_and_empty_systems_name_file_and_line() {
    let dir = temp_dir("units");
    let run = |name: &str, text: &str, extra: &[&str]| {
        let path = dir.join(name);
        fs::write(&path, text).unwrap();
        let mut args = vec!["--images", path.to_str().unwrap(), "--z-lens", "0.3"];
        args.extend(extra);
        refused(&dir, "reconstruct", &args)
    };
    // Degrees under a relative header.
    let err = run(
        "deg.cat",
        "#REFERENCE 3 342.18322 -44.530889\n1.1 342.19 -44.52 0.1 0.1 0 1.2 0\n\
         1.2 342.17 -44.54 0.1 0.1 0 1.2 0\n",
        &[],
    );
    assert!(
        err.contains("deg.cat: line 2, column 2 (x): '342.19'")
            && err.contains("looks like a position in degrees"),
        "{err}"
    );
    // Arcsec offsets without their header.
    let err = run(
        "arcsec.cat",
        "1.1 12.5 30.2 0.1 0.1 0 1.2 0\n1.2 40.1 -20.3 0.1 0.1 0 1.2 0\n",
        &[],
    );
    assert!(
        err.contains("arcsec.cat: line ") && err.contains("#REFERENCE 3 ra0 dec0"),
        "{err}"
    );
    // inf and an overflowing number.
    let err = run(
        "inf.cat",
        "1.1 342.19 -44.52 0.1 0.1 0 1.2 0\n1.2 342.17 -44.54 0.1 1e999 0 1.2 0\n",
        &[],
    );
    assert!(
        err.contains("inf.cat: line 2, column 5 (b): '1e999' is out of range"),
        "{err}"
    );
    // Every system unusable (a single image): the file and the line of each are named.
    let err = run(
        "single.cat",
        "# two single images\n1.1 342.19 -44.52 0.1 0.1 0 1.2 0\n2.1 342.17 -44.54 0.1 0.1 0 2 0\n",
        &[],
    );
    assert!(
        err.contains("single.cat: no system is left")
            && err.contains("1 (a single image, line 2), 2 (a single image, line 3)"),
        "{err}"
    );
    // A source in front of the lens.
    let err = run(
        "front.cat",
        "1.1 342.19 -44.52 0.1 0.1 0 1.2 0\n1.2 342.17 -44.54 0.1 0.1 0 1.2 0\n\
         2.1 342.18 -44.53 0.1 0.1 0 0.2 0\n2.2 342.18 -44.51 0.1 0.1 0 0.2 0\n",
        &[],
    );
    assert!(
        err.contains("front.cat: line 3 (system 2): z_s = 0.2 is not behind the lens"),
        "{err}"
    );
    // An arcs file with an empty image, and one with a system in front of the lens.
    let arcs = dir.join("arcs.json");
    let with_arcs = |text: &str| {
        fs::write(&arcs, text).unwrap();
        let args = ["--arcs", arcs.to_str().unwrap(), "--z-lens", "0.3"];
        refused(&dir, "reconstruct", &args)
    };
    let err =
        with_arcs("{\"systems\": [\n {\"id\": \"a\", \"z\": 2, \"images\": [[[1, 2]], []]}]}");
    assert!(
        err.contains("arcs.json: line 2: system a: no pixels in image 1"),
        "{err}"
    );
    let err = with_arcs(concat!(
        "{\"systems\": [\n",
        " {\"id\": \"a\", \"z\": 2, \"images\": [[[1, 2]], [[-1, -2]]]},\n",
        " {\"id\": \"b\", \"z\": 0.2, \"images\": [[[3, 2]], [[-3, -2]]]}]}"
    ));
    assert!(
        err.contains(
            "arcs.json: line 3 (system b): z_s = 0.2 is not behind the lens (z_lens = 0.3)"
        ),
        "{err}"
    );
}

#[test]
fn config_prints_every_setting_and_reads_back_as_the_defaults() {
    use wslap::ReconstructConfig;
    let out = wslap(&["config"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let read = ReconstructConfig::from_json_str(&text, "config output").unwrap();
    assert_eq!(read, ReconstructConfig::default());
    // Every field is written, the unset ones as null.
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["members"]["c_prior_sigma"], serde_json::Value::Null);
    assert_eq!(json["solver"]["iterations"], 8000);
    assert_eq!(
        json,
        serde_json::to_value(ReconstructConfig::default()).unwrap()
    );
}

/// A DS9 region file (fk5) as arcs: the teaching example's images drawn as 0.4-arcsec circles
/// labelled `text={1.1 z=1.5}`. Without a member catalogue the frame's origin is the regions'
/// mean position (said on stderr); the lens found fits the images.
#[test]
fn reconstruct_from_a_ds9_region_file() {
    let dir = temp_dir("regions");
    let cat = wslap::app::examples::teaching_image_catalog().unwrap();
    let (catalog, _) = wslap::parse_image_catalog(&cat, "images.cat", None).unwrap();
    let sky = catalog.reference.unwrap();
    let mut reg = String::from("# Region file format: DS9 version 4.1\nfk5\n");
    for s in &catalog.systems {
        for im in &s.images {
            let (ra, dec) = sky.offset_to_radec(im.position);
            let z = s.z.unwrap();
            // Image ids as letters (1.1 -> 1.a): sources.json must keep the labels' ids.
            let (system, image) = im.id.split_once('.').unwrap();
            let letter = (b'a' + image.parse::<u8>().unwrap() - 1) as char;
            reg += &format!("circle({ra:.8},{dec:.8},0.4\") # text={{{system}.{letter} z={z}}}\n");
        }
    }
    let regions = dir.join("arcs.reg");
    fs::write(&regions, reg).unwrap();
    // A fixed strength: with five systems on 16 x 16 cells the cross-validation of "auto"
    // cannot choose (every candidate's held-out median is 3.6 - 8.4 arcsec, each give or take
    // 1.6 - 3.3 over a bootstrap of the systems), and this test is about reading regions.
    let config = dir.join("config.json");
    fs::write(
        &config,
        r#"{"grid": {"cells": 16}, "products": {"pixels": 64, "size_arcsec": 60},
            "objective": {"regulariser": "gradient", "strength": 1.0}}"#,
    )
    .unwrap();
    let out_dir = dir.join("out");
    let out = wslap(&[
        "reconstruct",
        "--arcs",
        regions.to_str().unwrap(),
        "--z-lens",
        "0.3",
        "--config",
        config.to_str().unwrap(),
        "--iterations",
        "1000",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(
            "arcs.reg: no catalogue gives a frame, so its origin is the regions' mean position"
        ),
        "{stderr}"
    );
    let s = summary(&out_dir);
    let n_images: usize = catalog.systems.iter().map(|s| s.images.len()).sum();
    // About pi 0.4^2 / 0.2^2 = 12.6 lattice points per circle.
    let pixels = s["constraint_pixels"].as_u64().unwrap() as usize;
    assert!(
        (8 * n_images..=16 * n_images).contains(&pixels),
        "{pixels} pixels"
    );
    assert_eq!(s["settings"]["constraints"]["mode"], "arcs");
    let median = s["image_offset_median_arcsec"].as_f64().unwrap();
    assert!(median < 0.5, "median image offset {median} arcsec");
    let sources: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out_dir.join("sources.json")).unwrap()).unwrap();
    let ids: Vec<&str> = sources
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| s["observed"].as_array().unwrap())
        .map(|o| o["id"].as_str().unwrap())
        .collect();
    assert!(
        ids.len() == n_images
            && ids
                .iter()
                .all(|id| id.ends_with(".a") || id.ends_with(".b")),
        "{ids:?}"
    );
    // A bad region names its file and line.
    fs::write(&regions, "fk5\ncircle(150,2.2,1\")\n").unwrap();
    let err = refused(
        &dir,
        "reconstruct",
        &["--arcs", regions.to_str().unwrap(), "--z-lens", "0.3"],
    );
    assert!(
        err.contains("arcs.reg: line 2: a region without a label"),
        "{err}"
    );
}

/// `wslap maps --lenstool` evaluates a published Lenstool model (AS1063's CATS gold bestopt.par
/// with its potfile): the same Einstein radius as the library's model of the same files on the
/// same map, maps in the .par's sky frame, a potfile found where Lenstool would find it or
/// beside the .par, and a clear error when it is not found.
#[test]
fn maps_of_a_lenstool_model_match_the_library_and_name_a_missing_potfile() {
    use wslap::load_lenstool_model;
    use wslap::{ProductOptions, Products};
    let par = shared("AS1063/lenstool_cats/cats_gold_bestopt.par");
    let potfile = shared("AS1063/lenstool_cats/cats_gold_ref_potential_w_clumpNE.cat");
    let dir = temp_dir("lenstool");
    let out = wslap(&[
        "maps",
        "--lenstool",
        &par,
        "--potfile",
        &potfile,
        "--z-source",
        "2",
        "--size",
        "160",
        "--pixels",
        "200",
        "--out",
        &dir.display().to_string(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let model = load_lenstool_model(Path::new(&par), &[Path::new(&potfile)]).unwrap();
    let opts = ProductOptions {
        z_source: 2.0,
        size_arcsec: 160.0,
        pixels: 200,
        ..ProductOptions::default()
    };
    let library = Products::from_lens(&model.lens, model.plane, model.reference, &opts).unwrap();
    let theta_e = summary(&dir)["einstein_radius_arcsec"].as_f64().unwrap();
    assert!(
        (theta_e - library.curves.einstein_radius_arcsec).abs() <= 1e-9 * theta_e,
        "{theta_e} vs {}",
        library.curves.einstein_radius_arcsec
    );
    // The published model's radius at z_s = 2 (tests/inversion/reconstruct.rs checks it against the
    // reconstruction): about 30 arcsec.
    assert!((25.0..35.0).contains(&theta_e), "{theta_e}");
    let fits = read_image(&fs::read(dir.join("kappa.fits")).unwrap(), "kappa.fits").unwrap();
    let (geometry, reference) = fits.geometry().unwrap();
    assert_eq!(geometry.pixels, 200);
    let reference = reference.expect("the .par's reference");
    let wanted = model.reference.unwrap();
    assert!((reference.ra_deg - wanted.ra_deg).abs() < 1e-6);
    assert!((reference.dec_deg - wanted.dec_deg).abs() < 1e-6);

    // Without --potfile the .par's own `filein` is looked for next to it; here it has another
    // name, and the error says which file and what to do.
    let out = wslap(&[
        "maps",
        "--lenstool",
        &par,
        "--out",
        &dir.join("o").display().to_string(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("ref_potential_w_clumpNE.cat")
            && err.contains("give its member catalogue with --potfile"),
        "{err}"
    );
    // A `filein` naming a folder of the modeller's machine: the catalogue is read where
    // Lenstool run in the working folder would read it, else by its name beside the .par,
    // with a warning each time; the model is the same.
    let pkg = dir.join("pkg");
    fs::create_dir_all(dir.join("model/as1063")).unwrap();
    fs::create_dir_all(&pkg).unwrap();
    let text = fs::read_to_string(&par).unwrap().replace(
        "filein  1 ref_potential_w_clumpNE.cat",
        "filein  1 model/as1063/members.cat",
    );
    fs::write(pkg.join("best.par"), text).unwrap();
    fs::copy(&potfile, dir.join("model/as1063/members.cat")).unwrap();
    let moved = |out: &str| {
        Command::new(env!("CARGO_BIN_EXE_wslap"))
            .current_dir(&dir.0)
            .args(["maps", "--lenstool", "pkg/best.par", "--z-source", "2"])
            .args(["--size", "160", "--pixels", "200", "--out", out])
            .output()
            .unwrap()
    };
    let out = moved("here");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(
            "warning: pkg/best.par: line 87: the potfile's `filein model/as1063/members.cat` is \
             not in the .par's folder (pkg/model/as1063/members.cat does not exist): \
             model/as1063/members.cat is read instead"
        ),
        "{err}"
    );
    assert_eq!(
        summary(&dir.join("here"))["einstein_radius_arcsec"].as_f64(),
        Some(theta_e)
    );
    fs::rename(
        dir.join("model/as1063/members.cat"),
        pkg.join("members.cat"),
    )
    .unwrap();
    let out = moved("beside");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("pkg/members.cat is read instead"), "{err}");
    assert_eq!(
        summary(&dir.join("beside"))["einstein_radius_arcsec"].as_f64(),
        Some(theta_e)
    );

    // --potfile belongs to --lenstool.
    let out = wslap(&["maps", "--model", &par, "--potfile", &potfile, "--out", "x"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot be used with"));
}

/// `wslap images` on the elliptical NFW halo of tests/data/time_delays.json: the images and
/// delays of lenstronomy (tests/data/time_delays_reference.py), from the model file, from the
/// source's RA/Dec, and from the deflection maps `wslap maps` writes (with their ZLENS card).
#[test]
fn images_match_lenstronomy_from_a_model_and_from_maps() {
    let reference: serde_json::Value =
        serde_json::from_str(include_str!("data/time_delays.json")).unwrap();
    let case = reference["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "nfw_ellipse")
        .unwrap();
    let source = &case["sources"][0];
    let (bx, by) = (
        source["beta"][0].as_f64().unwrap(),
        source["beta"][1].as_f64().unwrap(),
    );
    let want: Vec<(f64, f64, f64)> = source["images"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| {
            (
                i["x"].as_f64().unwrap(),
                i["y"].as_f64().unwrap(),
                i["arrival_days"].as_f64().unwrap(),
            )
        })
        .collect();
    let dir = temp_dir("images");
    let model = dir.join("model.json");
    fs::write(
        &model,
        r#"{"z_lens": 0.3, "reference": {"ra": 342.18, "dec": -44.53}, "components": [
            {"type": "nfw", "x": 1.0, "y": -2.0, "m200": 1.0e15, "c200": 5.0, "q": 0.7, "pa": 30.0}]}"#,
    )
    .unwrap();
    let run = |args: &[&str]| -> serde_json::Value {
        let out = wslap(args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("JSON on stdout")
    };
    // Images in order of arrival, as lenstronomy sorted them: positions and delays.
    let check = |got: &serde_json::Value, position_atol: f64, delay_rtol: f64| {
        let images = got["images"].as_array().unwrap();
        assert_eq!(images.len(), want.len(), "{got}");
        for (image, &(x, y, t)) in images.iter().zip(&want) {
            let p = &image["position_arcsec"];
            let (px, py) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
            assert!(
                (px - x).hypot(py - y) < position_atol,
                "image at ({px}, {py}), lenstronomy ({x}, {y})"
            );
            let delay = image["delay_days"].as_f64().unwrap();
            let expected = t - want[0].2;
            assert!(
                (delay - expected).abs() <= delay_rtol * expected.abs().max(1.0),
                "delay {delay} d at ({x}, {y}), lenstronomy {expected} d"
            );
            assert!(image["radec_deg"].is_array());
        }
        assert_eq!(images[0]["delay_days"].as_f64(), Some(0.0));
    };
    let m = model.to_str().unwrap();
    let (sx, sy) = (bx.to_string(), by.to_string());
    let from_model = run(&[
        "images",
        "--model",
        m,
        "--source",
        &sx,
        &sy,
        "--z-source",
        "2",
    ]);
    // The model itself: Newton to 1e-11 arcsec, delays to the potentials' 1e-10.
    check(&from_model, 1e-6, 1e-6);
    let radec = &from_model["source_radec_deg"];
    let (ra, dec) = (radec[0].to_string(), radec[1].to_string());
    let from_sky = run(&[
        "images",
        "--model",
        m,
        "--source-radec",
        &ra,
        &dec,
        "--z-source",
        "2",
    ]);
    check(&from_sky, 1e-6, 1e-6);
    // Maps of 0.2 arcsec pixels: positions to a few 1e-3 arcsec, delays to 1e-5 (measured:
    // 6.4e-3 arcsec at the central image, 5e-6 relative on the shortest delay, 51 days).
    let maps = dir.join("maps");
    let out = wslap(&[
        "maps",
        "--model",
        m,
        "--size",
        "80",
        "--pixels",
        "400",
        "--out",
        maps.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    assert!(maps.join("psi.fits").exists());
    let from_maps = run(&[
        "images",
        "--maps",
        maps.to_str().unwrap(),
        "--source",
        &sx,
        &sy,
        "--z-source",
        "2",
    ]);
    check(&from_maps, 0.01, 1e-5);
    // Bad input says what is wrong.
    let out = wslap(&[
        "images",
        "--model",
        m,
        "--source-radec",
        "ten",
        "-44",
        "--z-source",
        "2",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("'ten' is not an angle"), "{err}");
    let out = wslap(&[
        "images",
        "--model",
        m,
        "--source",
        &sx,
        &sy,
        "--z-source",
        "0.2",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("greater than the lens redshift"), "{err}");
}

/// `--ensemble`: the members' maps in range/, and the summary maps are their statistics:
/// kappa-mean and kappa-std the mean and standard deviation of range/NNN-kappa.fits per pixel,
/// magnif-p50 between p16 and p84; the Einstein-radius range in summary.json brackets the
/// members'; the same seed gives the same ensemble; a size out of range is refused up front.
#[test]
fn reconstruct_ensemble_writes_its_statistics() {
    let dir = temp_dir("ensemble");
    let images = teaching_images(&dir);
    let config = dir.join("config.json");
    fs::write(
        &config,
        r#"{"grid": {"cells": 12}, "products": {"pixels": 48, "size_arcsec": 60},
            "objective": {"strength": 0.1}}"#,
    )
    .unwrap();
    let run = |out: &Path, members: &str| {
        wslap(&[
            "reconstruct",
            "--images",
            images.to_str().unwrap(),
            "--z-lens",
            "0.3",
            "--config",
            config.to_str().unwrap(),
            "--ensemble",
            members,
            "--seed",
            "7",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let out_dir = dir.join("out");
    let out = run(&out_dir, "4");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |path: PathBuf| {
        let bytes = fs::read(&path).unwrap();
        read_image(&bytes, &path.display().to_string())
            .unwrap()
            .to_map()
            .unwrap()
            .data
    };
    let members: Vec<Vec<f64>> = (1..=4)
        .map(|k| read(out_dir.join(format!("range/{k:03}-kappa.fits"))))
        .collect();
    let mean = read(out_dir.join("kappa-mean.fits"));
    let std = read(out_dir.join("kappa-std.fits"));
    let main = read(out_dir.join("kappa.fits"));
    let ensemble: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out_dir.join("ensemble.json")).unwrap()).unwrap();
    // The factor the spreads were widened by: at least 1, 1 without a calibration.
    let factor = ensemble["calibration"]["factor"].as_f64().unwrap_or(1.0);
    assert!(factor >= 1.0, "{}", ensemble["calibration"]);
    // FITS stores float32: compare to its precision. kappa-std is the members' rms deviation
    // from the main map (kappa.fits), widened by the factor.
    for i in 0..mean.len() {
        let m = members.iter().map(|k| k[i]).sum::<f64>() / 4.0;
        let s = (members
            .iter()
            .map(|k| (k[i] - main[i]).powi(2))
            .sum::<f64>()
            / 4.0)
            .sqrt();
        assert!((mean[i] - m).abs() <= 1e-6 * m.abs().max(1.0), "pixel {i}");
        assert!(
            (std[i] - factor * s).abs() <= 1e-6 * m.abs().max(1.0) * factor,
            "pixel {i}"
        );
    }
    assert!(std.iter().any(|&s| s > 0.0), "the members differ");
    let (p16, p50, p84) = (
        read(out_dir.join("magnif-p16.fits")),
        read(out_dir.join("magnif-p50.fits")),
        read(out_dir.join("magnif-p84.fits")),
    );
    assert!((0..p50.len()).all(|i| p16[i] <= p50[i] && p50[i] <= p84[i]));
    let mut radii: Vec<f64> = ensemble["members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["einstein_radius_arcsec"].as_f64().unwrap())
        .collect();
    assert_eq!(radii.len(), 4);
    let s = summary(&out_dir);
    let range = &s["einstein_radius_interval_arcsec"];
    let (lo, hi) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
    // The members' 16th and 84th percentiles' distances from their median (four values:
    // linear interpolation between the sorted ones), times the factor, about the main run's
    // Einstein radius.
    radii.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let pos = q * 3.0;
        let (i, t) = (pos.floor() as usize, pos.fract());
        radii[i] + t * (radii[(i + 1).min(3)] - radii[i])
    };
    let theta = s["einstein_radius_arcsec"].as_f64().unwrap();
    let want = [
        theta - factor * (at(0.5) - at(0.16)),
        theta + factor * (at(0.84) - at(0.5)),
    ];
    assert!(
        (lo - want[0]).abs() < 1e-9 && (hi - want[1]).abs() < 1e-9,
        "{lo} {hi}, want {want:?} from {radii:?} about {theta}"
    );
    assert!(lo <= theta && theta <= hi);
    assert_eq!(s["mass_within_interval_msun"].as_array().unwrap().len(), 3);
    // `wslap lookup` gives the ensemble's interval at its redshift, and says why not at another.
    let lookup = |z: &str| -> serde_json::Value {
        let out = wslap(&[
            "lookup",
            "--maps",
            out_dir.to_str().unwrap(),
            "--at-arcsec",
            "5",
            "3",
            "--z-source",
            z,
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let at2 = lookup("2");
    let band = &at2["positions"][0]["magnification_interval"];
    assert!(
        band[0].as_f64().unwrap() <= band[1].as_f64().unwrap(),
        "{at2}"
    );
    let at3 = lookup("3");
    assert!(at3["positions"][0].get("magnification_interval").is_none());
    assert!(
        at3["interval"].as_str().unwrap().contains("z_s = 2"),
        "{at3}"
    );
    // The same seed, the same members.
    let again = dir.join("again");
    assert!(run(&again, "4").status.success());
    assert_eq!(read(again.join("kappa-std.fits")), std);
    // Refused before any work.
    let out = run(&dir.join("bad"), "1");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--ensemble") && err.contains("2 to 200"),
        "{err}"
    );
    assert!(!dir.join("bad").join("summary.json").exists());
}

/// A Lenstool model with a background group (tests/data/lenstool/multiplane.par, after A370's
/// CATS bestopt.par): refused with the option to use, then evaluated in the single-plane
/// approximation with a warning naming the block moved; members with magnitude 99 are skipped
/// with a warning.
#[test]
fn maps_of_a_multi_plane_lenstool_model_need_single_plane() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lenstool");
    let par = data.join("multiplane.par").display().to_string();
    let dir = temp_dir("multiplane");
    let out_dir = dir.join("out").display().to_string();
    let base = [
        "maps",
        "--lenstool",
        &par,
        "--out",
        &out_dir,
        "--pixels",
        "64",
        "--size",
        "100",
    ];
    let out = wslap(&base);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("multiplane.par:42")
            && err.contains("`potfile1`")
            && err.contains("--single-plane"),
        "{err}"
    );
    let out = wslap(&[&base[..], &["--single-plane"]].concat());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: ") && err.contains("single-plane approximation: block `potfile1`"),
        "{err}"
    );
    assert!(
        err.contains("members.cat: line 4") && err.contains("no measurement"),
        "{err}"
    );
    assert!(Path::new(&out_dir).join("kappa.fits").exists());
    // --single-plane belongs to --lenstool.
    let out = wslap(&["maps", "--model", &par, "--single-plane", "--out", "x"]);
    assert!(!out.status.success());
}

/// `wslap maps --deflection` with published-style maps whose borders are NaN or zeros
/// (tests/data/hff_borders_*): used, with a warning counting the pixels without data, which
/// stay NaN in the maps written.
#[test]
fn maps_of_deflection_fits_with_blank_borders() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let x = data
        .join("hff_borders_x-arcsec-deflect.fits")
        .display()
        .to_string();
    let y = data
        .join("hff_borders_y-arcsec-deflect.fits")
        .display()
        .to_string();
    let dir = temp_dir("borders");
    let out = wslap(&[
        "maps",
        "--deflection",
        &x,
        &y,
        "--z-lens",
        "0.3",
        "--out",
        &dir.display().to_string(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("hff_borders_x-arcsec-deflect.fits: 446 pixels have no data"),
        "{err}"
    );
    let kappa = read_image(&fs::read(dir.join("kappa.fits")).unwrap(), "kappa.fits").unwrap();
    assert_eq!(kappa.non_finite_count(), 446);
    let radius = summary(&dir)["einstein_radius_arcsec"].as_f64().unwrap();
    assert!((3.0..6.0).contains(&radius), "{radius}");
}

/// `wslap lookup` on the maps of an SIS model: kappa, shear and magnification at the source's
/// redshift against the analytic SIS (kappa = |gamma| = theta_E / 2r, mu = 1 / (1 - theta_E/r)
/// with theta_E at z_s), at a position in arcsec, at RA/Dec and from a file of positions (with
/// ids, sexagesimal, a point off the maps); no ensemble interval without an ensemble.
#[test]
fn lookup_matches_an_sis() {
    let dir = temp_dir("lookup");
    let model = dir.join("model.json");
    fs::write(
        &model,
        r#"{"z_lens": 0.3, "reference": {"ra": 342.18, "dec": -44.53}, "components": [
            {"type": "sis", "x": 0.0, "y": 0.0, "sigma_v": 1000.0}]}"#,
    )
    .unwrap();
    let maps = dir.join("maps");
    let out = wslap(&[
        "maps",
        "--model",
        model.to_str().unwrap(),
        "--size",
        "120",
        "--pixels",
        "480",
        "--out",
        maps.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let plane = wslap::LensPlane::new(wslap::Cosmology::default(), 0.3).unwrap();
    let f = plane.distance_ratio(2.0).unwrap();
    let theta_e = f * wslap::sis_theta_e_arcsec(1000.0);
    let lookup = |args: &[&str]| -> serde_json::Value {
        let mut all = vec![
            "lookup",
            "--maps",
            maps.to_str().unwrap(),
            "--z-source",
            "2",
        ];
        all.extend(args);
        let out = wslap(&all);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("JSON")
    };
    // Bilinear sampling of 0.25" pixels at r = 25": 1e-3 of kappa and mu is ample.
    let check = |p: &serde_json::Value, r: f64| {
        let kappa = theta_e / (2.0 * r);
        let get = |k: &str| p[k].as_f64().unwrap_or_else(|| panic!("{k} in {p}"));
        assert!(
            (get("kappa") - kappa).abs() < 1e-3 * kappa,
            "{p} vs {kappa}"
        );
        assert!((get("gamma") - kappa).abs() < 1e-3 * kappa, "{p}");
        let mu = 1.0 / (1.0 - theta_e / r);
        assert!(
            (get("magnification") - mu).abs() < 1e-3 * mu.abs(),
            "{p} vs {mu}"
        );
        assert!(p.get("magnification_interval").is_none());
    };
    let at = lookup(&["--at-arcsec", "15", "-20"]);
    assert!(at["interval"].as_str().unwrap().starts_with("none"));
    check(&at["positions"][0], 25.0);
    let radec = &at["positions"][0]["radec_deg"];
    let (ra, dec) = (radec[0].to_string(), radec[1].to_string());
    check(&lookup(&["--at", &ra, &dec])["positions"][0], 25.0);
    // The same point in sexagesimal, with an id, and one far off the maps.
    let ra_deg = radec[0].as_f64().unwrap();
    let dec_deg = radec[1].as_f64().unwrap();
    let sexagesimal = |v: f64, scale: f64| {
        let sign = if v < 0.0 { "-" } else { "" };
        let x = v.abs() / scale;
        let (d, m) = (x.trunc(), (x.fract() * 60.0).trunc());
        let s = (x * 3600.0) - d * 3600.0 - m * 60.0;
        format!("{sign}{d}:{m}:{s:.6}")
    };
    let file = dir.join("positions.txt");
    fs::write(
        &file,
        format!(
            "# id RA Dec\nsn1 {} {}\nfar {} {}\n",
            sexagesimal(ra_deg, 15.0),
            sexagesimal(dec_deg, 1.0),
            ra_deg,
            dec_deg + 0.1
        ),
    )
    .unwrap();
    let listed = lookup(&["--positions", file.to_str().unwrap()]);
    let rows = listed["positions"].as_array().unwrap();
    assert_eq!(rows[0]["id"], "sn1");
    check(&rows[0], 25.0);
    assert_eq!(rows[1]["has_data"], false);
    assert!(rows[1].get("magnification").is_none());
    // A file of positions that is refused: the error message.
    let refused_file = |text: &str| {
        fs::write(&file, text).unwrap();
        let out = wslap(&[
            "lookup",
            "--maps",
            maps.to_str().unwrap(),
            "--z-source",
            "2",
            "--positions",
            file.to_str().unwrap(),
        ]);
        assert!(!out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    // A bad line names the file and line.
    let err = refused_file("sn1 342.18\n");
    assert!(err.contains("positions.txt: line 1"), "{err}");
    // More positions than a catalogue has rows are refused (8 million took 2.6 GB), in words.
    let err = refused_file(&"0 0\n".repeat(wslap::MAX_CATALOG_ROWS + 1));
    assert!(
        err.contains("positions.txt: 1000001 positions is more than the limit of 1000000"),
        "{err}"
    );
}

/// `--out` naming an existing file is refused before any work, not after a whole run.
#[test]
fn out_naming_a_file_is_refused_first() {
    let dir = temp_dir("out-file");
    let file = dir.join("results.txt");
    fs::write(&file, "keep me").unwrap();
    let images = shared("AS1063/lenstool_cats/cats_gold_mul_gold.cat");
    let out = file.to_str().unwrap();
    let t = std::time::Instant::now();
    let run = wslap(&[
        "reconstruct",
        "--images",
        &images,
        "--z-lens",
        "0.348",
        "--out",
        out,
    ]);
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("--out names an existing file"), "{err}");
    assert!(
        t.elapsed().as_secs_f64() < 5.0,
        "refused only after the run"
    );
    assert_eq!(fs::read_to_string(&file).unwrap(), "keep me");
}

/// The run's line names the external shear it fitted (on by default), or says that the
/// least-mass regulariser fitted none, as summary.json does.
#[test]
fn reconstruct_says_which_external_shear_it_fitted() {
    let dir = temp_dir("external-shear");
    let images = teaching_images(&dir);
    for (regulariser, said) in [
        ("gradient", "; external shear "),
        (
            "density",
            "; no external shear (the least-mass regulariser fits none)",
        ),
    ] {
        let config = dir.join(format!("{regulariser}.json"));
        let text = format!(
            r#"{{"grid": {{"cells": 16}}, "objective": {{"strength": 0.1, "regulariser": "{regulariser}"}}, "products": {{"pixels": 64}}}}"#
        );
        fs::write(&config, text).unwrap();
        let out_dir = dir.join(regulariser);
        let out = wslap(&[
            "reconstruct",
            "--images",
            images.to_str().unwrap(),
            "--z-lens",
            "0.3",
            "--config",
            config.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        let printed = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.status.success(), "{printed}");
        assert!(printed.contains(said), "{regulariser}: {printed}");
        let s = summary(&out_dir);
        assert_eq!(
            s["external_shear"].is_null(),
            regulariser == "density",
            "{s}"
        );
        assert_eq!(s["settings"]["grid"]["external_shear_sigma"], 0.1);
        // The reason the line gives is summary.json's, which the app's caption shows.
        match s["external_shear_left_out"].as_str() {
            Some(why) => assert!(said.contains(why), "{s}"),
            None => assert_eq!(regulariser, "gradient", "{s}"),
        }
    }
}
