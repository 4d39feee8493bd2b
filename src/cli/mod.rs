//! Command-line parsing and the subcommands.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// WSLAP+ free-form strong-lensing mass reconstruction.
#[derive(Debug, Parser)]
#[command(name = "wslap", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {}

pub fn run() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        None => {
            use clap::CommandFactory;
            let _ = Cli::command().print_help();
            ExitCode::SUCCESS
        }
    }
}
