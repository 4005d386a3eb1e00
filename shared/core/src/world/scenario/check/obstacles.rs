//! The obstacles of a scenario checked: the disks listed and drawn from the seed, the
//! unknown ones, and the moving ones with their routes.

use super::{Checker, MAX_MOVING_WAYPOINTS, MAX_ROUTE_WAYPOINTS, num};
use crate::control::vocabulary::{AgentSpec, ControllerKind, ControllerSpec, MAX_OBSTACLES};
use crate::geometry::{Disk, Field, Polygon, distance_polyline_polyline};
use crate::world::moving_obstacle::MovingObstacle;
use crate::world::scenario::file::{MovingFile, ObstaclesFile};
use crate::world::scenario::random::{Crowded, random_obstacles};
use crate::world::scenario::{PathSpec, ScenarioError};

/// The most polygon corners a scenario may list, all polygons together (the validity
/// check of a polygon is quadratic in its corners).
pub(crate) const MAX_POLYGON_VERTICES: usize = 4096;

impl Checker<'_> {
    /// The `[[obstacles.unknown]]` tables; `known` obstacles are already placed.
    pub(super) fn unknown_obstacles(
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
    pub(super) fn moving_obstacles(
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

    pub(super) fn moving_obstacle(
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

    pub(super) fn obstacles(
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
}

impl Checker<'_> {
    /// The `[[obstacles.polygon]]` tables: every corner a pair inside the field, the
    /// polygon simple (it may be convex or not, given either way round).
    pub(super) fn polygons(
        &self,
        raw: &ObstaclesFile,
        field: &Field,
    ) -> Result<Vec<Polygon>, ScenarioError> {
        let vertices: usize = raw.polygon.iter().map(|p| p.vertices_m.len()).sum();
        if vertices > MAX_POLYGON_VERTICES {
            return Err(self.invalid(
                "obstacles.polygon",
                format!("{vertices} vertices in all exceed the limit of {MAX_POLYGON_VERTICES}"),
            ));
        }
        let mut out = Vec::with_capacity(raw.polygon.len());
        for (i, polygon) in raw.polygon.iter().enumerate() {
            let name = format!("obstacles.polygon[{i}].vertices_m");
            let mut corners = Vec::with_capacity(polygon.vertices_m.len());
            for (k, xy) in polygon.vertices_m.iter().enumerate() {
                let &[x_m, y_m] = xy.as_slice() else {
                    return Err(self.invalid(
                        format!("{name}[{k}]"),
                        format!("must be a pair [x_m, y_m], got {} value(s)", xy.len()),
                    ));
                };
                corners.push(self.point_in_field(
                    &format!("{name}[{k}]"),
                    "vertex ",
                    (&format!("{name}[{k}][0]"), x_m),
                    (&format!("{name}[{k}][1]"), y_m),
                    field,
                )?);
            }
            out.push(Polygon::new(corners).map_err(|e| self.invalid(&name, e.to_string()))?);
        }
        Ok(out)
    }

    /// The centre's start and goal keep their clearance from every polygon, and every
    /// agent's slot at the start stands clear of them; those from `first_piece` on are the
    /// map's, and named so.
    pub(super) fn clear_of_polygons(
        &self,
        polygons: &[Polygon],
        first_piece: usize,
        agents: &[AgentSpec],
        path: &PathSpec,
    ) -> Result<(), ScenarioError> {
        for (k, polygon) in polygons.iter().enumerate() {
            let what = match k < first_piece {
                true => format!("polygon {k}"),
                false => "the map's blocked cells".to_string(),
            };
            for (name, pose) in [("path.start", &path.start), ("path.goal", &path.goal)] {
                let p = pose.position();
                let distance_m = polygon.distance_m(&p);
                if distance_m < path.centre_clearance_m.max(f64::MIN_POSITIVE) {
                    return Err(self.invalid(
                        name,
                        format!(
                            "({}, {}) is {} m from {what}, within the centre clearance {} m",
                            num(p.x),
                            num(p.y),
                            num(distance_m),
                            num(path.centre_clearance_m)
                        ),
                    ));
                }
            }
            for (i, a) in agents.iter().enumerate() {
                let p = a.slot.ideal_position(&path.start);
                if polygon.distance_m(&p) < a.radius_m {
                    return Err(self.invalid(
                        format!("formation.slots[{i}]"),
                        format!(
                            "at the start pose the agent at ({:.3}, {:.3}) overlaps {what}",
                            p.x, p.y
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Polygons are planned round by the best-point controller only, for holonomic
    /// agents (in sequential or parallel turns, a static or a changing world); anything
    /// else with polygons is refused, naming what is missing.
    pub(super) fn polygons_supported(
        &self,
        polygons: &[Polygon],
        agents: &[AgentSpec],
        controller: &ControllerSpec,
    ) -> Result<(), ScenarioError> {
        if polygons.is_empty() {
            return Ok(());
        }
        let refuse = |name: &str, what: String| {
            Err(self.invalid(
                name,
                format!("{what} beside polygon obstacles is not supported yet"),
            ))
        };
        if controller.kind != ControllerKind::BestPoint {
            return refuse(
                "controller",
                format!("controller {}", controller.kind.name()),
            );
        }
        if let Some(i) = agents.iter().position(|a| a.kinematics.has_heading()) {
            return refuse(
                &format!("formation.slots[{i}]"),
                "an agent with a heading".to_string(),
            );
        }
        // Parallel groups are made of agents that cannot meet within the step: each plans
        // round the polygons alone, as in sequential turns.
        Ok(())
    }
}
