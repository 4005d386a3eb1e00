//! The file side of a scenario: the raw serde structures of the format (units in the
//! names, unknown fields refused; read by [`Scenario::parse`](super::Scenario::parse) and
//! written by the resolved form, `super::resolved`), and the TOML errors that name the
//! line or the field.

use serde::{Deserialize, Serialize};

use super::ScenarioError;
use crate::control::vocabulary::{ControllerKind, TurnMode, TurnOrder};
use crate::geometry::Pose;
use crate::world::moving_obstacle::Route;

// ---------------------------------------------------------------------------------------
// The file format (serde side). Units are in the names; unknown fields are errors. A key
// left out when written (`skip_serializing_if`) is one the reader does not require.

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ScenarioFile {
    pub(super) name: String,
    #[serde(default)]
    pub(super) seed: u64,
    /// Absent with a `[map]`: the field is then the map's extent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) field: Option<FieldFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) map: Option<MapFile>,
    #[serde(default)]
    pub(super) obstacles: ObstaclesFile,
    pub(super) formation: FormationFile,
    pub(super) path: PathFile,
    /// `controller`; the older spelling `planner` is still read.
    #[serde(default, alias = "planner")]
    pub(super) controller: ControllerKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) cbf: Option<CbfFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) orca: Option<OrcaFile>,
    #[serde(default)]
    pub(super) turns: TurnsFile,
}

/// `[orca]`: ORCA's settings in its own model (RVO2's).
#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct OrcaFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) time_horizon_steps: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) max_neighbours: Option<usize>,
}

#[derive(Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct TurnsFile {
    #[serde(default)]
    pub(super) mode: TurnMode,
    /// `None`: [`TurnOrder::default_for`] the agents.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) order: Option<TurnOrder>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CbfFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) gamma_per_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) dt_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) gain_per_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) max_speed_m_per_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) sensing_radius_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) lse_sharpness_per_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) substeps: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) deadlock_escape: Option<bool>,
}

/// `[map]`: an occupancy map whose blocked cells are obstacles: a map_server YAML file
/// (`yaml`), or the cells themselves (`cells`, as a resolved scenario writes them).
#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MapFile {
    /// The map_server YAML file, relative to the scenario file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) yaml: Option<String>,
    /// With `cells`: where they were read from (a note, not read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) source: Option<String>,
    /// `"obstacle"` (the default) or `"free"`: what unknown cells are.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) unknown: Option<String>,
    /// `[x_m, y_m]`: where the map's lower-left corner lies (in place of the YAML's
    /// origin; required with `cells`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) origin_m: Option<Vec<f64>>,
    /// With `cells`: the side of a cell, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) resolution_m: Option<f64>,
    /// With `cells`: cells per row.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) width_cells: Option<usize>,
    /// With `cells`: rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) height_cells: Option<usize>,
    /// The cells, run-length encoded ([`ScenarioMap::cells_text`](super::ScenarioMap::cells_text)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) cells: Option<String>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FieldFile {
    pub(super) width_m: f64,
    pub(super) height_m: f64,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ObstaclesFile {
    #[serde(default = "default_obstacle_radius_m")]
    pub(super) radius_m: f64,
    /// `[x_m, y_m]` pairs; the length is checked by the [`Checker`] (serde would take the
    /// first two numbers of a longer array without a word).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(super) positions_m: Vec<Vec<f64>>,
    #[serde(default)]
    pub(super) disk: Vec<DiskFile>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) random: Option<RandomFile>,
    /// `[[obstacles.moving]]`: obstacles driven along routes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(super) moving: Vec<MovingFile>,
    /// `[[obstacles.unknown]]`: obstacles the centre's planner does not know at the start.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(super) unknown: Vec<DiskFile>,
    /// `[[obstacles.polygon]]`: simple polygons, convex or not, either orientation.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(super) polygon: Vec<PolygonFile>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PolygonFile {
    /// `[x_m, y_m]` pairs, checked by the [`Checker`] as `positions_m` is.
    pub(super) vertices_m: Vec<Vec<f64>>,
}

impl Default for ObstaclesFile {
    fn default() -> Self {
        Self {
            radius_m: default_obstacle_radius_m(),
            positions_m: Vec::new(),
            disk: Vec::new(),
            random: None,
            moving: Vec::new(),
            unknown: Vec::new(),
            polygon: Vec::new(),
        }
    }
}

/// The paper's Assumption 4: one obstacle radius for all, 1 m unless the file says.
pub(super) fn default_obstacle_radius_m() -> f64 {
    1.0
}

/// The paper's Assumption 3: one agent radius for all, 0.3 m unless the file says.
pub(super) fn default_agent_radius_m() -> f64 {
    0.3
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DiskFile {
    pub(super) x_m: f64,
    pub(super) y_m: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) radius_m: Option<f64>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MovingFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) radius_m: Option<f64>,
    /// `[x_m, y_m]` pairs, checked by the [`Checker`] as `positions_m` is.
    pub(super) waypoints_m: Vec<Vec<f64>>,
    pub(super) speed_m_per_step: f64,
    #[serde(default)]
    pub(super) route: Route,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RandomFile {
    pub(super) count: usize,
    #[serde(default)]
    pub(super) keep_clear_m: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) radius_m: Option<f64>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FormationFile {
    #[serde(default = "default_agent_radius_m")]
    pub(super) agent_radius_m: f64,
    /// Top speed of every agent, metres per step (absent: unbounded).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) max_step_m: Option<f64>,
    /// Sensing radius of every agent, metres (absent: every body is known).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) sensing_radius_m: Option<f64>,
    /// The agents' kinematic model by name (absent: holonomic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) kinematics: Option<String>,
    /// A unicycle's largest heading change per step, radians.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) max_turn_rad: Option<f64>,
    /// Whether an agent with a heading may drive backwards (absent: no).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) reverse: Option<bool>,
    /// A car's turning radius, metres (read to be refused with a clear reason).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) turning_radius_m: Option<f64>,
    /// Whether the agents end each move facing the centre's heading (absent: no).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) align_heading: Option<bool>,
    /// How many steps ahead an agent with a top speed looks along the centre's plan
    /// (absent: the default look-ahead).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) horizon_steps: Option<usize>,
    pub(super) slots: Vec<SlotFile>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SlotFile {
    pub(super) r_m: f64,
    pub(super) theta_deg: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) radius_m: Option<f64>,
    /// This slot's top speed, overriding the formation's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) max_step_m: Option<f64>,
    /// This slot's kinematic model, overriding the formation's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) kinematics: Option<String>,
    /// This slot's largest heading change per step, overriding the formation's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) max_turn_rad: Option<f64>,
    /// Whether this slot's agent may drive backwards, overriding the formation's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) reverse: Option<bool>,
    /// A car's turning radius (read to be refused with a clear reason).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) turning_radius_m: Option<f64>,
    /// The agent's heading relative to the centre's at the start, degrees (absent: 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) heading_deg: Option<f64>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PathFile {
    pub(super) start: PoseFile,
    pub(super) goal: PoseFile,
    pub(super) turning_radius_m: f64,
    pub(super) step_m: f64,
    /// Also read under its older spelling, `center_clearance_m`, so older files load.
    #[serde(alias = "center_clearance_m")]
    pub(super) centre_clearance_m: f64,
    #[serde(default)]
    pub(super) allow_reverse: bool,
    /// The centre holds while an agent lags farther than this behind its slot.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) max_lag_m: Option<f64>,
}

#[derive(Deserialize, Serialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub(super) struct PoseFile {
    pub(super) x_m: f64,
    pub(super) y_m: f64,
    pub(super) heading_deg: f64,
}

impl PoseFile {
    pub(super) fn pose(&self) -> Pose {
        Pose::new(self.x_m, self.y_m, self.heading_deg.to_radians())
    }
}

/// The raw file structures of a mission in JSON ([`Scenario::to_mission_json`]); `file`
/// names it in errors, with the path of the field at fault.
///
/// [`Scenario::to_mission_json`]: super::Scenario::to_mission_json
pub(super) fn parse_json_file(text: &str, file: &str) -> Result<ScenarioFile, ScenarioError> {
    // The plain parse first: tracking the path of every value costs a third of it, and
    // only an error needs the path (then the text is parsed again to find it).
    if let Ok(raw) = serde_json::from_str(text) {
        return Ok(raw);
    }
    let error = |field: String, e: serde_json::Error| ScenarioError::Parse {
        file: file.to_string(),
        field,
        reason: one_line(&e.to_string()),
    };
    let mut deserializer = serde_json::Deserializer::from_str(text);
    let raw = serde_path_to_error::deserialize(&mut deserializer).map_err(|e| {
        let path = e.path().to_string();
        let field = if path == "." || path.is_empty() {
            "(top level)".to_string()
        } else {
            path
        };
        error(field, e.into_inner())
    })?;
    deserializer
        .end()
        .map_err(|e| error("(after the mission)".into(), e))?;
    Ok(raw)
}

pub(super) fn parse_file(text: &str, file: &str) -> Result<ScenarioFile, ScenarioError> {
    let syntax = |e: toml::de::Error| ScenarioError::Parse {
        file: file.to_string(),
        field: e
            .span()
            .map(|s| line_column(text, s.start))
            .unwrap_or_else(|| "(syntax)".into()),
        reason: one_line(e.message()),
    };
    let deserializer = toml::Deserializer::parse(text).map_err(syntax)?;
    let raw = serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let top = path == "." || path.is_empty();
        // A missing field is reported at the table that lacks it: name the field itself.
        let missing = inner
            .message()
            .strip_prefix("missing field `")
            .and_then(|rest| rest.strip_suffix('`'))
            .map(str::to_owned);
        let field = match missing {
            Some(name) if top => name,
            Some(name) => format!("{path}.{name}"),
            None if top => inner
                .span()
                .map(|s| line_column(text, s.start))
                .unwrap_or_else(|| "(top level)".into()),
            None => path,
        };
        ScenarioError::Parse {
            file: file.to_string(),
            field,
            reason: one_line(inner.message()),
        }
    })?;
    let document: toml::Table = toml::from_str(text).map_err(syntax)?;
    if let Some(field) = table_given_as_array(&document) {
        return Err(ScenarioError::Parse {
            file: file.to_string(),
            field,
            reason:
                "invalid type: array, expected a table of named values (units are in the names)"
                    .into(),
        });
    }
    Ok(raw)
}

/// The first table of the format written as an array (`start = [3.0, 5.0, 0.0]`), if
/// any. Serde fills a struct from an array by position, silently dropping extra items;
/// the format wants every value named with its unit.
fn table_given_as_array(document: &toml::Table) -> Option<String> {
    const TABLES: [&str; 8] = [
        "field",
        "map",
        "obstacles",
        "obstacles.random",
        "formation",
        "path",
        "path.start",
        "path.goal",
    ];
    const ARRAYS_OF_TABLES: [&str; 5] = [
        "obstacles.disk",
        "obstacles.moving",
        "obstacles.unknown",
        "obstacles.polygon",
        "formation.slots",
    ];
    let lookup = |path: &str| {
        let mut parts = path.split('.');
        let mut value = document.get(parts.next()?)?;
        for part in parts {
            value = value.as_table()?.get(part)?;
        }
        Some(value)
    };
    if let Some(path) = TABLES
        .into_iter()
        .find(|path| lookup(path).is_some_and(toml::Value::is_array))
    {
        return Some(path.to_string());
    }
    ARRAYS_OF_TABLES.into_iter().find_map(|path| {
        let items = lookup(path)?.as_array()?;
        let i = items.iter().position(toml::Value::is_array)?;
        Some(format!("{path}[{i}]"))
    })
}

/// `line L, column C` of a byte offset (both from 1, the column in characters). An
/// offset past the end or inside a character is taken back to the character's start.
fn line_column(text: &str, offset: usize) -> String {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    format!("line {line}, column {column}")
}

fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use crate::geometry::Pose;
    use crate::world::scenario::{MINIMAL, Scenario};

    #[test]
    fn a_minimal_file_gets_the_papers_default_radii() {
        let s = Scenario::parse(MINIMAL, "min.toml").unwrap();
        assert_eq!(s.agents.len(), 2);
        assert!(s.agents.iter().all(|a| a.radius_m == 0.3));
        assert!(s.obstacles.is_empty());
    }

    #[test]
    fn the_embedded_paper_scenario_is_valid_and_has_the_papers_formation() {
        let s = Scenario::paper();
        let want = [
            (1.0, 0.0),
            (0.0, 0.0),
            (1.5, 45.0),
            (1.0, 120.0),
            (1.5, 180.0),
            (2.0, -120.0),
        ];
        assert_eq!(s.agents.len(), want.len());
        for (a, (r, th)) in s.agents.iter().zip(want) {
            assert_eq!(a.slot.r_m, r);
            assert!((a.slot.theta_rad - f64::to_radians(th)).abs() < 1e-15);
        }
        assert_eq!(s.path.start, Pose::new(2.0, 2.0, 0.0));
    }

    #[test]
    fn both_spellings_of_the_centre_clearance_load_the_same_scenario() {
        assert!(MINIMAL.contains("\ncentre_clearance_m = 0.3\n"));
        let old = MINIMAL.replace("centre_clearance_m", "center_clearance_m");
        let new = Scenario::parse(MINIMAL, "new.toml").unwrap_or_else(|e| panic!("{e}"));
        let old = Scenario::parse(&old, "old.toml").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(old, new);
        assert_eq!(new.path.centre_clearance_m, 0.3);
        // Written back, the old spelling becomes the new one.
        let resolved = old
            .to_resolved_toml("old.toml")
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            resolved.contains("\ncentre_clearance_m = 0.3\n"),
            "{resolved}"
        );
        assert!(!resolved.contains("center"), "{resolved}");
        // One key under two names: giving both is an error naming it.
        let both = MINIMAL.replace(
            "centre_clearance_m = 0.3",
            "centre_clearance_m = 0.3\ncenter_clearance_m = 0.3",
        );
        let e = Scenario::parse(&both, "both.toml").unwrap_err();
        assert!(e.to_string().starts_with("both.toml: "), "{e}");
        assert!(e.to_string().contains("centre_clearance_m"), "{e}");
        // Errors name the field by its new spelling, whichever the file used.
        let negative = MINIMAL.replace("centre_clearance_m = 0.3", "center_clearance_m = -1.0");
        let e = Scenario::parse(&negative, "neg.toml").unwrap_err();
        assert_eq!(e.field(), "path.centre_clearance_m", "{e}");
    }

    #[test]
    fn syntax_errors_point_at_the_line() {
        let e = Scenario::parse("name = \"x\"\n[field\n", "s.toml").unwrap_err();
        assert!(e.field().starts_with("line 2"), "{e}");
    }
}
