//! `coordinator plan [SCENARIO] [--out FILE]`: the centre path as CSV.

use std::io::Write;

use anyhow::Context;

use crate::cli::PlanArgs;
use runner::CliError;
use runner::loaded::load_and_plan;
use runner::output;

/// Carry out `plan`.
pub fn execute(args: &PlanArgs) -> Result<(), CliError> {
    let loaded = load_and_plan(args.scenario.as_deref())?;
    let csv = output::path_csv(&loaded.centre_path).context("formatting the path")?;
    match &args.out {
        Some(file) => output::write_atomically(file, &csv)?,
        None => std::io::stdout()
            .write_all(&csv)
            .context("writing the path to standard output")?,
    }
    Ok(())
}
