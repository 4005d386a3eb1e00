//! The scenario: field, obstacles, formation and path settings, read from TOML and
//! validated into a [`Scenario`] every other part can trust.
//!
//! Every error names the file and the field: `FILE: FIELD: REASON`. The format is
//! documented in `docs/scenario-format.md`.
//!
//! One concept per file:
//! - `model`: the validated [`Scenario`] and its [`PathSpec`];
//! - `error`: [`ScenarioError`], the one error of loading a scenario;
//! - `load`: reading a scenario, [`Scenario::load`] (a file, within its bound) and
//!   [`Scenario::parse`] (text), and the embedded paper scenario;
//! - `file`: the raw serde structures of the TOML format and the errors that name its
//!   line or field;
//! - `check`: validation of the raw structures into a [`Scenario`], and its limits;
//! - `map`: [`ScenarioMap`], the occupancy map the obstacles of `[map]` come from, its
//!   cells written inline in a resolved scenario, and the copy of it a run keeps;
//! - `random`: the obstacles drawn from the scenario's seed;
//! - `resolved`: [`Scenario::to_resolved_toml`], the scenario written back as a
//!   self-contained file.
//!
//! The agents, the controller and the capacities a scenario is made of are in
//! [`crate::control::vocabulary`].

mod check;
mod error;
mod file;
mod load;
mod map;
mod model;
mod random;
mod resolved;

pub use check::{
    Checks, MAX_ANGLE_DEG, MAX_FIELD_SIDE_M, MAX_MOVING_WAYPOINTS, MAX_ROUTE_WAYPOINTS, MAX_STEPS,
};
pub use error::ScenarioError;
pub use load::{MAX_SCENARIO_BYTES, PAPER_SCENARIO_NAME, PAPER_SCENARIO_TOML};
pub use map::{CellsTextError, ScenarioMap};
pub use model::{PathSpec, Scenario};
pub use resolved::{ResolveError, moving_obstacle_table};

/// A small valid scenario for the tests of this module: two agents, no obstacles.
#[cfg(test)]
const MINIMAL: &str = r#"
name = "t"
[field]
width_m = 20.0
height_m = 10.0
[formation]
slots = [ { r_m = 0.0, theta_deg = 0.0 }, { r_m = 1.0, theta_deg = 90.0 } ]
[path]
start = { x_m = 3.0, y_m = 5.0, heading_deg = 0.0 }
goal = { x_m = 17.0, y_m = 5.0, heading_deg = 0.0 }
turning_radius_m = 2.0
step_m = 0.5
centre_clearance_m = 0.3
"#;
