//! The safety invariant, checked with plain geometry: for every pair of bodies a, b at
//! every instant, `||p_a - p_b|| >= r_a + r_b` (to [`SAFETY_TOLERANCE_M`]).
//!
//! This check knows nothing of the controllers' inflation, margins or arcs: it takes the
//! polyline a body follows and the true radii. The coordinator's monitor is a second,
//! independent implementation of the same check on parry.

use std::ops::ControlFlow;

use crate::control::vocabulary::Body;
use crate::geometry::{Disk, DiskGrid, Field, Point, Polygon, Vector, distance_point_segment};

mod clearance;

pub use clearance::{
    bodies_grid, clearance_to_others_m, clearance_to_polygons_m, clearances_m, clearances_of_m,
};

/// How far a body may overlap another before it counts as a collision, in metres.
pub const SAFETY_TOLERANCE_M: f64 = 1e-9;

/// Why a move breaks the safety invariant.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Violation {
    /// A waypoint is NaN or infinite.
    #[error("waypoint {index} is not a finite point")]
    NotFinite {
        /// Index of the waypoint.
        index: usize,
    },
    /// The move has no waypoint or more than allowed.
    #[error("the move has {count} waypoints")]
    BadLength {
        /// How many waypoints it has.
        count: usize,
    },
    /// The first waypoint is not where the body stands.
    #[error("the move starts {offset_m} m away from the body")]
    Teleport {
        /// Distance from the body's position to the first waypoint.
        offset_m: f64,
    },
    /// The body would leave the field.
    #[error("waypoint {index} takes the body {overshoot_m} m outside the field")]
    OutsideField {
        /// Index of the waypoint.
        index: usize,
        /// How far the body's edge would stick out.
        overshoot_m: f64,
    },
    /// The body would overlap an obstacle.
    #[error("segment {segment} overlaps obstacle {obstacle} by {overlap_m} m")]
    HitsObstacle {
        /// Index of the segment (waypoint `segment` to `segment + 1`).
        segment: usize,
        /// Index of the obstacle.
        obstacle: usize,
        /// Overlap depth.
        overlap_m: f64,
    },
    /// The body would overlap a moving obstacle where it stands (a body that starts its
    /// move overlapping one, struck by it, may only move away from its centre).
    #[error("the move overlaps moving obstacle {obstacle} by {overlap_m} m")]
    HitsMovingObstacle {
        /// Index of the moving obstacle, in scenario order.
        obstacle: usize,
        /// Overlap depth.
        overlap_m: f64,
    },
    /// The body would overlap a polygon obstacle.
    #[error("segment {segment} overlaps polygon {polygon} by {overlap_m} m")]
    HitsPolygon {
        /// Index of the segment.
        segment: usize,
        /// Index of the polygon.
        polygon: usize,
        /// Overlap depth.
        overlap_m: f64,
    },
    /// The move is longer than the agent's top speed allows in one step.
    #[error("the move is {length_m} m long, beyond the top speed of {max_m} m per step")]
    TooLong {
        /// Length of the move.
        length_m: f64,
        /// The agent's top speed, metres per step.
        max_m: f64,
    },
    /// The move ends neither at its best point nor, under way, short of it.
    #[error("the move does not end at its best point")]
    WrongEnd,
    /// An agent with a heading sent a move without a finite end heading.
    #[error("the move of an agent with a heading does not say where it ends facing")]
    NoHeading,
    /// A unicycle's move needs more than one step's time: its turning and driving
    /// together exceed what the step allows.
    #[error("turning and driving take {share} of a step; at most one step is allowed")]
    TooMuchTurning {
        /// The share of a step the move takes at the least.
        share: f64,
    },
    /// A car's move is not one it can drive (too tight, reversing where it may not,
    /// turning in place, or too long along its arcs).
    #[error("a car cannot drive it: {0}")]
    NotDrivable(#[from] crate::control::kinematics::CarMoveError),
    /// The move comes too close to the move of an agent of the same parallel group.
    #[error(
        "the move comes within {distance_m} m of agent {agent}'s move in the same group (radii sum {reach_m} m)"
    )]
    MeetsGroupMate {
        /// The other agent.
        agent: usize,
        /// Smallest distance between the two moves.
        distance_m: f64,
        /// The sum of their radii.
        reach_m: f64,
    },
    /// The body would overlap another body.
    #[error("segment {segment} overlaps body {body} by {overlap_m} m")]
    HitsBody {
        /// Index of the segment.
        segment: usize,
        /// Index of the other body in the list given.
        body: usize,
        /// Overlap depth.
        overlap_m: f64,
    },
}

/// Check that a body of radius `radius_m` standing at `from` can follow `waypoints`
/// (a polyline starting at `from`) without leaving `field` or overlapping an obstacle of
/// `obstacles` (true radii) or one of `others` (which stand still).
pub fn check_move(
    field: &Field,
    obstacles: &DiskGrid,
    others: &[Body],
    radius_m: f64,
    from: &Point,
    waypoints: &[Point],
    max_waypoints: usize,
) -> Result<(), Violation> {
    check_move_skipping(
        field,
        obstacles,
        others,
        None,
        None,
        &[],
        radius_m,
        from,
        waypoints,
        &[],
        max_waypoints,
    )
}

/// The bodies a move is checked against in [`check_move_among`].
#[derive(Clone, Copy, Debug)]
pub struct Others<'a> {
    /// Every agent's body, by index (the mover's own is skipped).
    pub bodies: &'a [Body],
    /// A body `j` with `passing[j]` moves at the same time as the mover (simultaneous
    /// turns) and is not looked at here; the two moves are checked against each other in
    /// time ([`crate::world::groups::simultaneous_meetings`]). Empty: none passes.
    pub passing: &'a [bool],
    /// A grid over exactly `bodies` (same order, same disks), so that a move is checked
    /// against the bodies near it only; `None`: against each body in turn. The verdict is
    /// the same.
    pub grid: Option<&'a DiskGrid>,
}

/// [`check_move`] for body `agent` of `others.bodies` against the other bodies that
/// stand still (see [`Others`]), without copying them out: [`Violation::HitsBody`]
/// numbers the bodies as [`check_move`] would number them without `agent`.
///
/// `chord_errors_m` holds, for a car's move, how far each segment's arc bulges from it
/// ([`check_car_move`](crate::control::kinematics::check_car_move)): the segment is checked with
/// the agent's radius grown by it, so the whole arc is (empty for straight segments).
#[allow(clippy::too_many_arguments)]
pub fn check_move_among(
    field: &Field,
    obstacles: &DiskGrid,
    others: &Others<'_>,
    agent: usize,
    from: &Point,
    waypoints: &[Point],
    chord_errors_m: &[f64],
    max_waypoints: usize,
) -> Result<(), Violation> {
    // A grid over other bodies than these would miss some: never used then.
    let grid = others
        .grid
        .filter(|g| g.disks().len() == others.bodies.len());
    check_move_skipping(
        field,
        obstacles,
        others.bodies,
        grid,
        Some(agent),
        others.passing,
        others.bodies[agent].radius_m,
        from,
        waypoints,
        chord_errors_m,
        max_waypoints,
    )
}

/// [`check_move`] against `bodies` but the one at index `skip`, if any, and those
/// `passing` marks.
#[allow(clippy::too_many_arguments)]
fn check_move_skipping(
    field: &Field,
    obstacles: &DiskGrid,
    bodies: &[Body],
    grid: Option<&DiskGrid>,
    skip: Option<usize>,
    passing: &[bool],
    radius_m: f64,
    from: &Point,
    waypoints: &[Point],
    chord_errors_m: &[f64],
    max_waypoints: usize,
) -> Result<(), Violation> {
    // Segment k's chord error (0 past the end); a waypoint takes that of either segment.
    let error_m = |k: usize| chord_errors_m.get(k).copied().unwrap_or(0.0).max(0.0);
    if waypoints.is_empty() || waypoints.len() > max_waypoints {
        return Err(Violation::BadLength {
            count: waypoints.len(),
        });
    }
    if let Some(index) = waypoints
        .iter()
        .position(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(Violation::NotFinite { index });
    }
    let offset_m = (waypoints[0] - from).norm();
    if offset_m > SAFETY_TOLERANCE_M {
        return Err(Violation::Teleport { offset_m });
    }
    for (index, p) in waypoints.iter().enumerate() {
        let grown_m = radius_m + error_m(index).max(index.checked_sub(1).map_or(0.0, error_m));
        let overshoot_m = grown_m - field.signed_inset_m(p);
        if overshoot_m > SAFETY_TOLERANCE_M {
            return Err(Violation::OutsideField { index, overshoot_m });
        }
    }
    let single = [waypoints[0], waypoints[0]];
    let segments: &[Point] = if waypoints.len() == 1 {
        &single
    } else {
        waypoints
    };
    // The bodies a grid finds near a segment.
    let mut near: Vec<usize> = Vec::new();
    for (segment, w) in segments.windows(2).enumerate() {
        let (a, b) = (&w[0], &w[1]);
        let radius_m = radius_m + error_m(segment);
        let reach = Vector::new(radius_m, radius_m);
        let min = Point::new(a.x.min(b.x), a.y.min(b.y)) - reach;
        let max = Point::new(a.x.max(b.x), a.y.max(b.y)) + reach;
        let hit = obstacles.visit_box(&min, &max, |obstacle, o| {
            let overlap_m = o.radius_m + radius_m - distance_point_segment(&o.centre, a, b);
            if overlap_m > SAFETY_TOLERANCE_M {
                ControlFlow::Break(Violation::HitsObstacle {
                    segment,
                    obstacle,
                    overlap_m,
                })
            } else {
                ControlFlow::Continue(())
            }
        });
        if let ControlFlow::Break(v) = hit {
            return Err(v);
        }
        let meets = |j: usize, o: &Body| -> Option<Violation> {
            if Some(j) == skip || passing.get(j).copied().unwrap_or(false) {
                return None;
            }
            // A body whose centre lies farther than the radii sum outside the segment's
            // box is farther than that from the segment: it cannot overlap, and is
            // skipped without the distance (the first violation found is the same).
            // (Rounding moves the box's edges by an ulp, far below the tolerance.)
            let out_m = o.radius_m + radius_m;
            let c = &o.position;
            if c.x < a.x.min(b.x) - out_m
                || c.x > a.x.max(b.x) + out_m
                || c.y < a.y.min(b.y) - out_m
                || c.y > a.y.max(b.y) + out_m
            {
                return None;
            }
            let overlap_m = o.radius_m + radius_m - distance_point_segment(&o.position, a, b);
            // Numbered as in the list of the others (`bodies` without `skip`).
            let body = match skip {
                Some(s) if j > s => j - 1,
                _ => j,
            };
            (overlap_m > SAFETY_TOLERANCE_M).then_some(Violation::HitsBody {
                segment,
                body,
                overlap_m,
            })
        };
        match grid {
            // The bodies the grid finds near the segment (a margin far above rounding, so
            // every one the box test above lets through), in index order: the same first
            // violation as the scan.
            Some(grid) => {
                near.clear();
                let margin = Vector::new(1e-6, 1e-6);
                let _ = grid.visit_box(&(min - margin), &(max + margin), |j, _| {
                    near.push(j);
                    ControlFlow::<()>::Continue(())
                });
                near.sort_unstable();
                if let Some(v) = near.iter().find_map(|&j| meets(j, &bodies[j])) {
                    return Err(v);
                }
            }
            None => {
                if let Some(v) = bodies.iter().enumerate().find_map(|(j, o)| meets(j, o)) {
                    return Err(v);
                }
            }
        }
    }
    Ok(())
}

/// Check the move `waypoints` of a body of `radius_m` standing at `from` against the
/// moving obstacles `moving` where they stand (true radii, scenario order): no point of
/// it may come within reach of one, but a body that starts overlapping one (it was
/// struck) may leave it: its move must then never come closer to that obstacle's centre
/// than it started.
pub fn check_move_against_moving(
    moving: &[Disk],
    radius_m: f64,
    from: &Point,
    waypoints: &[Point],
) -> Result<(), Violation> {
    for (obstacle, o) in moving.iter().enumerate() {
        let reach_m = o.radius_m + radius_m;
        let closest_m = crate::geometry::distance_polyline_polyline(waypoints, &[o.centre]);
        if closest_m >= reach_m - SAFETY_TOLERANCE_M {
            continue;
        }
        let start_m = (from - o.centre).norm();
        let leaving =
            start_m < reach_m - SAFETY_TOLERANCE_M && closest_m >= start_m - SAFETY_TOLERANCE_M;
        if !leaving {
            return Err(Violation::HitsMovingObstacle {
                obstacle,
                overlap_m: reach_m - closest_m,
            });
        }
    }
    Ok(())
}

/// Check that a body of radius `radius_m` following `waypoints` (already checked by
/// [`check_move`] or [`check_move_among`]: finite, at least one) never overlaps one of
/// `polygons` beyond [`SAFETY_TOLERANCE_M`]: the exact distance of every segment to
/// every polygon, inside counting as overlap by at least the radius.
pub fn check_move_against_polygons(
    polygons: &[Polygon],
    radius_m: f64,
    waypoints: &[Point],
) -> Result<(), Violation> {
    let single = [waypoints.first().copied().unwrap_or(Point::origin()); 2];
    let segments: &[Point] = if waypoints.len() < 2 {
        &single
    } else {
        waypoints
    };
    for (segment, w) in segments.windows(2).enumerate() {
        for (polygon, shape) in polygons.iter().enumerate() {
            let overlap_m = radius_m - shape.distance_to_segment_m(&w[0], &w[1]);
            if overlap_m > SAFETY_TOLERANCE_M {
                return Err(Violation::HitsPolygon {
                    segment,
                    polygon,
                    overlap_m,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Disk;

    #[test]
    fn a_move_through_an_obstacle_or_a_body_is_a_violation() {
        let field = Field::new(10.0, 10.0);
        let obstacles = DiskGrid::new(vec![Disk::new(5.0, 5.0, 1.0)]);
        let from = Point::new(1.0, 5.0);
        let through = [from, Point::new(9.0, 5.0)];
        assert!(matches!(
            check_move(&field, &obstacles, &[], 0.3, &from, &through, 8),
            Err(Violation::HitsObstacle { obstacle: 0, .. })
        ));
        let around = [
            from,
            Point::new(3.0, 7.0),
            Point::new(7.0, 7.0),
            Point::new(9.0, 5.0),
        ];
        assert!(check_move(&field, &obstacles, &[], 0.3, &from, &around, 8).is_ok());
        let other = Body {
            position: Point::new(5.0, 7.5),
            radius_m: 0.3,
        };
        assert!(matches!(
            check_move(&field, &obstacles, &[other], 0.3, &from, &around, 8),
            Err(Violation::HitsBody { body: 0, .. })
        ));
        let nan = [from, Point::new(f64::NAN, 1.0)];
        assert!(matches!(
            check_move(&field, &obstacles, &[], 0.3, &from, &nan, 8),
            Err(Violation::NotFinite { index: 1 })
        ));
        let jump = [Point::new(2.0, 2.0)];
        assert!(matches!(
            check_move(&field, &obstacles, &[], 0.3, &from, &jump, 8),
            Err(Violation::Teleport { .. })
        ));
        let out = [from, Point::new(0.1, 5.0)];
        assert!(matches!(
            check_move(&field, &obstacles, &[], 0.3, &from, &out, 8),
            Err(Violation::OutsideField { index: 1, .. })
        ));
    }

    /// A body that moves at the same time is left to the check in time; one that stands
    /// is in the way, and is numbered as among the others.
    #[test]
    fn a_passing_body_is_not_in_the_way_of_a_move_alone() {
        let field = Field::new(10.0, 10.0);
        let obstacles = DiskGrid::new(Vec::new());
        let body = |x: f64| Body {
            position: Point::new(x, 5.0),
            radius_m: 0.3,
        };
        // Agent 1 moves along a row through where agent 2 stands; agent 0 is behind it.
        let bodies = [body(1.0), body(2.0), body(4.0)];
        let from = bodies[1].position;
        let ahead = [from, Point::new(6.0, 5.0)];
        let check = |passing: &[bool]| {
            let others = Others {
                bodies: &bodies,
                passing,
                grid: None,
            };
            check_move_among(&field, &obstacles, &others, 1, &from, &ahead, &[], 8)
        };
        assert!(matches!(
            check(&[]),
            Err(Violation::HitsBody { body: 1, .. })
        ));
        assert!(check(&[false, true, true]).is_ok());
        // Agent 0 passing changes nothing: agent 2 still stands in the way.
        assert!(matches!(
            check(&[true, true, false]),
            Err(Violation::HitsBody { body: 1, .. })
        ));
    }
}
