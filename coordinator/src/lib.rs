//! The coordinator: validates and plans a scenario, runs it over agent processes, and
//! writes the outputs. The binary's `main` calls [`run_cli`].

mod agents;
mod bench;
pub mod cli;
mod compare;
mod error;
mod ipc;
pub mod logging;
mod monitor;
pub mod output;
mod plan;
mod procfs;
pub mod render;
mod run_cmd;
pub mod runner;
mod stats;
pub mod validate;

pub use error::CliError;

/// Carry out one command line.
pub fn run_cli(cli: cli::Cli) -> Result<(), CliError> {
    match cli.command {
        cli::Command::Validate(args) => validate::run(&args),
        cli::Command::Plan(args) => plan::run(&args),
        cli::Command::Run(args) => run_cmd::run(&args),
        cli::Command::Compare(args) => compare::run(&args),
        cli::Command::Render(args) => render::run(&args),
        cli::Command::Bench(args) => bench::run(&args),
    }
}
