//! From catalogues to a mass map: the inversion (cell grid, members, constraints, region arcs,
//! the linear system, bad settings), the solvers, the stated objective, cross-validation and
//! the reconstruction end to end. Runs natively and in a dedicated browser worker (the tests
//! written with `#[test]` alone, and those that read ../shared/data, run natively only).

#[path = "../common/mod.rs"]
mod common;
mod fixtures;

mod cells;
mod constraints;
mod crossval;
// Reads tests/data from disk.
#[cfg(not(target_arch = "wasm32"))]
mod external_shear;
mod members;
mod objective;
mod reconstruct;
mod regions;
mod settings;
mod shear;
mod solver;
mod system;
