//! Loading a scenario: its file read, parsed and checked, or the embedded paper example.

use std::path::Path;

use super::check::{Checker, Checks};
use super::file::{parse_file, parse_json_file};
use super::{Scenario, ScenarioError};
use crate::input_file::{Links, read_input_text};

/// The paper's example (section III), embedded so `coordinator run` works with no file.
pub const PAPER_SCENARIO_TOML: &str = include_str!("../../../../../scenarios/paper.toml");
/// The name shown for the embedded paper scenario in messages.
pub const PAPER_SCENARIO_NAME: &str = "<embedded paper.toml>";
/// The largest scenario file read, in bytes: the most agents and obstacles a scenario may
/// hold, written out, take about a megabyte. Parsing TOML costs about 70 times its
/// length in memory when the file is one long list of numbers, so the bound is what
/// keeps a crafted file's cost in memory under 300 MB before its counts are checked.
pub const MAX_SCENARIO_BYTES: u64 = 4 << 20;

impl Scenario {
    /// Read and validate the scenario file at `path`.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        Self::parse(&Self::read(path)?, &path.display().to_string())
    }

    /// The text of the scenario file at `path`: a regular file of at most
    /// [`MAX_SCENARIO_BYTES`] of UTF-8 (anything else, a folder, a FIFO or a device
    /// included, is a [`ScenarioError::Read`], refused before its bytes are read).
    pub fn read(path: &Path) -> Result<String, ScenarioError> {
        read_input_text(path, MAX_SCENARIO_BYTES, Links::Follow).map_err(|e| ScenarioError::Read {
            file: path.display().to_string(),
            reason: e.to_string(),
        })
    }

    /// The paper's example, embedded in the library.
    pub fn paper() -> Self {
        match Self::parse(PAPER_SCENARIO_TOML, PAPER_SCENARIO_NAME) {
            Ok(s) => s,
            // The embedded file is checked by the test suite; reaching this is a build bug.
            Err(e) => panic!("embedded paper scenario is invalid: {e}"),
        }
    }

    /// Parse and validate scenario text; `file` names it in errors.
    ///
    /// ```
    /// use shared::world::scenario::Scenario;
    /// let text = r#"
    /// name = "two"
    /// [field]
    /// width_m = 20.0
    /// height_m = 10.0
    /// [formation]
    /// slots = [ { r_m = 0.0, theta_deg = 0.0 }, { r_m = 1.0, theta_deg = 90.0 } ]
    /// [path]
    /// start = { x_m = 3.0, y_m = 5.0, heading_deg = 0.0 }
    /// goal = { x_m = 17.0, y_m = 5.0, heading_deg = 0.0 }
    /// turning_radius_m = 2.0
    /// step_m = 0.5
    /// centre_clearance_m = 0.3
    /// "#;
    /// let s = Scenario::parse(text, "two.toml").unwrap();
    /// assert_eq!(s.agents.len(), 2);
    /// assert_eq!(s.agents[1].radius_m, 0.3, "the paper's default agent radius");
    /// assert_eq!(s.path.step_m, 0.5);
    /// // A value out of range is refused, naming the file and the field.
    /// let bad = text.replace("step_m = 0.5", "step_m = -1.0");
    /// let e = Scenario::parse(&bad, "two.toml").unwrap_err();
    /// assert_eq!(e.to_string(), "two.toml: path.step_m: must be positive, got -1");
    /// ```
    pub fn parse(text: &str, file: &str) -> Result<Self, ScenarioError> {
        let raw = parse_file(text, file)?;
        Checker {
            file,
            checks: Checks::All,
        }
        .check(raw)
    }

    /// The scenario of a run's mission, `text` as [`Scenario::to_mission_json`] wrote
    /// it; `file` names it in errors. `checks`: [`Checks::All`] for text from elsewhere
    /// (over a network, say); [`Checks::Values`] for the very text a coordinator
    /// validated (an agent whose mission file matches the digest its coordinator handed
    /// it): every value is still checked on its own, so nothing computed from the
    /// result can go undefined, but not the O(n^2) rules relating the parts.
    ///
    /// ```
    /// use shared::world::scenario::{Checks, Scenario};
    /// let paper = Scenario::paper();
    /// let json = paper.to_mission_json().unwrap();
    /// for checks in [Checks::All, Checks::Values] {
    ///     assert_eq!(Scenario::from_mission_json(&json, "mission.json", checks).unwrap(), paper);
    /// }
    /// // Each value is still checked.
    /// let bad = json.replace("\"step_m\":0.25", "\"step_m\":-0.25");
    /// let e = Scenario::from_mission_json(&bad, "mission.json", Checks::Values).unwrap_err();
    /// assert_eq!(e.to_string(), "mission.json: path.step_m: must be positive, got -0.25");
    /// ```
    pub fn from_mission_json(
        text: &str,
        file: &str,
        checks: Checks,
    ) -> Result<Self, ScenarioError> {
        let raw = parse_json_file(text, file)?;
        Checker { file, checks }.check(raw)
    }
}
