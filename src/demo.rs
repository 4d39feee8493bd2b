//! Built-in example models, so that the app and the CLI show something real with no input.
//!
//! They are model files (see `model.rs`) kept as JSON text: the same text a user can download,
//! edit and load again.

/// A massive cluster at z = 0.35: an elliptical NFW halo, a central galaxy and 14 truncated-NFW
/// member galaxies. At z_s = 2 it has an Einstein radius of about 30 arcsec and a radial
/// critical curve near the centre.
pub const CLUSTER_MODEL_JSON: &str = r#"{
  "cosmology": {"h0": 70.0, "omega_m": 0.3},
  "z_lens": 0.35,
  "reference": {"ra": 342.18322, "dec": -44.53092},
  "components": [
    {"type": "nfw", "x": 0.0, "y": 0.0, "m200": 1.6e15, "c200": 6.0, "q": 0.7, "pa": 35.0},
    {"type": "tnfw", "x": 0.0, "y": 0.0, "m200": 6.0e12, "c200": 12.0, "r_trunc": 12.0},
    {"type": "tnfw", "x": 24.0, "y": 17.0, "m200": 8.0e11, "c200": 12.0, "r_trunc": 5.0},
    {"type": "tnfw", "x": -31.0, "y": -12.0, "m200": 6.0e11, "c200": 12.0, "r_trunc": 4.5},
    {"type": "tnfw", "x": 15.0, "y": -28.0, "m200": 5.0e11, "c200": 12.0, "r_trunc": 4.0},
    {"type": "tnfw", "x": -12.0, "y": 34.0, "m200": 5.0e11, "c200": 12.0, "r_trunc": 4.0},
    {"type": "tnfw", "x": 41.0, "y": 3.0, "m200": 4.0e11, "c200": 12.0, "r_trunc": 3.5},
    {"type": "tnfw", "x": -45.0, "y": 22.0, "m200": 3.0e11, "c200": 12.0, "r_trunc": 3.0},
    {"type": "tnfw", "x": 8.0, "y": 47.0, "m200": 3.0e11, "c200": 12.0, "r_trunc": 3.0},
    {"type": "tnfw", "x": -22.0, "y": -40.0, "m200": 3.0e11, "c200": 12.0, "r_trunc": 3.0},
    {"type": "tnfw", "x": 52.0, "y": -30.0, "m200": 2.5e11, "c200": 12.0, "r_trunc": 3.0},
    {"type": "tnfw", "x": -58.0, "y": -35.0, "m200": 2.0e11, "c200": 12.0, "r_trunc": 2.5},
    {"type": "tnfw", "x": 33.0, "y": 55.0, "m200": 2.0e11, "c200": 12.0, "r_trunc": 2.5},
    {"type": "tnfw", "x": -5.0, "y": -62.0, "m200": 2.0e11, "c200": 12.0, "r_trunc": 2.5},
    {"type": "tnfw", "x": 65.0, "y": 20.0, "m200": 1.5e11, "c200": 12.0, "r_trunc": 2.0}
  ]
}"#;

/// A teaching example: one isothermal galaxy-group halo and a satellite, simple enough to reason
/// about by hand (the SIS Einstein radius is `4 pi (sigma_v/c)^2 D_ls/D_s`).
pub const TEACHING_MODEL_JSON: &str = r#"{
  "z_lens": 0.3,
  "components": [
    {"type": "sis", "x": 0.0, "y": 0.0, "sigma_v": 700.0},
    {"type": "sis", "x": 18.0, "y": 6.0, "sigma_v": 150.0}
  ]
}"#;
