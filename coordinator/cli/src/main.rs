//! `coordinator`: the user's entry point. `main` only sets up logging, parses the
//! command line and calls [`coordinator::run_cli`]; everything else is in the library so
//! it is tested in-process.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    runner::logging::init();
    let cli = coordinator::cli::Cli::parse();
    match coordinator::run_cli(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
