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
    /// Run a scenario with one agent process per agent and write the outputs.
    Run(RunArgs),
}

/// Arguments of `run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The scenario file (TOML); the embedded paper example when omitted.
    pub scenario: Option<PathBuf>,
    /// Output folder (default `runs/<name>-<UTC time>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The agent executable (default: `agent` beside this program).
    #[arg(long)]
    pub agent_bin: Option<PathBuf>,
    /// Turn deadline in milliseconds: an agent that has not answered by then is checked
    /// on and, if dead, frozen as an obstacle.
    #[arg(long, default_value_t = 250)]
    pub turn_deadline_ms: u64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
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
