//! WSLAP+ free-form strong-lensing mass reconstruction (Sendra, Diego, Broadhurst & Lazkoz).
//!
//! The modules follow the pipeline: cosmology → mass components → maps and critical curves →
//! rendering and file formats. Angles are arcsec in the tangent-plane frame of [method §1]
//! (+x West, +y North); every stored deflection, convergence and shear is for `D_ls/D_s = 1`.
//! The wasm boundary (`wasm.rs`) and the CLI (`main.rs`) are thin shells around this library.
//!
//! [method §1]: crate::method#1-frames-and-units

pub mod app;
pub mod arcs;
pub mod catalog;
pub mod cosmology;
pub mod curves;
pub mod demo;
pub mod ds9;
pub mod error;
pub mod fits;
pub mod grid;
pub mod images;
pub mod inversion;
pub mod lenstool_par;
pub mod limits;
pub mod maps;
pub mod method;
pub mod model;
pub mod paper;
pub mod products;
pub mod profiles;
pub mod radial;
pub mod reconstruct;
pub mod render;
pub mod simulate;
pub mod sky;
pub mod solver;
pub mod threads;
pub mod units;

#[cfg(target_arch = "wasm32")]
mod wasm;

pub use cosmology::{Cosmology, CosmologyError, LensPlane};
pub use curves::CriticalCurves;
pub use grid::{Map, MapGeometry};
pub use profiles::{Lens, MassComponent};
