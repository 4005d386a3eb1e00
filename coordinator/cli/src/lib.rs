//! The `coordinator` command: the user's entry point. The binary's `main` calls
//! [`run_cli`]; each command is carried out by the crate that owns it: running a formation
//! by `runner` (the `formation-runner` package), the tools round a run (`render`, `bench`,
//! `bound`, `compare`) by `tools` (`formation-tools`), the rest here.

pub mod cli;
mod plan;
mod run_command;
mod simulate_command;
mod validate_command;

pub use runner::CliError;

/// Carry out one command line.
pub fn run_cli(cli: cli::Cli) -> Result<(), CliError> {
    match cli.command {
        cli::Command::Validate(args) => validate_command::execute(&args),
        cli::Command::Plan(args) => plan::execute(&args),
        cli::Command::Run(args) => run_command::execute(&args),
        cli::Command::Simulate(args) => simulate_command::execute(&args),
        cli::Command::Bound(args) => tools::bound::execute(&args),
        cli::Command::Compare(args) => tools::compare::execute(&args),
        cli::Command::Render(args) => tools::render::execute(&args),
        cli::Command::Bench(args) => tools::bench::execute(&args),
    }
}
