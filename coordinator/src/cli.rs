//! The command line (clap).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// Decentralized formation control with collision avoidance: each agent its own process,
/// talking over iceoryx2 shared memory.
#[derive(Debug, Parser)]
#[command(name = "coordinator", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check a scenario file (including that the centre has a path); plan nothing else.
    Validate(ValidateArgs),
    /// Plan the formation centre's path with Hybrid A* and write it as CSV.
    Plan(PlanArgs),
}

/// Arguments of `validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The scenario file (TOML).
    pub scenario: PathBuf,
}

/// Arguments of `plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The scenario file (TOML); the embedded paper example when omitted.
    pub scenario: Option<PathBuf>,
    /// Where to write the CSV (`step,x_m,y_m,heading_rad`); standard output when omitted.
    #[arg(long)]
    pub out: Option<PathBuf>,
}
