//! Validation: the raw file structures checked, field by field, into a [`Scenario`]
//! every other part can trust, and the limits the checks enforce.
//!
//! Here the checker's primitives (finite, positive, an angle, a pose, a point in the
//! field, a disk) and the order of the checks ([`Checker::check`]); by part of the file:
//! `obstacles.rs`, `formation.rs`; whether the parts fit together at the start:
//! `feasibility.rs`.

use super::file::{DiskFile, PoseFile, ScenarioFile};
use super::{PathSpec, Scenario, ScenarioError};
use crate::control::vocabulary::{ControllerKind, TurnMode, TurnOrder};
use crate::geometry::{Disk, Field, Point, Pose};

mod feasibility;
mod formation;
mod map;
mod obstacles;

/// Largest field side accepted, in metres: beyond this the numbers stop being a field.
pub const MAX_FIELD_SIDE_M: f64 = 10_000.0;
/// Bound on the number of centre steps: `step_m` may not cut the field's diagonal into
/// more than a quarter of this many steps. It also bounds how finely the centre's
/// planner samples the path: every `turning_radius_m / 16` and `centre_clearance_m / 2`
/// at most, so neither may cut the diagonal into more than this many samples.
pub const MAX_STEPS: usize = 200_000;
/// Most waypoints of one moving obstacle's route.
pub const MAX_ROUTE_WAYPOINTS: usize = 256;
/// Most waypoints of all moving obstacles' routes together (so the mission file every
/// agent reads stays small).
pub const MAX_MOVING_WAYPOINTS: usize = 65_536;
/// Largest magnitude of an angle in degrees (headings and slot angles): beyond it an
/// angle is a typo, and far beyond it a double has no precision left for the angle.
pub const MAX_ANGLE_DEG: f64 = 360.0;

/// A number for a message: plain when short, in exponent form when huge or tiny (a
/// 1e308 m field should not print 309 digits).
fn num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() || (1e-4..1e9).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Validation of the raw file structures of the file `file` (named in every error).
pub(super) struct Checker<'a> {
    /// The file as given.
    pub(super) file: &'a str,
    /// How much to check: [`Checks::All`] for a file from a user, [`Checks::Values`]
    /// for one that was validated whole before.
    pub(super) checks: Checks,
}

/// How much of a scenario to check ([`Scenario::from_mission_json`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Checks {
    /// Every rule: each value, and that the parts fit together (slot pairs apart, the
    /// formation clear of the obstacles at the start, the start and goal clear).
    All,
    /// Each value alone (finite, in range, a known key): what keeps every computation
    /// on the scenario well defined. The rules that relate parts to each other are
    /// skipped; they cost O(n^2) for n slots and were checked before.
    Values,
}

impl Checker<'_> {
    fn invalid(&self, field: impl Into<String>, reason: impl Into<String>) -> ScenarioError {
        ScenarioError::Invalid {
            file: self.file.to_string(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    fn finite(&self, field: &str, v: f64) -> Result<f64, ScenarioError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(field, format!("must be a finite number, got {v}")))
        }
    }

    fn angle_deg(&self, field: &str, v: f64) -> Result<f64, ScenarioError> {
        self.finite(field, v)?;
        if v.abs() > MAX_ANGLE_DEG {
            return Err(self.invalid(
                field,
                format!(
                    "{} degrees is outside -{MAX_ANGLE_DEG}..={MAX_ANGLE_DEG}",
                    num(v)
                ),
            ));
        }
        Ok(v)
    }

    fn positive(&self, field: &str, v: f64, max: f64) -> Result<f64, ScenarioError> {
        self.finite(field, v)?;
        if v <= 0.0 {
            return Err(self.invalid(field, format!("must be positive, got {}", num(v))));
        }
        if v > max {
            return Err(self.invalid(
                field,
                format!("{} is larger than the limit {}", num(v), num(max)),
            ));
        }
        Ok(v)
    }

    fn non_negative(&self, field: &str, v: f64, max: f64) -> Result<f64, ScenarioError> {
        self.finite(field, v)?;
        if v < 0.0 {
            return Err(self.invalid(field, format!("must not be negative, got {}", num(v))));
        }
        if v > max {
            return Err(self.invalid(
                field,
                format!("{} is larger than the limit {}", num(v), num(max)),
            ));
        }
        Ok(v)
    }

    fn pose(&self, field: &str, p: &PoseFile, area: &Field) -> Result<Pose, ScenarioError> {
        self.finite(&format!("{field}.x_m"), p.x_m)?;
        self.finite(&format!("{field}.y_m"), p.y_m)?;
        self.angle_deg(&format!("{field}.heading_deg"), p.heading_deg)?;
        if !area.contains(&Point::new(p.x_m, p.y_m), 0.0) {
            return Err(self.invalid(
                field,
                format!(
                    "({}, {}) is outside the {} x {} m field",
                    num(p.x_m),
                    num(p.y_m),
                    area.width_m,
                    area.height_m
                ),
            ));
        }
        Ok(p.pose())
    }

    /// The scenario `raw` describes, or the first rule it breaks.
    pub(super) fn check(&self, raw: ScenarioFile) -> Result<Scenario, ScenarioError> {
        if raw.name.trim().is_empty() {
            return Err(self.invalid("name", "must not be empty"));
        }
        let map = raw
            .map
            .as_ref()
            .map(|m| self.map(m, raw.obstacles.polygon.len()))
            .transpose()?;
        let (width_m, height_m) = match (&raw.field, &map) {
            (Some(f), _) => (f.width_m, f.height_m),
            (None, Some(map)) => self.field_of_map(map)?,
            (None, None) => {
                return Err(self.invalid(
                    "field",
                    "missing: give [field] width_m and height_m, or a [map] whose extent is the field",
                ));
            }
        };
        let width_m = self.positive("field.width_m", width_m, MAX_FIELD_SIDE_M)?;
        let height_m = self.positive("field.height_m", height_m, MAX_FIELD_SIDE_M)?;
        let field = Field::new(width_m, height_m);
        let side_m = width_m.max(height_m);

        // Path settings first: random obstacles keep clear of the start and goal.
        let p = &raw.path;
        let start = self.pose("path.start", &p.start, &field)?;
        let goal = self.pose("path.goal", &p.goal, &field)?;
        let path = PathSpec {
            start,
            goal,
            turning_radius_m: self.positive("path.turning_radius_m", p.turning_radius_m, side_m)?,
            step_m: self.positive("path.step_m", p.step_m, side_m)?,
            centre_clearance_m: self.non_negative(
                "path.centre_clearance_m",
                p.centre_clearance_m,
                0.5 * width_m.min(height_m),
            )?,
            allow_reverse: p.allow_reverse,
            max_lag_m: p
                .max_lag_m
                .map(|v| self.positive("path.max_lag_m", v, side_m))
                .transpose()?,
        };
        let diagonal_m = width_m.hypot(height_m);
        if diagonal_m / path.step_m > MAX_STEPS as f64 / 4.0 {
            return Err(self.invalid(
                "path.step_m",
                format!(
                    "{} m is too small for a {width_m} x {height_m} m field (more than {MAX_STEPS} steps)",
                    num(path.step_m)
                ),
            ));
        }
        // The planner samples the centre path every turning_radius_m / 16 and
        // centre_clearance_m / 2 at most: bound the samples as the steps are bounded.
        let finest_m = diagonal_m / MAX_STEPS as f64;
        if path.turning_radius_m / 16.0 < finest_m {
            return Err(self.invalid(
                "path.turning_radius_m",
                format!(
                    "{} m is too small for a {width_m} x {height_m} m field (the planner would sample the path more than {MAX_STEPS} times across it; at least {} m)",
                    num(path.turning_radius_m),
                    num(16.0 * finest_m)
                ),
            ));
        }
        if path.centre_clearance_m > 0.0 && path.centre_clearance_m / 2.0 < finest_m {
            return Err(self.invalid(
                "path.centre_clearance_m",
                format!(
                    "{} m is too small for a {width_m} x {height_m} m field (the planner would sample the path more than {MAX_STEPS} times across it; 0 or at least {} m)",
                    num(path.centre_clearance_m),
                    num(2.0 * finest_m)
                ),
            ));
        }

        let obstacles = self.obstacles(&raw.obstacles, &field, &path, raw.seed)?;
        let agents = self.agents(&raw.formation, &field)?;
        let unknown = self.unknown_obstacles(&raw.obstacles, &field, obstacles.len())?;
        let mut all_static = obstacles.clone();
        all_static.extend_from_slice(&unknown);
        let mut polygons = self.polygons(&raw.obstacles, &field)?;
        if let Some(map) = &map {
            polygons.extend(self.map_pieces(map, &field)?);
        }
        if self.checks == Checks::All {
            self.start_and_goal_clear(&all_static, &field, &path)?;
            self.formation_fits_at_start(&agents, &all_static, &field, &path)?;
            let first_piece = map.as_ref().map_or(polygons.len(), |m| m.first_piece);
            self.clear_of_polygons(&polygons, first_piece, &agents, &path)?;
        }
        let moving =
            self.moving_obstacles(&raw.obstacles, &field, &path, &agents, all_static.len())?;
        if !moving.is_empty()
            && let Some(i) = agents.iter().position(|a| a.kinematics.has_heading())
        {
            return Err(self.invalid(
                "obstacles.moving",
                format!(
                    "moving obstacles beside agents with a heading (agent {i}) are not supported yet: the escape from a moving obstacle assumes a holonomic agent"
                ),
            ));
        }
        let controller = self.controller(
            raw.controller,
            raw.cbf.as_ref(),
            raw.orca.as_ref(),
            &agents,
            side_m,
        )?;
        self.polygons_supported(&polygons, &agents, &controller)?;
        let turns = raw.turns.mode;
        if turns != TurnMode::Sequential
            && let Some(i) = agents.iter().position(|a| a.max_step_m.is_none())
        {
            return Err(self.invalid(
                "turns.mode",
                format!(
                    "{} turns need a top speed for every agent (formation.max_step_m), and agent {i} has none",
                    turns.name()
                ),
            ));
        }
        if turns == TurnMode::Simultaneous && controller.kind != ControllerKind::Orca {
            return Err(self.invalid(
                "turns.mode",
                format!(
                    "simultaneous turns are ORCA's own model: they need controller = \"orca\", not {:?}",
                    controller.kind.name()
                ),
            ));
        }

        let turn_order = raw
            .turns
            .order
            .unwrap_or_else(|| TurnOrder::default_for(&agents));
        Ok(Scenario {
            name: raw.name,
            seed: raw.seed,
            field,
            obstacles,
            moving,
            unknown,
            polygons,
            map,
            agents,
            path,
            controller,
            turns,
            turn_order,
        })
    }

    /// The point `(x, y)` (each a field path and its value) when both are finite and it
    /// lies in `field` (edges included), else the error naming `name`, `what` the point
    /// is in the message (`"obstacle centre "`, or `""` for a waypoint).
    fn point_in_field(
        &self,
        name: &str,
        what: &str,
        x: (&str, f64),
        y: (&str, f64),
        field: &Field,
    ) -> Result<Point, ScenarioError> {
        let p = Point::new(self.finite(x.0, x.1)?, self.finite(y.0, y.1)?);
        if !field.contains(&p, 0.0) {
            return Err(self.invalid(
                name,
                format!(
                    "{what}({}, {}) is outside the {} x {} m field",
                    num(p.x),
                    num(p.y),
                    field.width_m,
                    field.height_m
                ),
            ));
        }
        Ok(p)
    }

    /// A disk table (`[[obstacles.disk]]` or `[[obstacles.unknown]]` item) named `name`.
    fn disk(
        &self,
        name: &str,
        d: &DiskFile,
        default_radius_m: f64,
        field: &Field,
    ) -> Result<Disk, ScenarioError> {
        let side_m = field.width_m.max(field.height_m);
        let radius_m = match d.radius_m {
            Some(r) => self.positive(&format!("{name}.radius_m"), r, side_m)?,
            None => default_radius_m,
        };
        let c = self.point_in_field(
            name,
            "obstacle centre ",
            (&format!("{name}.x_m"), d.x_m),
            (&format!("{name}.y_m"), d.y_m),
            field,
        )?;
        Ok(Disk::new(c.x, c.y, radius_m))
    }
}

#[cfg(test)]
mod tests {
    use crate::world::scenario::{MINIMAL, Scenario};

    #[test]
    fn errors_name_the_file_and_the_field() {
        let cases = [
            (
                MINIMAL.replace("width_m = 20.0", "width_m = -1.0"),
                "field.width_m",
            ),
            (
                MINIMAL.replace("width_m = 20.0", "width_m = nan"),
                "field.width_m",
            ),
            (
                MINIMAL.replace("step_m = 0.5", "step_m = inf"),
                "path.step_m",
            ),
            (MINIMAL.replace("[path]", "[path]\nspeed = 1"), "path.speed"),
            (
                MINIMAL.replace("r_m = 1.0", "r_m = 0.5"),
                "formation.slots[1]",
            ),
            (
                MINIMAL.replace("r_m = 1.0", "r_m = \"far\""),
                "formation.slots[1].r_m",
            ),
            (MINIMAL.replace("x_m = 3.0", "x_m = 30.0"), "path.start"),
        ];
        for (text, field) in cases {
            let e = Scenario::parse(&text, "bad.toml").unwrap_err();
            assert_eq!(e.field(), field, "{e}");
            let line = e.to_string();
            assert!(line.starts_with("bad.toml: "), "{line}");
            assert!(!line.contains('\n'), "one line: {line}");
        }
    }
}
