//! The coordinator: validates and plans a scenario, runs it over agent processes, and
//! writes the outputs. The binary's `main` calls [`run_cli`].

mod agent_uids;
mod agents;
mod bench;
mod bound;
pub mod cli;
mod compare;
mod dead_nodes;
mod error;
mod force_quit;
mod ipc;
pub mod logging;
mod monitor;
pub mod netns;
pub mod network;
pub mod output;
mod plan;
mod procfs;
pub mod render;
mod resume;
mod run_command;
pub mod run_log;
mod simulate_command;
pub mod stale_runs;
mod stats;
pub mod turns;
pub mod validate;

pub use error::CliError;

/// Carry out one command line.
pub fn run_cli(cli: cli::Cli) -> Result<(), CliError> {
    match cli.command {
        cli::Command::Validate(args) => validate::execute(&args),
        cli::Command::Plan(args) => plan::execute(&args),
        cli::Command::Run(args) => run_command::execute(&args),
        cli::Command::Simulate(args) => simulate_command::execute(&args),
        cli::Command::Bound(args) => bound::execute(&args),
        cli::Command::Compare(args) => compare::execute(&args),
        cli::Command::Render(args) => render::execute(&args),
        cli::Command::Bench(args) => bench::execute(&args),
    }
}
