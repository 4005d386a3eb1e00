//! `agent`: one formation agent as its own OS process. `main` only sets up logging,
//! parses the command line and calls [`agent::run`].

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    agent::init_logging();
    let args = agent::Args::parse();
    match agent::run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!("agent {}: {e:#}", args.agent);
            ExitCode::FAILURE
        }
    }
}
