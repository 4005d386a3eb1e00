//! The independent safety monitor: every published move is checked with parry against
//! the true obstacles and agents before it is accepted (the controllers' own geometry, with
//! its margins and arcs, is not consulted). Its check of a move against the agent's
//! kinematic model is in `kinematics.rs`.

use std::ops::ControlFlow;

use nalgebra::{Isometry2, Vector2};
use parry2d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry2d_f64::query;
use parry2d_f64::shape::{Ball, Polyline, Segment};
use parry2d_f64::utils::point_in_poly2d;
use shared::control::safety::SAFETY_TOLERANCE_M;
use shared::control::vocabulary::Body;
use shared::geometry::{Disk, DiskGrid, Field, Point, Polygon};

mod kinematics;

pub use kinematics::check_kinematics;

/// Why the monitor refused a move.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// No waypoint, or more than the protocol allows.
    #[error("{0} waypoints")]
    Length(usize),
    /// A waypoint is NaN or infinite.
    #[error("waypoint {0} is not finite")]
    NotFinite(usize),
    /// The move does not start where the agent stands.
    #[error("the move starts {0} m from the agent")]
    Teleport(f64),
    /// The move does not end at the announced best point (and is not under way).
    #[error("the move does not end at its best point")]
    WrongEnd,
    /// The move is longer than the agent's top speed.
    #[error("the move is {length_m} m long, beyond the top speed of {max_m} m per step")]
    TooLong {
        /// Length of the move.
        length_m: f64,
        /// Top speed, metres per step.
        max_m: f64,
    },
    /// An agent with a heading did not say where its move leaves it facing, or said
    /// something that is not an angle.
    #[error("the move gives no finite end heading for an agent with a heading")]
    NoHeading,
    /// A holonomic agent reported a heading.
    #[error("the move gives an end heading for a holonomic agent")]
    UnexpectedHeading,
    /// Driving and turning together take more than one step.
    #[error("the move's turning and driving take {share} of a step")]
    TooMuchTurning {
        /// The share of the step the move takes at the least.
        share: f64,
    },
    /// The move meets the move of another agent of the same group (parallel or
    /// simultaneous turns).
    #[error(
        "the move comes within {distance_m} m of agent {agent}'s move in the same group (radii sum {reach_m} m)"
    )]
    GroupMate {
        /// The other agent.
        agent: usize,
        /// Smallest distance between the two moves' polylines (in `simultaneous` turns,
        /// between the two agents at the same time).
        distance_m: f64,
        /// The two agents' radii summed: the least distance allowed.
        reach_m: f64,
    },
    /// The agent would leave the field.
    #[error("waypoint {0} leaves the field")]
    OutsideField(usize),
    /// The agent would overlap an obstacle.
    #[error("segment {segment} overlaps obstacle {obstacle}")]
    Obstacle {
        /// Segment index.
        segment: usize,
        /// Obstacle index.
        obstacle: usize,
    },
    /// The agent would overlap a polygon obstacle.
    #[error("segment {segment} overlaps polygon {polygon}")]
    Polygon {
        /// Segment index.
        segment: usize,
        /// Polygon index.
        polygon: usize,
    },
    /// The agent would overlap a moving obstacle where it stands during the turn.
    #[error("segment {segment} overlaps moving obstacle {obstacle}")]
    MovingObstacle {
        /// Segment index.
        segment: usize,
        /// Moving obstacle index, in scenario order.
        obstacle: usize,
    },
    /// A car's segment stands for an arc tighter than its turning radius.
    #[error("segment {segment} bends with radius {radius_m} m, tighter than the turning radius")]
    TooTight {
        /// Segment index.
        segment: usize,
        /// The radius of the arc tangent to the heading through the segment.
        radius_m: f64,
    },
    /// A car that may not reverse has a segment behind its heading.
    #[error("segment {0} is driven in reverse, which this agent may not")]
    Reversing(usize),
    /// A car's move ends facing other than its arcs leave it (it turned in place).
    #[error("the move ends {off_rad} rad off the heading its arcs leave it at")]
    EndHeading {
        /// The difference, radians.
        off_rad: f64,
    },
    /// The agent would overlap another agent.
    #[error("segment {segment} overlaps agent {agent}")]
    Agent {
        /// Segment index.
        segment: usize,
        /// The other agent's index.
        agent: usize,
    },
}

/// How much farther than the radii sum a body's centre may lie outside a segment's box
/// and still be handed to parry's query ([`SafetyMonitor::check`]): far more than any
/// rounding, far less than any spacing.
const PREFILTER_SLACK_M: f64 = 1e-3;

/// A published move as the monitor checks it ([`SafetyMonitor::check`]).
#[derive(Clone, Copy, Debug)]
pub struct MoveUnderCheck<'a> {
    /// The moving agent, an index into [`Standing::bodies`].
    pub agent: usize,
    /// Where the agent stands.
    pub from: &'a Point,
    /// The path it published, starting where it stands.
    pub waypoints: &'a [Point],
    /// The best point it published.
    pub best: &'a Point,
    /// The agent says it stops short of `best` (top speed): the path need not end there.
    pub under_way: bool,
    /// For a car, how far each segment's arc bulges from it ([`check_kinematics`]); each
    /// segment is checked with the agent's radius grown by it (empty: straight segments).
    pub chord_errors_m: &'a [f64],
}

/// The bodies a move is checked against, where they stand.
#[derive(Clone, Copy, Debug)]
pub struct Standing<'a> {
    /// Every agent's body, by index (the mover's own among them).
    pub bodies: &'a [Body],
    /// The agents that move at the same time (`simultaneous` turns): not checked here,
    /// but against the move in time when the group is settled (empty: none).
    pub passing: &'a [bool],
    /// A grid over exactly `bodies` (same order, same disks), so a move is checked
    /// against the bodies near it only; `None`: against each body in turn. Same result.
    pub grid: Option<&'a DiskGrid>,
}

/// Static obstacles in a parry BVH, the moving ones where they stand, and the field.
pub struct SafetyMonitor {
    field: Field,
    obstacles: Vec<Disk>,
    bvh: Bvh,
    /// The moving obstacles where they stand now ([`Self::move_obstacles`]).
    moving: Vec<Disk>,
    /// The polygon obstacles: corners, closed boundary as a parry polyline, box.
    polygons: Vec<(Vec<Point>, Polyline, Aabb)>,
}

impl SafetyMonitor {
    /// A monitor for `obstacles` (true radii) in `field`.
    pub fn new(field: Field, obstacles: &[Disk]) -> Self {
        let leaves: Vec<Aabb> = obstacles
            .iter()
            .map(|o| {
                let r = Vector2::new(o.radius_m, o.radius_m);
                Aabb::new(o.centre - r, o.centre + r)
            })
            .collect();
        Self {
            field,
            obstacles: obstacles.to_vec(),
            bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves),
            moving: Vec::new(),
            polygons: Vec::new(),
        }
    }

    /// The same monitor, also keeping every move clear of `polygons` (checked with
    /// parry's own segment-polyline distance and point-in-polygon test).
    pub fn with_polygons(mut self, polygons: &[Polygon]) -> Self {
        self.polygons = polygons
            .iter()
            .map(|p| {
                let corners = p.vertices().to_vec();
                let n = corners.len() as u32;
                let ring = (0..n).map(|i| [i, (i + 1) % n]).collect();
                let line = Polyline::new(corners.clone(), Some(ring));
                let aabb = Aabb::from_points(corners.iter().copied());
                (corners, line, aabb)
            })
            .collect();
        self
    }

    /// The moving obstacles drive along `sweeps` (one polyline each, from where they
    /// stood to where they stand now, radius `radius_m`) while every body of `bodies`
    /// stands still: `(obstacle, agent)` for each live agent (`alive`) a sweep comes
    /// within reach of, checked with parry's segment-ball query. From now on moves are
    /// checked against each obstacle at the end of its sweep.
    pub fn move_obstacles(
        &mut self,
        sweeps: &[(Vec<Point>, f64)],
        bodies: &[Body],
        alive: &[bool],
    ) -> Vec<(usize, usize)> {
        let identity = Isometry2::identity();
        let mut struck = Vec::new();
        self.moving.clear();
        for (m, (sweep, radius_m)) in sweeps.iter().enumerate() {
            let Some(&end) = sweep.last() else { continue };
            self.moving.push(Disk {
                centre: end,
                radius_m: *radius_m,
            });
            let pairs: Vec<Segment> = match sweep.as_slice() {
                [only] => vec![Segment::new(*only, *only)],
                _ => sweep.windows(2).map(|w| Segment::new(w[0], w[1])).collect(),
            };
            for (a, body) in bodies.iter().enumerate() {
                if !alive.get(a).copied().unwrap_or(false) {
                    continue;
                }
                let ball = Ball::new(body.radius_m + radius_m - SAFETY_TOLERANCE_M);
                let at = Isometry2::translation(body.position.x, body.position.y);
                if pairs
                    .iter()
                    .any(|seg| query::intersection_test(&identity, seg, &at, &ball).unwrap_or(true))
                {
                    struck.push((m, a));
                }
            }
        }
        struck
    }

    /// Check that agent `mv.agent` (standing at `mv.from`) may follow `mv.waypoints` to
    /// `mv.best` while the bodies of `standing` stand still (all agents, by index; those
    /// it marks passing move at the same time and are checked against this move in time
    /// when the group is settled). At most `max_waypoints` waypoints.
    pub fn check(
        &self,
        mv: &MoveUnderCheck<'_>,
        standing: &Standing<'_>,
        max_waypoints: usize,
    ) -> Result<(), Refusal> {
        let MoveUnderCheck {
            agent,
            from,
            waypoints,
            best,
            under_way,
            chord_errors_m,
        } = *mv;
        let bodies = standing.bodies;
        // A grid over other bodies than these would miss some: never used then.
        let grid = standing.grid.filter(|g| g.disks().len() == bodies.len());
        debug_assert!(standing.grid.is_none_or(|g| {
            g.disks()
                .iter()
                .zip(bodies)
                .all(|(d, b)| d.centre == b.position && d.radius_m == b.radius_m)
        }));
        if waypoints.is_empty() || waypoints.len() > max_waypoints {
            return Err(Refusal::Length(waypoints.len()));
        }
        if let Some(i) = waypoints
            .iter()
            .chain(std::iter::once(best))
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(Refusal::NotFinite(i));
        }
        let start_offset_m = (waypoints[0] - from).norm();
        if start_offset_m > SAFETY_TOLERANCE_M {
            return Err(Refusal::Teleport(start_offset_m));
        }
        if !under_way && waypoints.last() != Some(best) {
            return Err(Refusal::WrongEnd);
        }
        let radius_m = bodies[agent].radius_m;
        let error_m = |k: usize| chord_errors_m.get(k).copied().unwrap_or(0.0).max(0.0);
        let largest_error_m = chord_errors_m.iter().copied().fold(0.0, f64::max);
        let outer_m = radius_m + largest_error_m;
        let inner = Aabb::new(
            Point::new(outer_m, outer_m),
            Point::new(self.field.width_m - outer_m, self.field.height_m - outer_m),
        );
        let tol = Vector2::new(SAFETY_TOLERANCE_M, SAFETY_TOLERANCE_M);
        let inner = Aabb::new(inner.mins - tol, inner.maxs + tol);
        if let Some(i) = waypoints
            .iter()
            .position(|p| !inner.contains_local_point(p))
        {
            return Err(Refusal::OutsideField(i));
        }
        let identity = Isometry2::identity();
        // The bodies near a segment, when a grid indexes them; the margin is far above
        // any rounding, so the grid finds every body the prefilter below lets through.
        let mut near: Vec<usize> = Vec::new();
        let grown = Vector2::new(2.0 * PREFILTER_SLACK_M, 2.0 * PREFILTER_SLACK_M);
        let pairs: Vec<[Point; 2]> = if waypoints.len() == 1 {
            vec![[waypoints[0], waypoints[0]]]
        } else {
            waypoints.windows(2).map(|w| [w[0], w[1]]).collect()
        };
        for (segment, [a, b]) in pairs.iter().enumerate() {
            let shape = Segment::new(*a, *b);
            // A car's arc lies within its chord error of the chord.
            let radius_m = radius_m + error_m(segment);
            let hits = |centre: &Point, other_radius_m: f64| -> bool {
                // Overlap deeper than the tolerance <=> the segment meets the ball shrunk
                // by the tolerance.
                let ball = Ball::new(other_radius_m + radius_m - SAFETY_TOLERANCE_M);
                let at = Isometry2::translation(centre.x, centre.y);
                query::intersection_test(&identity, &shape, &at, &ball).unwrap_or(true)
            };
            let reach = Vector2::new(radius_m, radius_m);
            let sweep = Aabb::new(
                Point::new(a.x.min(b.x), a.y.min(b.y)) - reach,
                Point::new(a.x.max(b.x), a.y.max(b.y)) + reach,
            );
            for leaf in self.bvh.intersect_aabb(&sweep) {
                let o = &self.obstacles[leaf as usize];
                if hits(&o.centre, o.radius_m) {
                    return Err(Refusal::Obstacle {
                        segment,
                        obstacle: leaf as usize,
                    });
                }
            }
            for (polygon, (corners, line, aabb)) in self.polygons.iter().enumerate() {
                if !aabb.intersects(&sweep) {
                    continue;
                }
                let inside = point_in_poly2d(a, corners) || point_in_poly2d(b, corners);
                let distance_m = query::distance(&identity, &shape, &identity, line).unwrap_or(0.0);
                if inside || distance_m < radius_m - SAFETY_TOLERANCE_M {
                    return Err(Refusal::Polygon { segment, polygon });
                }
            }
            for (obstacle, o) in self.moving.iter().enumerate() {
                // Outside the segment's box grown by the radii sum: cannot meet it.
                let out = o.radius_m + radius_m + PREFILTER_SLACK_M;
                let c = &o.centre;
                if c.x < a.x.min(b.x) - out
                    || c.x > a.x.max(b.x) + out
                    || c.y < a.y.min(b.y) - out
                    || c.y > a.y.max(b.y) + out
                {
                    continue;
                }
                if hits(&o.centre, o.radius_m) {
                    // Struck already (it starts overlapping the obstacle): it may leave,
                    // never coming closer to the obstacle's centre than it started.
                    let start_m = nalgebra::distance(from, &o.centre);
                    let reach_m = o.radius_m + radius_m - SAFETY_TOLERANCE_M;
                    let at = Isometry2::translation(o.centre.x, o.centre.y);
                    let closest_m =
                        query::distance(&identity, &shape, &at, &Ball::new(0.0)).unwrap_or(0.0);
                    if !(start_m < reach_m && closest_m >= start_m - SAFETY_TOLERANCE_M) {
                        return Err(Refusal::MovingObstacle { segment, obstacle });
                    }
                }
            }
            let meets = |other: usize, body: &Body| -> Option<Refusal> {
                // Moving at the same time: checked against this move in time, later.
                if standing.passing.get(other).copied().unwrap_or(false) {
                    return None;
                }
                // A body whose centre lies farther than the radii sum outside the
                // segment's box cannot meet it: skipped without the parry query (with
                // [`PREFILTER_SLACK_M`] to spare, so no body the query would find is).
                let c = &body.position;
                let out = body.radius_m + radius_m + PREFILTER_SLACK_M;
                if c.x < a.x.min(b.x) - out
                    || c.x > a.x.max(b.x) + out
                    || c.y < a.y.min(b.y) - out
                    || c.y > a.y.max(b.y) + out
                {
                    return None;
                }
                (other != agent && hits(&body.position, body.radius_m)).then_some(Refusal::Agent {
                    segment,
                    agent: other,
                })
            };
            match grid {
                // Only the bodies the grid finds near the segment, in index order: the
                // same bodies the prefilter lets through, so the same first refusal.
                Some(grid) => {
                    near.clear();
                    let _ =
                        grid.visit_box(&(sweep.mins - grown), &(sweep.maxs + grown), |other, _| {
                            near.push(other);
                            ControlFlow::<()>::Continue(())
                        });
                    near.sort_unstable();
                    for &other in &near {
                        if let Some(refusal) = meets(other, &bodies[other]) {
                            return Err(refusal);
                        }
                    }
                }
                None => {
                    for (other, body) in bodies.iter().enumerate() {
                        if let Some(refusal) = meets(other, body) {
                            return Err(refusal);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// Check that the polyline `waypoints` is no longer than the top speed `max_step_m`
/// (to the safety tolerance); without a top speed any length passes.
pub fn check_length(waypoints: &[Point], max_step_m: Option<f64>) -> Result<(), Refusal> {
    let Some(max_m) = max_step_m else {
        return Ok(());
    };
    let length_m: f64 = waypoints
        .windows(2)
        .map(|w| nalgebra::distance(&w[0], &w[1]))
        .sum();
    if length_m > max_m + SAFETY_TOLERANCE_M {
        return Err(Refusal::TooLong { length_m, max_m });
    }
    Ok(())
}

/// The smallest distance between the polylines `a` and `b` (a single point is a
/// polyline), computed with parry's segment-segment query.
pub fn distance_between_moves_m(a: &[Point], b: &[Point]) -> f64 {
    let segments = |p: &[Point]| -> Vec<Segment> {
        match p {
            [] => Vec::new(),
            [only] => vec![Segment::new(*only, *only)],
            _ => p.windows(2).map(|w| Segment::new(w[0], w[1])).collect(),
        }
    };
    let identity = Isometry2::identity();
    let mut best = f64::INFINITY;
    for sa in segments(a) {
        for sb in segments(b) {
            let d = query::distance(&identity, &sa, &identity, &sb).unwrap_or(0.0);
            best = best.min(d);
        }
    }
    best
}

/// The smallest distance between two agents moving at once along the polylines `a` and
/// `b`, each at a constant speed over the same time (ORCA's own model, `simultaneous`
/// turns): the least distance from the origin to a piece of their relative motion
/// ([`shared::geometry::relative_motion`]), computed with parry's segment-point query.
pub fn distance_between_simultaneous_moves_m(a: &[Point], b: &[Point]) -> f64 {
    let identity = Isometry2::identity();
    let origin = Ball::new(0.0);
    shared::geometry::relative_motion(a, b)
        .into_iter()
        .map(|(from, to)| {
            let piece = Segment::new(Point::from(from), Point::from(to));
            query::distance(&identity, &piece, &identity, &origin).unwrap_or(0.0)
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests;
