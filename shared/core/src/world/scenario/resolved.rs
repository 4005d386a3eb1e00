//! The resolved form of a scenario: the scenario written back as a self-contained TOML
//! file that loads to the same scenario, bit for bit (the `scenario.toml` of a run's
//! output folder, and the mission file the agents read). It is the file structures the
//! parser reads ([`super::file`]), filled from the [`Scenario`] and serialised with
//! `toml`, so a key has one spelling for reading and writing.

use super::check::MAX_ANGLE_DEG;
use super::file::{
    CbfFile, DiskFile, FieldFile, FormationFile, MapFile, MovingFile, ObstaclesFile, OrcaFile,
    PathFile, PolygonFile, PoseFile, ScenarioFile, SlotFile, TurnsFile, default_agent_radius_m,
    default_obstacle_radius_m,
};
use super::{Scenario, ScenarioMap};
use crate::control::vocabulary::Kinematics;
use crate::geometry::{Disk, Point, Pose};
use crate::world::moving_obstacle::MovingObstacle;

/// Why a scenario has no resolved TOML form (only a scenario built by hand, not one this
/// module parsed, can meet these).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResolveError {
    /// A value the file format cannot hold so that it reads back to the same bits.
    #[error("{field}: {reason}")]
    NotRepresentable {
        /// Dotted path of the field in the file format.
        field: String,
        /// Why it cannot be written.
        reason: String,
    },
    /// The TOML serialiser refused the file structures.
    #[error("writing TOML: {0}")]
    Toml(#[from] toml::ser::Error),
    /// The JSON serialiser refused the file structures (its message).
    #[error("writing JSON: {0}")]
    Json(String),
}

impl Scenario {
    /// The scenario as a self-contained TOML file in the scenario format: every obstacle
    /// listed as an `[[obstacles.disk]]` with its radius (random ones as drawn, no
    /// `[obstacles.random]` left), every agent with its own radius, every default
    /// written out (the seed, the default radii, the controller, the `[cbf]` settings,
    /// `allow_reverse`, the turn mode). Numbers are written in a form that parses back to
    /// the same bits (`toml` writes Rust's shortest round-trip digits), and angles in the
    /// degrees that convert back to the same radians, so [`Scenario::parse`] of the text
    /// gives this scenario bit for bit. `source` (a file name) is named in the comment
    /// header.
    ///
    /// Fails only for a scenario that no file could give: a seed beyond TOML's integers,
    /// an angle no degree value converts to, or agents with different sensing radii.
    pub fn to_resolved_toml(&self, source: &str) -> Result<String, ResolveError> {
        let file = self.to_file()?;
        let body = toml::to_string(&file)?;
        // Debug escapes every control character: the name stays on the comment line.
        let name = comment_safe(&format!("{:?}", self.name));
        Ok(format!(
            "# Resolved form of scenario {name} as run, from {source}:\n\
             # every obstacle listed explicitly ({} obstacles, those drawn from the seed\n\
             # included; the seed is kept but no longer draws any), every default written\n\
             # out, the controller as run. It loads to the same scenario, bit for bit.\n\n{body}",
            self.obstacles.len(),
            source = comment_safe(source),
        ))
    }

    /// The scenario as a run's mission, the form its agents read at start-up: the
    /// structures of [`Scenario::to_resolved_toml`], as compact JSON. It reads back with
    /// [`Scenario::from_mission_json`] to this scenario, bit for bit (shortest round-trip
    /// digits), and parses several times faster than TOML: at 1000 agents every agent
    /// reading a 95 kB TOML file was the largest share of a run's start-up.
    ///
    /// Fails as [`Scenario::to_resolved_toml`] does.
    pub fn to_mission_json(&self) -> Result<String, ResolveError> {
        serde_json::to_string(&self.to_file()?).map_err(|e| ResolveError::Json(e.to_string()))
    }

    /// The file structures [`Scenario::parse`] reads, filled so that they check back into
    /// this scenario.
    fn to_file(&self) -> Result<ScenarioFile, ResolveError> {
        if i64::try_from(self.seed).is_err() {
            return Err(ResolveError::NotRepresentable {
                field: "seed".into(),
                reason: format!("{} is beyond TOML's integers", self.seed),
            });
        }
        let c = &self.controller.cbf;
        Ok(ScenarioFile {
            name: self.name.clone(),
            seed: self.seed,
            field: Some(FieldFile {
                width_m: self.field.width_m,
                height_m: self.field.height_m,
            }),
            // The cells themselves: the resolved form loads alone, in any process.
            map: self.map.as_ref().map(|m| MapFile {
                yaml: None,
                source: Some(m.source.clone()),
                unknown: Some(if m.unknown_free { "free" } else { "obstacle" }.to_string()),
                origin_m: Some(m.grid.origin_m.to_vec()),
                resolution_m: Some(m.grid.resolution_m),
                width_cells: Some(m.grid.width),
                height_cells: Some(m.grid.height),
                cells: Some(ScenarioMap::cells_text(&m.grid)),
            }),
            obstacles: self.obstacles_file(),
            formation: self.formation_file()?,
            path: PathFile {
                start: pose_file("path.start", &self.path.start)?,
                goal: pose_file("path.goal", &self.path.goal)?,
                turning_radius_m: self.path.turning_radius_m,
                step_m: self.path.step_m,
                centre_clearance_m: self.path.centre_clearance_m,
                allow_reverse: self.path.allow_reverse,
                max_lag_m: self.path.max_lag_m,
            },
            controller: self.controller.kind,
            cbf: Some(CbfFile {
                gamma_per_s: Some(c.gamma_per_s),
                dt_s: Some(c.dt_s),
                gain_per_s: Some(c.gain_per_s),
                max_speed_m_per_s: Some(c.max_speed_m_per_s),
                sensing_radius_m: Some(c.sensing_radius_m),
                lse_sharpness_per_m: Some(self.controller.lse_sharpness_per_m),
                substeps: Some(c.substeps),
                deadlock_escape: Some(c.deadlock_escape),
            }),
            orca: Some(OrcaFile {
                time_horizon_steps: Some(self.controller.orca.time_horizon_steps),
                max_neighbours: Some(self.controller.orca.max_neighbours),
            }),
            turns: TurnsFile {
                mode: self.turns,
                order: Some(self.turn_order),
            },
        })
    }

    fn obstacles_file(&self) -> ObstaclesFile {
        // The default radius is checked even when every obstacle has its own: write one
        // the checks accept (the first obstacle's, or at most the field's side).
        let side_m = self.field.width_m.max(self.field.height_m);
        let radius_m = self
            .obstacles
            .first()
            .map_or(default_obstacle_radius_m().min(side_m), |o| o.radius_m);
        ObstaclesFile {
            radius_m,
            positions_m: Vec::new(),
            disk: self.obstacles.iter().map(disk_file).collect(),
            random: None,
            moving: self.moving.iter().map(moving_file).collect(),
            unknown: self.unknown.iter().map(disk_file).collect(),
            // The map's pieces are not written: the map is.
            polygon: self.polygons[..self
                .map
                .as_ref()
                .map_or(self.polygons.len(), |m| m.first_piece)]
                .iter()
                .map(|p| PolygonFile {
                    vertices_m: p.vertices().iter().map(|v| vec![v.x, v.y]).collect(),
                })
                .collect(),
        }
    }

    fn formation_file(&self) -> Result<FormationFile, ResolveError> {
        // The file has one sensing radius for the formation.
        let sensing_radius_m = self.agents.first().and_then(|a| a.sensing_radius_m);
        if let Some(i) = self
            .agents
            .iter()
            .position(|a| a.sensing_radius_m != sensing_radius_m)
        {
            return Err(ResolveError::NotRepresentable {
                field: format!("formation.slots[{i}]"),
                reason: "the file format has one sensing radius for every agent".into(),
            });
        }
        let slots = self
            .agents
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let field = format!("formation.slots[{i}].theta_deg");
                Ok(SlotFile {
                    r_m: a.slot.r_m,
                    theta_deg: degrees_for(a.slot.theta_rad)
                        .ok_or_else(|| not_in_degrees(field, a.slot.theta_rad))?,
                    radius_m: Some(a.radius_m),
                    max_step_m: a.max_step_m,
                    kinematics: a
                        .kinematics
                        .has_heading()
                        .then(|| a.kinematics.name().to_string()),
                    max_turn_rad: match a.kinematics {
                        Kinematics::Unicycle { max_turn_rad, .. } => Some(max_turn_rad),
                        Kinematics::Holonomic | Kinematics::Car { .. } => None,
                    },
                    reverse: a.kinematics.has_heading().then(|| a.kinematics.reverse()),
                    turning_radius_m: match a.kinematics {
                        Kinematics::Car {
                            turning_radius_m, ..
                        } => Some(turning_radius_m),
                        _ => None,
                    },
                    heading_deg: match a.kinematics.has_heading() {
                        true => Some(degrees_for(a.heading_offset_rad).ok_or_else(|| {
                            not_in_degrees(
                                format!("formation.slots[{i}].heading_deg"),
                                a.heading_offset_rad,
                            )
                        })?),
                        false => None,
                    },
                })
            })
            .collect::<Result<_, ResolveError>>()?;
        Ok(FormationFile {
            agent_radius_m: self
                .agents
                .first()
                .map_or(default_agent_radius_m(), |a| a.radius_m),
            // Every slot carries its own top speed and kinematics.
            max_step_m: None,
            sensing_radius_m,
            kinematics: None,
            max_turn_rad: None,
            reverse: None,
            turning_radius_m: None,
            align_heading: self.agents.iter().any(|a| a.align_heading).then_some(true),
            // One look-ahead for the formation.
            horizon_steps: self.agents.first().map(|a| a.horizon_steps),
            slots,
        })
    }
}

fn disk_file(d: &Disk) -> DiskFile {
    DiskFile {
        x_m: d.centre.x,
        y_m: d.centre.y,
        radius_m: Some(d.radius_m),
    }
}

fn moving_file(m: &MovingObstacle) -> MovingFile {
    MovingFile {
        radius_m: Some(m.radius_m),
        waypoints_m: m
            .waypoints_m
            .iter()
            .map(|p: &Point| vec![p.x, p.y])
            .collect(),
        speed_m_per_step: m.speed_m_per_step,
        route: m.route,
    }
}

/// `pose` as the file writes it (`field` names it in the error when its heading has no
/// degree value).
fn pose_file(field: &str, pose: &Pose) -> Result<PoseFile, ResolveError> {
    let heading_deg = degrees_for(pose.heading_rad)
        .ok_or_else(|| not_in_degrees(format!("{field}.heading_deg"), pose.heading_rad))?;
    Ok(PoseFile {
        x_m: pose.x_m,
        y_m: pose.y_m,
        heading_deg,
    })
}

fn not_in_degrees(field: String, rad: f64) -> ResolveError {
    ResolveError::NotRepresentable {
        field,
        reason: format!(
            "no angle in degrees within -{MAX_ANGLE_DEG}..={MAX_ANGLE_DEG} converts to {rad:?} rad"
        ),
    }
}

/// `obstacle` as a `[[obstacles.moving]]` table of a scenario file, ending in a newline:
/// what [`Scenario::to_resolved_toml`] writes for it (the same file structure,
/// serialised alone), and what a program adding moving obstacles to a scenario text
/// appends.
///
/// # Panics
///
/// Never: the table holds numbers, arrays of numbers and a name, all of which TOML
/// writes.
///
/// ```
/// use shared::geometry::Point;
/// use shared::world::moving_obstacle::{MovingObstacle, Route};
/// use shared::world::scenario::moving_obstacle_table;
/// let patrol = MovingObstacle::new(
///     0.5,
///     vec![Point::new(15.0, 2.0), Point::new(15.0, 18.0)],
///     0.4,
///     Route::Loop,
/// );
/// assert_eq!(
///     moving_obstacle_table(&patrol),
///     "[[obstacles.moving]]\nradius_m = 0.5\nwaypoints_m = [[15.0, 2.0], [15.0, 18.0]]\n\
///      speed_m_per_step = 0.4\nroute = \"loop\"\n"
/// );
/// ```
pub fn moving_obstacle_table(obstacle: &MovingObstacle) -> String {
    #[derive(serde::Serialize)]
    struct Only {
        obstacles: OnlyMoving,
    }
    #[derive(serde::Serialize)]
    struct OnlyMoving {
        moving: [MovingFile; 1],
    }
    let table = Only {
        obstacles: OnlyMoving {
            moving: [moving_file(obstacle)],
        },
    };
    match toml::to_string(&table) {
        Ok(text) => text,
        Err(e) => panic!("a moving obstacle's table is always TOML: {e}"),
    }
}

/// `s` fit for a TOML comment (no control characters).
fn comment_safe(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect()
}

/// An angle in degrees within the format's range whose `to_radians()` is exactly `rad`
/// (bit for bit), preferring a short decimal (`120.0` rather than `119.99999999999999`):
/// the file's value when `rad` came from a file.
fn degrees_for(rad: f64) -> Option<f64> {
    if !rad.is_finite() {
        return None;
    }
    let exact = |d: f64| d.abs() <= MAX_ANGLE_DEG && d.to_radians().to_bits() == rad.to_bits();
    let d0 = rad.to_degrees();
    for digits in 0..=15 {
        let scale = 10f64.powi(digits);
        let d = (d0 * scale).round() / scale;
        if exact(d) {
            return Some(d);
        }
    }
    // `to_radians` is one rounded multiplication, so monotone: walk towards `rad`.
    let mut d = d0;
    for _ in 0..256 {
        if exact(d) {
            return Some(d);
        }
        d = if d.to_radians() < rad {
            d.next_up()
        } else {
            d.next_down()
        };
    }
    None
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    use super::*;

    /// `a` and `b` equal and bit for bit the same (Debug prints every float in its
    /// shortest round-trip form, so `-0.0` and `0.0` differ there).
    fn assert_same(a: &Scenario, b: &Scenario, what: &str) {
        assert_eq!(a, b, "{what}");
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "{what}: bit for bit");
    }

    /// The resolved text of `s`, checked to parse back to `s`.
    fn round_trip(s: &Scenario, what: &str) -> String {
        let text = s
            .to_resolved_toml(what)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let back = Scenario::parse(&text, "resolved.toml")
            .unwrap_or_else(|e| panic!("{what}: resolved text does not load: {e}\n{text}"));
        assert_same(&back, s, what);
        assert_eq!(back.obstacles.len(), s.obstacles.len(), "{what}");
        text
    }

    #[test]
    fn awkward_values_round_trip_bit_for_bit() {
        let text = r#"
name = "odd \"name\" \u00e9 # not a comment"
seed = 9223372036854775807
controller = "cbf"
[cbf]
gamma_per_s = 0.30000000000000004
dt_s = 3.0
gain_per_s = 1e-7
max_speed_m_per_s = 0.1
sensing_radius_m = 1.2345678901234567
lse_sharpness_per_m = 987.125
substeps = 7
deadlock_escape = false
[field]
width_m = 20.000000000000004
height_m = 10.0
[obstacles]
radius_m = 0.3
positions_m = [[10.0, 9.9999999999999982]]
disk = [ { x_m = 12.5, y_m = 0.1, radius_m = 0.7 } ]
[obstacles.random]
count = 5
keep_clear_m = 1.5
radius_m = 0.45
[formation]
agent_radius_m = 0.2
max_step_m = 0.15000000000000002
sensing_radius_m = 0.75
slots = [
  { r_m = 0.0, theta_deg = -0.0 },
  { r_m = 1.0000000000000002, theta_deg = 33.333333333333336, radius_m = 0.25, max_step_m = 0.1 },
  { r_m = 1.0, theta_deg = -179.99999999999997 },
  { r_m = 1.0, theta_deg = 360.0 },
  { r_m = 1.5, theta_deg = 0.1 },
]
[path]
start = { x_m = 3.0, y_m = 5.0, heading_deg = -0.0 }
goal = { x_m = 17.0, y_m = 5.0, heading_deg = -359.99999999999994 }
turning_radius_m = 2.0
step_m = 0.1
centre_clearance_m = 0.0
allow_reverse = true
[turns]
mode = "parallel"
"#;
        let s = Scenario::parse(text, "odd.toml").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.obstacles.len(), 7);
        let resolved = round_trip(&s, "odd\nfile # name.toml");
        assert!(resolved.contains("odd?file # name.toml"), "{resolved}");
        assert!(
            resolved.contains("theta_deg = 33.333333333333336"),
            "{resolved}"
        );
        assert!(resolved.contains("theta_deg = 360.0"), "{resolved}");
        assert!(resolved.contains("heading_deg = -0.0"), "{resolved}");
        // A field smaller than the default radii: the written defaults must still pass.
        let tiny = r#"
name = "tiny"
[field]
width_m = 0.8
height_m = 0.6
[obstacles]
radius_m = 0.05
[formation]
agent_radius_m = 0.1
slots = [ { r_m = 0.0, theta_deg = 0.0 } ]
[path]
start = { x_m = 0.2, y_m = 0.3, heading_deg = 0.0 }
goal = { x_m = 0.6, y_m = 0.3, heading_deg = 0.0 }
turning_radius_m = 0.1
step_m = 0.05
centre_clearance_m = 0.1
"#;
        let s = Scenario::parse(tiny, "tiny.toml").unwrap_or_else(|e| panic!("{e}"));
        round_trip(&s, "tiny.toml");
    }

    #[test]
    fn every_angle_in_range_has_exact_degrees() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        for _ in 0..20_000 {
            let d: f64 = rng.random_range(-MAX_ANGLE_DEG..=MAX_ANGLE_DEG);
            let rad = d.to_radians();
            let back = degrees_for(rad).unwrap_or_else(|| panic!("{d:?}"));
            assert_eq!(back.to_radians().to_bits(), rad.to_bits(), "{d:?}");
        }
        assert_eq!(degrees_for(f64::NAN), None);
        assert_eq!(degrees_for(100.0), None, "about 5730 degrees: out of range");
    }

    #[test]
    fn a_scenario_no_file_could_give_has_no_resolved_form() {
        let mut s = Scenario::paper();
        s.seed = u64::MAX;
        let e = s.to_resolved_toml("x").unwrap_err();
        assert!(e.to_string().starts_with("seed: "), "{e}");
        let mut s = Scenario::paper();
        s.agents[1].sensing_radius_m = Some(3.0);
        let e = s.to_resolved_toml("x").unwrap_err();
        assert!(e.to_string().starts_with("formation.slots[1]: "), "{e}");
        let mut s = Scenario::paper();
        s.agents[2].slot.theta_rad = f64::NAN;
        let e = s.to_resolved_toml("x").unwrap_err();
        assert!(
            e.to_string().starts_with("formation.slots[2].theta_deg: "),
            "{e}"
        );
    }
}
