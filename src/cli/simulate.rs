//! `wslap simulate`: the simulated A1689-like cluster of the WSLAP+ paper and its arcs.

use std::path::PathBuf;

use clap::Args;
use wslap::{write_simulation, Simulation, SimulationConfig};

/// Simulate the paper's A1689-like cluster (94 elliptical NFW galaxies plus a smooth halo with
/// 3x their mass, 2.58e14 Msun/h in a 3.3 arcmin field) and the arcs of 30 background sources.
///
/// Writes into DIR: truth/model.json (soft + galaxy-true), truth/soft.json,
/// truth/galaxies-true.json, truth/galaxies-model.json, the truth maps and critical curves at
/// z_s = 3 (FITS, JSON, DS9, kappa.png), arcs.json (every constraint pixel), arcs.png,
/// images.cat and members.cat (Lenstool) and simulation.json (summary, true source positions).
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Seed of every random draw.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Pixel of the ray-traced image in arcsec (0.2 to 1).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.5)]
    pixel: f64,
    /// Output folder (created if missing).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

pub fn run(args: &SimulateArgs) -> Result<(), String> {
    super::input::check_out_dir(&args.out)?;
    let config = SimulationConfig {
        seed: args.seed,
        pixel_arcsec: args.pixel,
        ..SimulationConfig::default()
    };
    let sim = Simulation::new(&config).map_err(|e| e.to_string())?;
    let s = sim.summary();
    println!(
        "simulated cluster (seed {}): soft {:.4e} + galaxies {:.4e} = {:.4e} Msun ({:.4e} Msun/h) \
         inside the {} arcsec field; Einstein radius at z_s = 3: {:.2} arcsec",
        s.seed,
        s.soft_mass_msun,
        s.galaxy_mass_msun,
        s.total_mass_msun,
        s.total_mass_msun_per_h,
        s.field_arcsec,
        s.theta_e_z3_arcsec
    );
    println!(
        "{} systems, {} images, {} constraint pixels of {} arcsec, {} systems with a radial arc \
         ({:.2} s)",
        s.n_systems,
        s.n_images,
        s.n_pixels,
        s.pixel_arcsec,
        s.n_radial_arc_systems,
        s.elapsed_ms / 1e3
    );
    let files = write_simulation(&sim, &args.out).map_err(|e| e.to_string())?;
    for f in files {
        println!("wrote {}", f.display());
    }
    Ok(())
}
