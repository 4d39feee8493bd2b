//! Files in and out: Lenstool catalogues, FITS and DS9 regions and the kappa figure, line
//! plots and multi-panel figures, and the simulated cluster's catalogues and images. Runs
//! natively and in a dedicated browser worker (file-system tests natively only).

#[path = "../common/mod.rs"]
mod common;

mod catalog;
mod formats;
mod lenstool;
mod plot;
mod simulate;
