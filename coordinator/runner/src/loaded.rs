//! A scenario loaded as a run takes it: read, checked completely, its centre path
//! planned.

use std::path::Path;

use shared::geometry::Pose;
use shared::run::simulate::plan_centre_path;
use shared::world::scenario::{Scenario, ScenarioError};

/// A scenario checked completely, with its text and its centre path.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The validated scenario.
    pub scenario: Scenario,
    /// The file's text.
    pub text: String,
    /// The file as given (or the embedded paper scenario's name), for messages.
    pub source: String,
    /// The centre path, one pose per step.
    pub centre_path: Vec<Pose>,
}

/// Load `file` (or the embedded paper scenario) and check it completely, planning the
/// centre path (a scenario with no path to its goal is invalid).
pub fn load_and_plan(file: Option<&Path>) -> Result<Loaded, ScenarioError> {
    let (scenario, text, name) = match file {
        Some(path) => {
            let name = path.display().to_string();
            let text = Scenario::read(path)?;
            (Scenario::parse(&text, &name)?, text, name)
        }
        None => (
            Scenario::paper(),
            shared::world::scenario::PAPER_SCENARIO_TOML.to_string(),
            shared::world::scenario::PAPER_SCENARIO_NAME.to_string(),
        ),
    };
    let centre_path = plan_centre_path(&scenario).map_err(|e| ScenarioError::Invalid {
        file: name.clone(),
        field: "path".into(),
        reason: format!("no path for the formation centre from start to goal: {e}"),
    })?;
    Ok(Loaded {
        scenario,
        text,
        source: name,
        centre_path,
    })
}
