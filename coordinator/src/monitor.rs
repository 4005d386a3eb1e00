//! The independent safety monitor: every published move is checked with parry against
//! the true obstacles and agents before it is accepted (the controllers' own geometry, with
//! its margins and arcs, is not consulted).

use nalgebra::{Isometry2, Vector2};
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry2d_f64::query;
use parry2d_f64::shape::{Ball, Segment};
use shared::geometry::{Disk, Field, Point};
use shared::safety::SAFETY_TOLERANCE_M;
use shared::vocabulary::{Body, Kinematics};

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
    /// The move meets the move of another agent of the same parallel group.
    #[error("the move comes within {distance_m} m of agent {agent}'s move in the same group")]
    GroupMate {
        /// The other agent.
        agent: usize,
        /// Smallest distance between the two moves' polylines.
        distance_m: f64,
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

/// How far past a whole step a unicycle's turning and driving may reach: rounding only.
const STEP_SHARE_TOLERANCE: f64 = 1e-9;

/// How much more a car's arc may turn along one segment than its turning radius allows,
/// radians: the rounding of a short segment's direction only.
const TURN_TOLERANCE_RAD: f64 = 1e-7;

/// How far a car's end heading may differ from the one its arcs give, radians.
const END_HEADING_TOLERANCE_RAD: f64 = 1e-6;

/// Segments shorter than this have no direction: driven without turning.
const DEGENERATE_SEGMENT_M: f64 = 1e-12;

/// How much farther than the radii sum a body's centre may lie outside a segment's box
/// and still be handed to parry's query ([`SafetyMonitor::check`]): far more than any
/// rounding, far less than any spacing.
const PREFILTER_SLACK_M: f64 = 1e-3;

/// Static obstacles in a parry BVH, the moving ones where they stand, and the field.
pub struct SafetyMonitor {
    field: Field,
    obstacles: Vec<Disk>,
    bvh: Bvh,
    /// The moving obstacles where they stand now ([`Self::move_obstacles`]).
    moving: Vec<Disk>,
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
        }
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

    /// Check that agent `agent` (radius `radius_m`, standing at `from`) may follow
    /// `waypoints` to `best` while every body of `bodies` (all agents, by index) stands
    /// still. `under_way`: the agent says it stops short of `best` (top speed), so the
    /// move need not end there. `chord_errors_m`: for a car, how far each segment's arc
    /// bulges from it ([`check_kinematics`]); each segment is checked with the agent's
    /// radius grown by it (empty: straight segments).
    #[allow(clippy::too_many_arguments)]
    pub fn check(
        &self,
        agent: usize,
        from: &Point,
        waypoints: &[Point],
        best: &Point,
        under_way: bool,
        bodies: &[Body],
        chord_errors_m: &[f64],
        max_waypoints: usize,
    ) -> Result<(), Refusal> {
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
            for (other, body) in bodies.iter().enumerate() {
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
                    continue;
                }
                if other != agent && hits(&body.position, body.radius_m) {
                    return Err(Refusal::Agent {
                        segment,
                        agent: other,
                    });
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

/// Check a move against the agent's kinematics, on its own arithmetic (angles from dot
/// and cross products, not the controllers' code): a holonomic agent reports no heading;
/// a unicycle facing `start_heading_rad` reports a finite `end_heading_rad`, and turning
/// in place at the vertices (the least turning over driving each segment forwards or,
/// with `reverse`, backwards) plus driving fits one step: turning / `max_turn_rad` +
/// length / `max_step_m` at most 1. A car's segments each stand for the arc that leaves
/// tangent to the heading (forwards, or backwards when the segment lies behind it):
/// each arc's radius is at least `turning_radius_m`, none is reversed unless `reverse`,
/// their length is within the top speed, and the end heading is the one they leave it
/// at. On success, each segment's chord error (none but for a car), for [`SafetyMonitor::check`].
pub fn check_kinematics(
    kinematics: Kinematics,
    start_heading_rad: Option<f64>,
    waypoints: &[Point],
    end_heading_rad: Option<f64>,
    max_step_m: Option<f64>,
) -> Result<Vec<f64>, Refusal> {
    let (max_turn_rad, reverse) = match kinematics {
        Kinematics::Unicycle {
            max_turn_rad,
            reverse,
        } => (max_turn_rad, reverse),
        Kinematics::Car {
            turning_radius_m,
            reverse,
        } => {
            return check_car(
                turning_radius_m,
                reverse,
                start_heading_rad,
                waypoints,
                end_heading_rad,
                max_step_m,
            );
        }
        Kinematics::Holonomic => {
            return match end_heading_rad {
                None => Ok(Vec::new()),
                Some(_) => Err(Refusal::UnexpectedHeading),
            };
        }
    };
    let (Some(start), Some(end)) = (start_heading_rad, end_heading_rad.filter(|h| h.is_finite()))
    else {
        return Err(Refusal::NoHeading);
    };
    let unit = |rad: f64| Vector2::new(rad.cos(), rad.sin());
    let angle = |a: &Vector2<f64>, b: &Vector2<f64>| (a.x * b.y - a.y * b.x).atan2(a.dot(b)).abs();
    // The least turning so far ending facing forwards [0] or backwards [1] along the
    // last segment, and the way it faces then.
    let mut cost = [0.0, f64::INFINITY];
    let mut facing = [unit(start), unit(start)];
    let mut length_m = 0.0;
    for w in waypoints.windows(2) {
        let d = w[1] - w[0];
        let norm = d.norm();
        length_m += norm;
        if norm <= DEGENERATE_SEGMENT_M {
            continue;
        }
        let ahead = d / norm;
        let options = [ahead, -ahead];
        let mut next = [f64::INFINITY; 2];
        for (o, way) in options.iter().enumerate().take(if reverse { 2 } else { 1 }) {
            for p in 0..2 {
                next[o] = next[o].min(cost[p] + angle(&facing[p], way));
            }
        }
        cost = next;
        facing = options;
    }
    let turning_rad = (0..2)
        .map(|p| cost[p] + angle(&facing[p], &unit(end)))
        .fold(f64::INFINITY, f64::min);
    let share = turning_rad / max_turn_rad + length_m / max_step_m.unwrap_or(f64::INFINITY);
    if share.is_nan() || share > 1.0 + STEP_SHARE_TOLERANCE {
        return Err(Refusal::TooMuchTurning { share });
    }
    Ok(Vec::new())
}

/// [`check_kinematics`] for a car: read each segment back as the arc tangent to the
/// heading through it, and check it.
fn check_car(
    turning_radius_m: f64,
    reverse: bool,
    start_heading_rad: Option<f64>,
    waypoints: &[Point],
    end_heading_rad: Option<f64>,
    max_step_m: Option<f64>,
) -> Result<Vec<f64>, Refusal> {
    let (Some(start), Some(end)) = (start_heading_rad, end_heading_rad.filter(|h| h.is_finite()))
    else {
        return Err(Refusal::NoHeading);
    };
    let mut heading = Vector2::new(start.cos(), start.sin());
    let mut length_m = 0.0;
    let mut errors_m = Vec::with_capacity(waypoints.len());
    for (segment, w) in waypoints.windows(2).enumerate() {
        let d = w[1] - w[0];
        let chord_m = d.norm();
        if chord_m <= DEGENERATE_SEGMENT_M {
            length_m += chord_m;
            errors_m.push(0.0);
            continue;
        }
        let backwards = heading.dot(&d) < 0.0;
        if backwards && !reverse {
            return Err(Refusal::Reversing(segment));
        }
        let way = if backwards { -heading } else { heading };
        // The chord's angle to the way driven: the arc turns by twice it.
        let angle_rad = (way.x * d.y - way.y * d.x).atan2(way.dot(&d));
        let sin = angle_rad.abs().sin();
        let most_rad = (0.5 * chord_m / turning_radius_m).min(1.0).asin();
        if angle_rad.abs() > most_rad + TURN_TOLERANCE_RAD {
            return Err(Refusal::TooTight {
                segment,
                radius_m: chord_m / (2.0 * sin),
            });
        }
        length_m += if sin > 0.0 {
            chord_m * angle_rad.abs() / sin
        } else {
            chord_m
        };
        errors_m.push(0.5 * chord_m * (0.5 * angle_rad.abs()).tan());
        heading = nalgebra::Rotation2::new(2.0 * angle_rad) * heading;
    }
    let want = Vector2::new(end.cos(), end.sin());
    let off_rad = (heading.x * want.y - heading.y * want.x)
        .atan2(heading.dot(&want))
        .abs();
    if off_rad.is_nan() || off_rad > END_HEADING_TOLERANCE_RAD {
        return Err(Refusal::EndHeading { off_rad });
    }
    if let Some(max_m) = max_step_m
        && (length_m.is_nan() || length_m > max_m + SAFETY_TOLERANCE_M)
    {
        return Err(Refusal::TooLong { length_m, max_m });
    }
    Ok(errors_m)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn bodies() -> Vec<Body> {
        vec![
            Body {
                position: Point::new(1.0, 5.0),
                radius_m: 0.3,
            },
            Body {
                position: Point::new(5.0, 7.5),
                radius_m: 0.3,
            },
        ]
    }

    const UNICYCLE: Kinematics = Kinematics::Unicycle {
        max_turn_rad: 2.0,
        reverse: false,
    };

    #[test]
    fn headings_are_required_of_unicycles_and_refused_of_holonomic_agents() {
        let path = [Point::new(0.0, 0.0), Point::new(0.5, 0.0)];
        let holonomic = Kinematics::Holonomic;
        assert_eq!(
            check_kinematics(holonomic, None, &path, None, None),
            Ok(Vec::new())
        );
        assert_eq!(
            check_kinematics(holonomic, None, &path, Some(0.0), None),
            Err(Refusal::UnexpectedHeading)
        );
        for end in [None, Some(f64::NAN), Some(f64::INFINITY)] {
            assert_eq!(
                check_kinematics(UNICYCLE, Some(0.0), &path, end, Some(1.0)),
                Err(Refusal::NoHeading)
            );
        }
        assert_eq!(
            check_kinematics(UNICYCLE, Some(0.0), &path, Some(0.0), Some(1.0)),
            Ok(Vec::new())
        );
    }

    #[test]
    fn turning_and_driving_share_the_step() {
        // Half a step's drive, then a quarter turn: 0.5 + (pi/2)/2 = 1.285 of a step.
        let path = [Point::new(0.0, 0.0), Point::new(0.5, 0.0)];
        let quarter = std::f64::consts::FRAC_PI_2;
        assert!(matches!(
            check_kinematics(UNICYCLE, Some(0.0), &path, Some(quarter), Some(1.0)),
            Err(Refusal::TooMuchTurning { share }) if (share - (0.5 + quarter / 2.0)).abs() < 1e-12
        ));
        // Half the turn fits with the drive: 0.5 + 1.0 / 2 = 1.
        assert_eq!(
            check_kinematics(UNICYCLE, Some(0.0), &path, Some(1.0), Some(1.0)),
            Ok(Vec::new())
        );
        // Backwards: a half turn first without reverse, none with it.
        let behind = [Point::new(0.0, 0.0), Point::new(-0.5, 0.0)];
        assert!(check_kinematics(UNICYCLE, Some(0.0), &behind, Some(0.0), Some(1.0)).is_err());
        let reversing = Kinematics::Unicycle {
            max_turn_rad: 2.0,
            reverse: true,
        };
        assert_eq!(
            check_kinematics(reversing, Some(0.0), &behind, Some(0.0), Some(1.0)),
            Ok(Vec::new())
        );
    }

    proptest::proptest! {
        /// The monitor and the controllers' own arithmetic agree on every polyline: the
        /// monitor takes exactly the moves whose share of the step is at most 1.
        #[test]
        fn the_turning_check_agrees_with_the_kinematics_module(
            start in -3.2f64..3.2,
            end in -3.2f64..3.2,
            reverse in proptest::bool::ANY,
            xs in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 0..5),
        ) {
            let limits = shared::kinematics::UnicycleLimits {
                max_step_m: 2.0,
                max_turn_rad: 3.0,
                reverse,
            };
            let mut path = vec![Point::origin()];
            path.extend(xs.iter().map(|&(x, y)| Point::new(x, y)));
            let share = shared::kinematics::unicycle_step_share(start, &path, end, &limits);
            let kinematics = Kinematics::Unicycle { max_turn_rad: 3.0, reverse };
            let verdict = check_kinematics(kinematics, Some(start), &path, Some(end), Some(2.0));
            if (share - 1.0).abs() > 1e-6 {
                proptest::prop_assert_eq!(verdict.is_ok(), share <= 1.0, "share {}", share);
            }
            if let Err(Refusal::TooMuchTurning { share: got }) = verdict {
                proptest::prop_assert!((got - share).abs() < 1e-9);
            }
        }

        /// On random polylines from a random heading, the monitor's car check (its own
        /// arithmetic) and the library's agree: both take the move or both refuse it,
        /// and where they take it they give the same chord errors.
        #[test]
        fn the_car_check_agrees_with_the_kinematics_module(
            start in -3.2f64..3.2,
            end_off in proptest::prop_oneof![proptest::strategy::Just(0.0), -0.1f64..0.1],
            rho_m in 0.1f64..2.0,
            reverse in proptest::bool::ANY,
            xs in proptest::collection::vec((-0.3f64..0.3, -0.3f64..0.3), 0..4),
        ) {
            let mut path = vec![Point::origin()];
            path.extend(xs.iter().map(|&(x, y)| Point::new(x, y)));
            // The end heading the chords give, give or take `end_off`.
            let mut heading = start;
            for w in path.windows(2) {
                heading += shared::kinematics::car_piece(heading, &w[0], &w[1]).turn_rad;
            }
            let end = heading + end_off;
            let limits = shared::kinematics::CarLimits {
                max_step_m: 1.5,
                turning_radius_m: rho_m,
                reverse,
            };
            let library = shared::kinematics::check_car_move(start, &path, Some(end), &limits);
            let kinematics = Kinematics::Car { turning_radius_m: rho_m, reverse };
            let monitor = check_kinematics(kinematics, Some(start), &path, Some(end), Some(1.5));
            proptest::prop_assert_eq!(library.is_ok(), monitor.is_ok(), "{:?} {:?}", library, monitor);
            if let (Ok(a), Ok(b)) = (library, monitor) {
                proptest::prop_assert_eq!(a.len(), b.len());
                for (x, y) in a.iter().zip(&b) {
                    proptest::prop_assert!((x - y).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn moves_longer_than_the_top_speed_and_moves_that_meet_are_caught() {
        let path = [Point::new(0.0, 0.0), Point::new(3.0, 4.0)];
        assert_eq!(check_length(&path, None), Ok(()));
        assert_eq!(check_length(&path, Some(5.0)), Ok(()));
        assert!(matches!(
            check_length(&path, Some(4.9)),
            Err(Refusal::TooLong { .. })
        ));
        let across = [Point::new(0.0, 4.0), Point::new(3.0, 0.0)];
        assert_eq!(distance_between_moves_m(&path, &across), 0.0);
        let beside = [Point::new(10.0, 4.0)];
        assert!((distance_between_moves_m(&path, &beside) - 7.0).abs() < 1e-12);
    }

    #[test]
    fn the_monitor_refuses_what_breaks_the_invariant_and_accepts_the_rest() {
        let m = SafetyMonitor::new(Field::new(10.0, 10.0), &[Disk::new(5.0, 5.0, 1.0)]);
        let from = Point::new(1.0, 5.0);
        let clear = [from, Point::new(3.0, 3.0)];
        assert_eq!(
            m.check(0, &from, &clear, &clear[1], false, &bodies(), &[], 8),
            Ok(())
        );
        let through = [from, Point::new(9.0, 5.0)];
        assert!(matches!(
            m.check(0, &from, &through, &through[1], false, &bodies(), &[], 8),
            Err(Refusal::Obstacle { obstacle: 0, .. })
        ));
        let around = [
            from,
            Point::new(3.0, 7.0),
            Point::new(7.0, 7.0),
            Point::new(9.0, 5.0),
        ];
        assert_eq!(
            m.check(0, &from, &around, &around[3], false, &bodies()[..1], &[], 8),
            Ok(())
        );
        assert!(matches!(
            m.check(0, &from, &around, &around[3], false, &bodies(), &[], 8),
            Err(Refusal::Agent { agent: 1, .. })
        ));
        let nan = [from, Point::new(f64::NAN, 0.0)];
        assert!(matches!(
            m.check(0, &from, &nan, &nan[1], false, &bodies(), &[], 8),
            Err(Refusal::NotFinite(1))
        ));
        let jump = [Point::new(2.0, 2.0)];
        assert!(matches!(
            m.check(0, &from, &jump, &jump[0], false, &bodies(), &[], 8),
            Err(Refusal::Teleport(_))
        ));
        let out = [from, Point::new(0.2, 5.0)];
        assert!(matches!(
            m.check(0, &from, &out, &out[1], false, &bodies(), &[], 8),
            Err(Refusal::OutsideField(1))
        ));
        assert!(matches!(
            m.check(0, &from, &clear, &from, false, &bodies(), &[], 8),
            Err(Refusal::WrongEnd)
        ));
        // Under way, a move may stop short of its best point.
        assert_eq!(
            m.check(0, &from, &clear, &from, true, &bodies(), &[], 8),
            Ok(())
        );
        // Touching is allowed: exactly the radii sum away.
        let touch = [from, Point::new(3.7, 5.0)];
        assert_eq!(
            m.check(0, &from, &touch, &touch[1], false, &bodies()[..1], &[], 8),
            Ok(())
        );
    }
}
