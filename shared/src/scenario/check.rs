//! Validation: the raw file structures checked, field by field, into a [`Scenario`]
//! every other part can trust, and the limits the checks enforce.

use super::file::{
    CbfFile, DiskFile, FormationFile, MovingFile, ObstaclesFile, PoseFile, ScenarioFile,
};
use super::random::{Crowded, random_obstacles};
use super::{PathSpec, Scenario, ScenarioError};
use crate::formation::Slot;
use crate::geometry::{Disk, Field, Point, Pose, distance_polyline_polyline};
use crate::moving_obstacle::MovingObstacle;
use crate::vocabulary::{AgentSpec, MAX_AGENTS, MAX_OBSTACLES, PlannerKind, PlannerSpec, TurnMode};

/// Largest field side accepted, in metres: beyond this the numbers stop being a field.
pub const MAX_FIELD_SIDE_M: f64 = 10_000.0;
/// Bound on the number of centre steps: `step_m` may not cut the field's diagonal into
/// more than a quarter of this many steps. It also bounds how finely the centre path
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
        let width_m = self.positive("field.width_m", raw.field.width_m, MAX_FIELD_SIDE_M)?;
        let height_m = self.positive("field.height_m", raw.field.height_m, MAX_FIELD_SIDE_M)?;
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
        self.start_and_goal_clear(&all_static, &field, &path)?;
        self.formation_fits_at_start(&agents, &all_static, &field, &path)?;
        let moving =
            self.moving_obstacles(&raw.obstacles, &field, &path, &agents, all_static.len())?;
        let planner = self.planner(raw.planner, raw.cbf.as_ref(), &agents, side_m)?;
        let turns = raw.turns.mode;
        if turns == TurnMode::Parallel
            && let Some(i) = agents.iter().position(|a| a.max_step_m.is_none())
        {
            return Err(self.invalid(
                "turns.mode",
                format!(
                    "parallel turns need a top speed for every agent (formation.max_step_m), and agent {i} has none"
                ),
            ));
        }

        Ok(Scenario {
            name: raw.name,
            seed: raw.seed,
            field,
            obstacles,
            moving,
            unknown,
            agents,
            path,
            planner,
            turns,
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

    /// The `[[obstacles.unknown]]` tables; `known` obstacles are already placed.
    fn unknown_obstacles(
        &self,
        raw: &ObstaclesFile,
        field: &Field,
        known: usize,
    ) -> Result<Vec<Disk>, ScenarioError> {
        if known + raw.unknown.len() > MAX_OBSTACLES {
            return Err(self.invalid(
                "obstacles.unknown",
                format!(
                    "{} unknown obstacles and {known} others exceed the capacity of {MAX_OBSTACLES}",
                    raw.unknown.len()
                ),
            ));
        }
        raw.unknown
            .iter()
            .enumerate()
            .map(|(i, d)| self.disk(&format!("obstacles.unknown[{i}]"), d, raw.radius_m, field))
            .collect()
    }

    /// The `[[obstacles.moving]]` tables, checked against the agents' top speeds and
    /// sensing, the start and goal poses and the formation at the start; `statics`
    /// obstacles are already placed.
    fn moving_obstacles(
        &self,
        raw: &ObstaclesFile,
        field: &Field,
        path: &PathSpec,
        agents: &[AgentSpec],
        statics: usize,
    ) -> Result<Vec<MovingObstacle>, ScenarioError> {
        if statics + raw.moving.len() > MAX_OBSTACLES {
            return Err(self.invalid(
                "obstacles.moving",
                format!(
                    "{} moving obstacles and {statics} others exceed the capacity of {MAX_OBSTACLES}",
                    raw.moving.len()
                ),
            ));
        }
        let waypoints: usize = raw.moving.iter().map(|m| m.waypoints_m.len()).sum();
        if waypoints > MAX_MOVING_WAYPOINTS {
            return Err(self.invalid(
                "obstacles.moving",
                format!("{waypoints} waypoints in all exceed the limit of {MAX_MOVING_WAYPOINTS}"),
            ));
        }
        raw.moving
            .iter()
            .enumerate()
            .map(|(i, m)| self.moving_obstacle(i, m, raw.radius_m, field, path, agents))
            .collect()
    }

    fn moving_obstacle(
        &self,
        i: usize,
        m: &MovingFile,
        default_radius_m: f64,
        field: &Field,
        path: &PathSpec,
        agents: &[AgentSpec],
    ) -> Result<MovingObstacle, ScenarioError> {
        let name = format!("obstacles.moving[{i}]");
        let side_m = field.width_m.max(field.height_m);
        let radius_m = match m.radius_m {
            Some(r) => self.positive(&format!("{name}.radius_m"), r, side_m)?,
            None => default_radius_m,
        };
        if m.waypoints_m.len() < 2 || m.waypoints_m.len() > MAX_ROUTE_WAYPOINTS {
            return Err(self.invalid(
                format!("{name}.waypoints_m"),
                format!(
                    "a route needs 2 to {MAX_ROUTE_WAYPOINTS} waypoints, got {}",
                    m.waypoints_m.len()
                ),
            ));
        }
        let mut waypoints = Vec::with_capacity(m.waypoints_m.len());
        for (k, xy) in m.waypoints_m.iter().enumerate() {
            let wname = format!("{name}.waypoints_m[{k}]");
            let &[x_m, y_m] = xy.as_slice() else {
                return Err(self.invalid(
                    wname,
                    format!("must be a pair [x_m, y_m], got {} value(s)", xy.len()),
                ));
            };
            waypoints.push(self.point_in_field(
                &wname,
                "",
                (&format!("{wname}[0]"), x_m),
                (&format!("{wname}[1]"), y_m),
                field,
            )?);
        }
        let speed_name = format!("{name}.speed_m_per_step");
        let speed_m = self.positive(&speed_name, m.speed_m_per_step, side_m)?;
        // Agents must be able to outrun it, and to see it before it can reach them.
        for (a, spec) in agents.iter().enumerate() {
            if let Some(max_m) = spec.max_step_m
                && speed_m > max_m
            {
                return Err(self.invalid(
                    speed_name,
                    format!(
                        "{} m per step is faster than the top speed of agent {a} ({} m per step): agents must be able to outrun a moving obstacle",
                        num(speed_m),
                        num(max_m)
                    ),
                ));
            }
            if let (Some(sensing_m), Some(max_m)) = (spec.sensing_radius_m, spec.max_step_m)
                && sensing_m < max_m + spec.radius_m + speed_m
            {
                return Err(self.invalid(
                    "formation.sensing_radius_m",
                    format!(
                        "{} m does not cover the move of agent {a}, its radius and the step of moving obstacle {i} ({} + {} + {} m): it could end a turn where that obstacle reaches it unseen",
                        num(sensing_m),
                        num(max_m),
                        num(spec.radius_m),
                        num(speed_m)
                    ),
                ));
            }
        }
        let first = waypoints[0];
        for (pname, pose) in [("path.start", &path.start), ("path.goal", &path.goal)] {
            let gap_m = (pose.position() - first).norm() - radius_m;
            if gap_m < path.centre_clearance_m {
                return Err(self.invalid(
                    format!("{name}.waypoints_m[0]"),
                    format!(
                        "the obstacle starts {} m from {pname}, within the centre clearance {} m",
                        num(gap_m),
                        path.centre_clearance_m
                    ),
                ));
            }
        }
        let obstacle = MovingObstacle::new(radius_m, waypoints, speed_m, m.route);
        // Its first motion comes before any turn: it must not reach the formation.
        let first_motion = obstacle.sweep(1);
        for (a, spec) in agents.iter().enumerate() {
            let p = spec.slot.ideal_position(&path.start);
            if distance_polyline_polyline(&first_motion, &[p]) < radius_m + spec.radius_m {
                return Err(self.invalid(
                    format!("{name}.waypoints_m[0]"),
                    format!(
                        "the obstacle starts on agent {a} (at ({:.3}, {:.3}) at the start pose) or reaches it with its first motion, before the agent's first turn",
                        p.x, p.y
                    ),
                ));
            }
        }
        Ok(obstacle)
    }

    fn planner(
        &self,
        kind: PlannerKind,
        raw: Option<&CbfFile>,
        agents: &[AgentSpec],
        side_m: f64,
    ) -> Result<PlannerSpec, ScenarioError> {
        let mut spec = PlannerSpec {
            kind,
            ..PlannerSpec::default()
        };
        if let Some(c) = raw {
            let set = |name: &str, v: Option<f64>, slot: &mut f64| -> Result<(), ScenarioError> {
                if let Some(v) = v {
                    *slot = self.positive(&format!("cbf.{name}"), v, side_m.max(1e3))?;
                }
                Ok(())
            };
            set("gamma_per_s", c.gamma_per_s, &mut spec.cbf.gamma_per_s)?;
            set("dt_s", c.dt_s, &mut spec.cbf.dt_s)?;
            set("gain_per_s", c.gain_per_s, &mut spec.cbf.gain_per_s)?;
            set(
                "max_speed_m_per_s",
                c.max_speed_m_per_s,
                &mut spec.cbf.max_speed_m_per_s,
            )?;
            set(
                "sensing_radius_m",
                c.sensing_radius_m,
                &mut spec.cbf.sensing_radius_m,
            )?;
            set(
                "lse_sharpness_per_m",
                c.lse_sharpness_per_m,
                &mut spec.lse_sharpness_per_m,
            )?;
        }
        spec.check(agents)
            .map_err(|e| self.invalid("cbf", e.to_string()))?;
        Ok(spec)
    }

    fn obstacles(
        &self,
        raw: &ObstaclesFile,
        field: &Field,
        path: &PathSpec,
        seed: u64,
    ) -> Result<Vec<Disk>, ScenarioError> {
        let side_m = field.width_m.max(field.height_m);
        let default_radius_m = self.positive("obstacles.radius_m", raw.radius_m, side_m)?;
        let explicit = raw.positions_m.len() + raw.disk.len();
        if explicit > MAX_OBSTACLES {
            return Err(self.invalid(
                "obstacles",
                format!(
                    "{} explicit obstacles ({} in positions_m, {} in disk) exceed the capacity of {MAX_OBSTACLES}",
                    explicit,
                    raw.positions_m.len(),
                    raw.disk.len()
                ),
            ));
        }
        let mut obstacles = Vec::with_capacity(explicit);
        for (i, xy) in raw.positions_m.iter().enumerate() {
            let name = format!("obstacles.positions_m[{i}]");
            let &[x_m, y_m] = xy.as_slice() else {
                return Err(self.invalid(
                    name,
                    format!("must be a pair [x_m, y_m], got {} value(s)", xy.len()),
                ));
            };
            let c = self.point_in_field(
                &name,
                "obstacle centre ",
                (&format!("{name}[0]"), x_m),
                (&format!("{name}[1]"), y_m),
                field,
            )?;
            obstacles.push(Disk::new(c.x, c.y, default_radius_m));
        }
        for (i, d) in raw.disk.iter().enumerate() {
            obstacles.push(self.disk(
                &format!("obstacles.disk[{i}]"),
                d,
                default_radius_m,
                field,
            )?);
        }
        if let Some(random) = &raw.random {
            if random.count > MAX_OBSTACLES - explicit {
                return Err(self.invalid(
                    "obstacles.random.count",
                    format!(
                        "{} random obstacles and {explicit} explicit ones exceed the capacity of {MAX_OBSTACLES}",
                        random.count
                    ),
                ));
            }
            let radius_m = match random.radius_m {
                Some(r) => self.positive("obstacles.random.radius_m", r, side_m)?,
                None => default_radius_m,
            };
            let keep_clear_m =
                self.non_negative("obstacles.random.keep_clear_m", random.keep_clear_m, side_m)?;
            let drawn = random_obstacles(random.count, radius_m, keep_clear_m, field, path, seed)
                .map_err(|Crowded { placed }| {
                self.invalid(
                    "obstacles.random",
                    format!(
                        "could place only {placed} of {} obstacles clear of the start and goal",
                        random.count
                    ),
                )
            })?;
            obstacles.extend(drawn);
        }
        if obstacles.len() > MAX_OBSTACLES {
            return Err(self.invalid(
                "obstacles",
                format!(
                    "{} obstacles exceed the capacity of {MAX_OBSTACLES}",
                    obstacles.len()
                ),
            ));
        }
        Ok(obstacles)
    }

    fn agents(&self, raw: &FormationFile, field: &Field) -> Result<Vec<AgentSpec>, ScenarioError> {
        let hold_m = 0.5 * field.width_m.min(field.height_m);
        let default_radius_m =
            self.positive("formation.agent_radius_m", raw.agent_radius_m, hold_m)?;
        if raw.slots.is_empty() {
            return Err(self.invalid("formation.slots", "the formation has no agents"));
        }
        if raw.slots.len() > MAX_AGENTS {
            return Err(self.invalid(
                "formation.slots",
                format!(
                    "{} agents exceed the capacity of {MAX_AGENTS}",
                    raw.slots.len()
                ),
            ));
        }
        let diagonal_m = field.width_m.hypot(field.height_m);
        let default_max_step_m = raw
            .max_step_m
            .map(|v| self.positive("formation.max_step_m", v, diagonal_m))
            .transpose()?;
        let sensing_radius_m = raw
            .sensing_radius_m
            .map(|v| self.positive("formation.sensing_radius_m", v, diagonal_m))
            .transpose()?;
        let mut agents = Vec::with_capacity(raw.slots.len());
        for (i, s) in raw.slots.iter().enumerate() {
            let name = format!("formation.slots[{i}]");
            let r_m = self.non_negative(
                &format!("{name}.r_m"),
                s.r_m,
                field.width_m.hypot(field.height_m),
            )?;
            let theta_deg = self.angle_deg(&format!("{name}.theta_deg"), s.theta_deg)?;
            let radius_m = match s.radius_m {
                Some(r) => self.positive(&format!("{name}.radius_m"), r, hold_m)?,
                None => default_radius_m,
            };
            let max_step_m = match s.max_step_m {
                Some(v) => Some(self.positive(&format!("{name}.max_step_m"), v, diagonal_m)?),
                None => default_max_step_m,
            };
            // A move must never reach a body the agent cannot see: every point of a move
            // lies within max_step_m of the start, so an unseen disk (farther than the
            // sensing radius from the centre) stays clear iff the sensing radius covers
            // the move plus the agent's own radius.
            if let Some(sensing_m) = sensing_radius_m {
                let Some(step_m) = max_step_m else {
                    return Err(self.invalid(
                        "formation.sensing_radius_m",
                        format!(
                            "limited sensing needs a top speed (formation.max_step_m or {name}.max_step_m): without one a move could reach a body the agent cannot see"
                        ),
                    ));
                };
                if sensing_m < step_m + radius_m {
                    return Err(self.invalid(
                        "formation.sensing_radius_m",
                        format!(
                            "{} m does not cover the move of agent {i} plus its radius ({} + {} m): a move could reach a body it cannot see",
                            num(sensing_m),
                            num(step_m),
                            num(radius_m)
                        ),
                    ));
                }
            }
            agents.push(AgentSpec {
                slot: Slot::new(r_m, theta_deg.to_radians()),
                radius_m,
                max_step_m,
                sensing_radius_m,
            });
        }
        // The paper's Assumption 2: the nominal formation is itself collision-free.
        let origin = Pose::new(0.0, 0.0, 0.0);
        for i in 0..agents.len() {
            for j in 0..i {
                let d = (agents[i].slot.ideal_position(&origin)
                    - agents[j].slot.ideal_position(&origin))
                .norm();
                let need = agents[i].radius_m + agents[j].radius_m;
                if d < need {
                    return Err(self.invalid(
                        format!("formation.slots[{i}]"),
                        format!(
                            "slot is {d:.4} m from slot {j}, closer than their radii sum {need:.4} m (Assumption 2)"
                        ),
                    ));
                }
            }
        }
        Ok(agents)
    }

    fn start_and_goal_clear(
        &self,
        obstacles: &[Disk],
        field: &Field,
        path: &PathSpec,
    ) -> Result<(), ScenarioError> {
        for (name, pose) in [("path.start", &path.start), ("path.goal", &path.goal)] {
            let p = pose.position();
            if field.signed_inset_m(&p) < path.centre_clearance_m {
                return Err(self.invalid(
                    name,
                    format!(
                        "({}, {}) is closer to the field's edge than the centre clearance {} m",
                        p.x, p.y, path.centre_clearance_m
                    ),
                ));
            }
            if let Some((k, o)) = obstacles
                .iter()
                .enumerate()
                .find(|(_, o)| o.signed_distance_m(&p) < path.centre_clearance_m)
            {
                return Err(self.invalid(
                    name,
                    format!(
                        "({}, {}) is within the centre clearance {} m of obstacle {k} at ({}, {}) radius {} m",
                        p.x, p.y, path.centre_clearance_m, o.centre.x, o.centre.y, o.radius_m
                    ),
                ));
            }
        }
        Ok(())
    }

    fn formation_fits_at_start(
        &self,
        agents: &[AgentSpec],
        obstacles: &[Disk],
        field: &Field,
        path: &PathSpec,
    ) -> Result<(), ScenarioError> {
        for (i, a) in agents.iter().enumerate() {
            let name = format!("formation.slots[{i}]");
            let p = a.slot.ideal_position(&path.start);
            if field.signed_inset_m(&p) < a.radius_m {
                return Err(self.invalid(
                    name,
                    format!(
                        "at the start pose the agent at ({:.3}, {:.3}) does not fit inside the field",
                        p.x, p.y
                    ),
                ));
            }
            if let Some((k, o)) = obstacles
                .iter()
                .enumerate()
                .find(|(_, o)| o.signed_distance_m(&p) < a.radius_m)
            {
                return Err(self.invalid(
                    name,
                    format!(
                        "at the start pose the agent at ({:.3}, {:.3}) overlaps obstacle {k} at ({}, {})",
                        p.x, p.y, o.centre.x, o.centre.y
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::scenario::{MINIMAL, Scenario};

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
