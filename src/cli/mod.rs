//! Command-line parsing and the subcommands (native only).

mod images;
mod input;
mod lookup;
mod maps;
mod paper;
mod reconstruct;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// WSLAP+ free-form strong-lensing mass reconstruction.
///
/// Angles are arcsec in the tangent-plane frame of the reference point (+x West, +y North);
/// maps of kappa, shear and deflection are for D_ls/D_s = 1 (the HFF convention).
#[derive(Debug, Parser)]
#[command(name = "wslap", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Maps(maps::MapsArgs),
    Images(images::ImagesArgs),
    Lookup(lookup::LookupArgs),
    Reconstruct(reconstruct::ReconstructArgs),
    Config(reconstruct::ConfigArgs),
    Simulate(simulate::SimulateArgs),
    Paper(paper::PaperArgs),
}

/// Parses the arguments, runs the subcommand, prints any error with its context.
pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Maps(args) => maps::run(&args),
        Command::Images(args) => images::run(&args),
        Command::Lookup(args) => lookup::run(&args),
        Command::Reconstruct(args) => reconstruct::run(&args),
        Command::Config(_) => reconstruct::print_config(),
        Command::Simulate(args) => simulate::run(&args),
        Command::Paper(args) => paper::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}
