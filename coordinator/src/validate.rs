//! `coordinator validate SCENARIO`: parse, check, and make sure the centre has a path.

use shared::geometry::Pose;
use shared::scenario::{Scenario, ScenarioError};
use shared::simulate::plan_centre_path;

use crate::cli::ValidateArgs;
use crate::error::CliError;

/// Load `file` (or the embedded paper scenario) and check it completely, planning the
/// centre path (a scenario with no path to its goal is invalid). Returns the scenario and
/// its centre path, one pose per step.
pub fn load_and_plan(
    file: Option<&std::path::Path>,
) -> Result<(Scenario, Vec<Pose>), ScenarioError> {
    let (scenario, name) = match file {
        Some(path) => (Scenario::load(path)?, path.display().to_string()),
        None => (
            Scenario::paper(),
            shared::scenario::PAPER_SCENARIO_NAME.to_string(),
        ),
    };
    let path = plan_centre_path(&scenario).map_err(|e| ScenarioError::Invalid {
        file: name,
        field: "path".into(),
        reason: format!("no path for the formation centre from start to goal: {e}"),
    })?;
    Ok((scenario, path))
}

/// Run `validate`.
pub fn run(args: &ValidateArgs) -> Result<(), CliError> {
    let (scenario, path) = load_and_plan(Some(&args.scenario))?;
    eprintln!(
        "{}: valid: {} agents, {} obstacles, centre path of {} steps",
        args.scenario.display(),
        scenario.agents.len(),
        scenario.obstacles.len(),
        path.len().saturating_sub(1)
    );
    Ok(())
}
