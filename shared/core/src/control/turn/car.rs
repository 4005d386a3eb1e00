//! A car-like agent's turn: a drivable path to the best point.
//!
//! The best point is the holonomic one (Theorem 1: the closest reachable point to the
//! slot for a disk that moves any way). A car reaches a position with any heading, so it
//! looks for the shortest Reeds-Shepp path (Dubins without reverse) from its pose to the
//! best point facing the centre's heading first (the way its slot moves), then facing
//! each of [`GOAL_HEADINGS`] world headings or its own, shortest first, and takes the
//! first whose swept disk keeps clear of every inflated body and inside the field
//! (checked exactly along each arc); with `align_heading`, the centre's heading only.
//! When none is clear, the project's Hybrid A* searches a way among the obstacles and
//! the other agents (in a window of the field round the car and its goal), and the car
//! takes the shortest clear path to the search's pose four, two or one steps ahead, or
//! else to the farthest nearer one it clears. That path, cut at the top speed, is the
//! move; without one the car stands. Unlike the holonomic guarantee, a car is not
//! promised to reach its best point (a heuristic: `docs/method.md`, reachability by
//! kinematic model).

use std::ops::ControlFlow;

use crate::control::kinematics::{CarLimits, CarPiece, car_piece, car_waypoints, curve_prefix};
use crate::control::vocabulary::Body;
use crate::geometry::{Disk, DiskGrid, Field, Point, Pose, distance_point_segment};
use crate::paths::curve::CurvePath;
use crate::paths::hybrid_astar::{self, HybridAStarSettings};
use crate::paths::{dubins, reeds_shepp};

/// The world headings a car tries to reach its best point with (besides the centre's
/// and its own): every eighth of a turn.
pub const GOAL_HEADINGS: usize = 8;

/// The largest chord error of a car's published chords, as a share of the planning
/// margin: the chords' checks add it, and it stays well inside the margin.
const CHORD_ERROR_SHARE: f64 = 0.1;

/// An arc turning less than this along one chord is taken as straight, radians.
const STRAIGHT_TURN_RAD: f64 = 1e-9;

/// The world a car plans in: what it must keep clear of.
#[derive(Clone, Copy)]
pub(super) struct CarWorld<'a> {
    /// The field.
    pub field: &'a Field,
    /// The static obstacles, true radii.
    pub obstacles: &'a DiskGrid,
    /// The other agents it senses.
    pub others: &'a [Body],
    /// Its own radius plus the planning margin, metres.
    pub reach_m: f64,
    /// The planning margin, metres.
    pub margin_m: f64,
}

/// A car's planned drive this step.
pub(super) struct CarDrive {
    /// The chords driven this step, from the start.
    pub waypoints: Vec<Point>,
    /// The heading where they end.
    pub end_heading_rad: f64,
    /// Whether the path reaches the goal this step.
    pub complete: bool,
}

/// The car's drive from `start` towards `goal` this step, or `None` when no path to it
/// (ending with any of `goal_headings`) keeps clear of `world`. The paths to the first
/// `preferred` headings are tried first, in order; then the others, shortest first.
pub(super) fn plan_car_drive(
    start: &Pose,
    goal: &Point,
    goal_headings: &[f64],
    preferred: usize,
    limits: &CarLimits,
    world: &CarWorld<'_>,
) -> Option<CarDrive> {
    let shortest = |to: &Pose| shortest_car_path(start, to, limits);
    let mut candidates: Vec<(bool, CurvePath)> = goal_headings
        .iter()
        .enumerate()
        .map(|(k, h)| (k >= preferred, shortest(&Pose::new(goal.x, goal.y, *h))))
        .filter(|(_, p)| p.length_m().is_finite())
        .collect();
    // The preferred ones first, then the shortest; on a tie the earlier heading.
    candidates.sort_by(|(a_later, a), (b_later, b)| {
        a_later
            .cmp(b_later)
            .then(a.length_m().total_cmp(&b.length_m()))
    });
    if let Some(drive) = candidates
        .into_iter()
        .find_map(|(_, path)| drive_along(start, path, true, limits, world))
    {
        return Some(drive);
    }
    // None is clear: follow the search's way, by the shortest path to one of its poses
    // four, two or one steps ahead, or else to a nearer one, the farthest that is clear.
    // (Near a body the shortest path to a pose past the search's first cusp may cut
    // into it; a pose on the search's first piece is reached by that piece itself.)
    let (poses, reach_m) = searched_path(start, goal, goal_headings, limits, world)?;
    let world = CarWorld { reach_m, ..*world };
    let mut along_m = vec![0.0];
    for w in poses.windows(2) {
        let last = along_m.last().copied().unwrap_or(0.0);
        along_m.push(last + (w[1].position() - w[0].position()).norm());
    }
    let ahead = |steps: f64| {
        along_m
            .iter()
            .position(|s| *s >= steps * limits.max_step_m)
            .unwrap_or(poses.len() - 1)
    };
    let nearer = (1..=ahead(1.0)).rev();
    // A short search gives the same pose for several of these: each is tried once.
    let mut tried = Vec::new();
    [ahead(4.0), ahead(2.0)]
        .into_iter()
        .chain(nearer)
        .filter(|k| {
            let first = !tried.contains(k);
            tried.push(*k);
            first
        })
        .find_map(|k| {
            let path = shortest(&poses[k]);
            path.length_m()
                .is_finite()
                .then_some(())
                .and_then(|()| drive_along(start, path, k + 1 == poses.len(), limits, &world))
        })
}

/// The shortest path a car within `limits` drives from `from` to `to`: Reeds-Shepp when
/// it may reverse, Dubins when not.
fn shortest_car_path(from: &Pose, to: &Pose, limits: &CarLimits) -> CurvePath {
    if limits.reverse {
        reeds_shepp::shortest_path(from, to, limits.turning_radius_m)
    } else {
        dubins::shortest_path(from, to, limits.turning_radius_m)
    }
}

/// The drive this step along `path` from `start`, if its swept disk keeps clear of
/// `world` all along; `to_goal`: the path ends at the goal.
fn drive_along(
    start: &Pose,
    path: CurvePath,
    to_goal: bool,
    limits: &CarLimits,
    world: &CarWorld<'_>,
) -> Option<CarDrive> {
    let max_error_m = CHORD_ERROR_SHARE * world.margin_m;
    let (whole, _) = car_waypoints(start, &path, max_error_m);
    if !chords_clear(start.heading_rad, &whole, world) {
        return None;
    }
    let complete = to_goal && path.length_m() <= limits.max_step_m;
    let cut = if path.length_m() <= limits.max_step_m {
        path
    } else {
        curve_prefix(&path, limits.max_step_m)
    };
    let (waypoints, end_heading_rad) = car_waypoints(start, &cut, max_error_m);
    Some(CarDrive {
        waypoints,
        end_heading_rad,
        complete,
    })
}

/// How much nearer than its start's clearance a car's searched path may keep: the
/// search must find its start free.
const START_SLACK_M: f64 = 1e-6;

/// Expansions a car's local search may take before it gives up (and the car stands).
pub const SEARCH_EXPANSIONS: usize = 20_000;

/// How far round its start and its goal a car's search looks, at least, metres (and at
/// least [`SEARCH_WINDOW_TURNS`] turning radii): the search runs in that window of the
/// field, not the whole field, whose edges it keeps clear of like the field's own.
pub const SEARCH_WINDOW_M: f64 = 5.0;

/// How far round its start and its goal a car's search looks, at least, in turning radii.
pub const SEARCH_WINDOW_TURNS: f64 = 8.0;

/// The part of the field a car's search runs in: the box round `start` and `goal` grown
/// by the window's margin, inside the field, its corner on the search's coarse grid
/// (so that its cells are the field's). Its origin, and its size as a field.
fn search_window(
    field: &Field,
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
) -> (Point, Field) {
    let margin_m = SEARCH_WINDOW_M.max(SEARCH_WINDOW_TURNS * settings.turning_radius_m);
    let grid_m = settings.cell_m * settings.heuristic_downsample as f64;
    let low = |a: f64, b: f64| (((a.min(b) - margin_m) / grid_m).floor() * grid_m).max(0.0);
    let origin = Point::new(low(start.x_m, goal.x_m), low(start.y_m, goal.y_m));
    let far_x = (start.x_m.max(goal.x_m) + margin_m).min(field.width_m);
    let far_y = (start.y_m.max(goal.y_m) + margin_m).min(field.height_m);
    (
        origin,
        Field::new((far_x - origin.x).max(0.0), (far_y - origin.y).max(0.0)),
    )
}

/// When no direct path is clear: the project's Hybrid A* from `start` to the goal facing
/// the first of `goal_headings`, among the obstacles and the other agents: its dense
/// poses, with the reach it keeps from every body and
/// edge: the car's radius plus the margin, or less where the car starts nearer than
/// that (as it may, once the others closed in), but never less than its radius plus
/// a fifth of the margin.
fn searched_path(
    start: &Pose,
    goal: &Point,
    goal_headings: &[f64],
    limits: &CarLimits,
    world: &CarWorld<'_>,
) -> Option<(Vec<Pose>, f64)> {
    let heading_rad = *goal_headings.first()?;
    let mut disks: Vec<Disk> = world.obstacles.disks().to_vec();
    disks.extend(
        world
            .others
            .iter()
            .map(|b| Disk::new(b.position.x, b.position.y, b.radius_m)),
    );
    let start_clearance_m = disks
        .iter()
        .map(|d| (start.position() - d.centre).norm() - d.radius_m)
        .fold(world.field.signed_inset_m(&start.position()), f64::min);
    let reach_m = world
        .reach_m
        .min(start_clearance_m - START_SLACK_M)
        // Above its radius by twice the chords' largest bulge, which the checks add.
        .max(world.reach_m - (1.0 - 2.0 * CHORD_ERROR_SHARE) * world.margin_m);
    let mut settings = HybridAStarSettings::new(limits.turning_radius_m, reach_m, limits.reverse);
    settings.max_expansions = SEARCH_EXPANSIONS;
    let to = Pose::new(goal.x, goal.y, heading_rad);
    // In a window round the start and the goal: the heuristic's grids cost their cells
    // at every search (on a 120 m field, most of a boxed-in car's turn), and the way out
    // of what boxes a car in lies near.
    let (origin, window) = search_window(world.field, start, &to, &settings);
    let shift =
        |p: &Pose, by: f64| Pose::new(p.x_m + by * origin.x, p.y_m + by * origin.y, p.heading_rad);
    let reach = |d: &Disk| d.radius_m + reach_m;
    let local: Vec<Disk> = disks
        .iter()
        .filter(|d| {
            d.centre.x + reach(d) >= origin.x
                && d.centre.x - reach(d) <= origin.x + window.width_m
                && d.centre.y + reach(d) >= origin.y
                && d.centre.y - reach(d) <= origin.y + window.height_m
        })
        .map(|d| Disk::new(d.centre.x - origin.x, d.centre.y - origin.y, d.radius_m))
        .collect();
    let poses = hybrid_astar::plan(
        &window,
        &local,
        &shift(start, -1.0),
        &shift(&to, -1.0),
        &settings,
    )
    .ok()?;
    let poses: Vec<Pose> = poses.iter().map(|p| shift(p, 1.0)).collect();
    (poses.len() >= 2).then_some((poses, reach_m))
}

/// Whether the arcs that the chords `points` stand for, driven from `heading_rad`,
/// keep `world.reach_m` from every body and the field's edges: exactly, along each arc.
fn chords_clear(heading_rad: f64, points: &[Point], world: &CarWorld<'_>) -> bool {
    let Some(start) = points.first() else {
        return true;
    };
    // A car that starts nearer a body (or an edge) than the reach, as it may after the
    // formation closed in round it, must only not come nearer than it starts.
    let need_m =
        |centre: &Point, radius_m: f64| (radius_m + world.reach_m).min((start - centre).norm());
    let edge_m = world.reach_m.min(world.field.signed_inset_m(start));
    let mut heading_rad = heading_rad;
    points.windows(2).all(|w| {
        let (a, b) = (&w[0], &w[1]);
        let piece = car_piece(heading_rad, a, b);
        let arc = Arc::of(heading_rad, a, b, &piece);
        heading_rad += piece.turn_rad;
        if arc.least_inset_m(world.field) < edge_m {
            return false;
        }
        let grow = nalgebra::Vector2::repeat(world.reach_m + piece.chord_error_m);
        let min = Point::new(a.x.min(b.x), a.y.min(b.y)) - grow;
        let max = Point::new(a.x.max(b.x), a.y.max(b.y)) + grow;
        let hit = world.obstacles.visit_box(&min, &max, |_, o| {
            if arc.distance_m(&o.centre) < need_m(&o.centre, o.radius_m) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        hit.is_continue()
            && world
                .others
                .iter()
                .all(|o| arc.distance_m(&o.position) >= need_m(&o.position, o.radius_m))
    })
}

/// One chord's arc (less than a half turn), or the chord itself when straight.
enum Arc {
    /// A straight chord.
    Straight(Point, Point),
    /// An arc round `centre` of `radius_m` from `from` to `to`.
    Round {
        centre: Point,
        radius_m: f64,
        from: Point,
        to: Point,
    },
}

impl Arc {
    /// The arc from `a`, tangent to `heading_rad`, to `b` that `piece` reads; a chord
    /// whose arc turns less than [`STRAIGHT_TURN_RAD`] is taken as straight (its bulge
    /// is below a nanometre a metre, and its centre too far out to compute with).
    fn of(heading_rad: f64, a: &Point, b: &Point, piece: &CarPiece) -> Self {
        if piece.turn_rad.is_nan() || piece.turn_rad.abs() < STRAIGHT_TURN_RAD {
            return Self::Straight(*a, *b);
        }
        let way = if piece.reverse { -1.0 } else { 1.0 };
        let m = nalgebra::Vector2::new(heading_rad.cos(), heading_rad.sin()) * way;
        // Left of the way driven for a counter-clockwise turn of the motion, else right.
        let side = nalgebra::Vector2::new(-m.y, m.x) * piece.turn_rad.signum();
        Self::Round {
            centre: a + side * piece.radius_m,
            radius_m: piece.radius_m,
            from: *a,
            to: *b,
        }
    }

    /// Whether the direction `d` from the centre lies within the arc's sweep.
    fn sweeps(centre: &Point, from: &Point, to: &Point, d: &nalgebra::Vector2<f64>) -> bool {
        let (u, v) = (from - centre, to - centre);
        let cross = |p: &nalgebra::Vector2<f64>, q: &nalgebra::Vector2<f64>| p.x * q.y - p.y * q.x;
        let turn = cross(&u, &v);
        cross(&u, d) * turn >= 0.0 && cross(d, &v) * turn >= 0.0 && u.dot(d) + v.dot(d) > 0.0
    }

    /// The distance from `q` to the arc, metres.
    fn distance_m(&self, q: &Point) -> f64 {
        match self {
            Self::Straight(a, b) => distance_point_segment(q, a, b),
            Self::Round {
                centre,
                radius_m,
                from,
                to,
            } => {
                let d = q - centre;
                if Self::sweeps(centre, from, to, &d) {
                    (d.norm() - radius_m).abs()
                } else {
                    (q - from).norm().min((q - to).norm())
                }
            }
        }
    }

    /// The least inset of the arc's points in `field` (negative outside).
    fn least_inset_m(&self, field: &Field) -> f64 {
        let (a, b) = match self {
            Self::Straight(a, b) | Self::Round { from: a, to: b, .. } => (a, b),
        };
        let mut least_m = field.signed_inset_m(a).min(field.signed_inset_m(b));
        if let Self::Round {
            centre,
            radius_m,
            from,
            to,
        } = self
        {
            // The arc's point farthest towards each edge, where it lies within the sweep.
            for d in [(-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0)] {
                let d = nalgebra::Vector2::new(d.0, d.1);
                if Self::sweeps(centre, from, to, &d) {
                    least_m = least_m.min(field.signed_inset_m(&(centre + d * *radius_m)));
                }
            }
        }
        least_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points along the arc a chord stands for, closely spaced (the test's oracle).
    fn dense(heading_rad: f64, a: &Point, b: &Point) -> Vec<Point> {
        let piece = car_piece(heading_rad, a, b);
        let path = CurvePath {
            segments: vec![crate::paths::curve::Segment {
                steer: if piece.turn_rad.abs() < 1e-15 {
                    crate::paths::curve::Steer::Straight
                } else if (piece.turn_rad > 0.0) != piece.reverse {
                    crate::paths::curve::Steer::Left
                } else {
                    crate::paths::curve::Steer::Right
                },
                length_m: if piece.reverse {
                    -piece.length_m
                } else {
                    piece.length_m
                },
            }],
            turning_radius_m: if piece.radius_m.is_finite() {
                piece.radius_m
            } else {
                1.0
            },
        };
        let start = Pose::new(a.x, a.y, heading_rad);
        let end = path.end_pose(&start).position();
        assert!(
            (end - b).norm() < 1e-9,
            "the oracle arc ends at the chord's end"
        );
        path.sample(&start, 1e-4)
            .iter()
            .map(|p| p.position())
            .collect()
    }

    /// A car 17 mm from an obstacle on its right, facing along it (a field of
    /// `paper-car` with seed 9, agent 2 at step 115): no direct path to its best point is
    /// clear, the search finds a way, but the shortest paths to the search's poses one,
    /// two and four steps ahead all cut into the obstacle. It used to stand there for the
    /// rest of the run; it follows the search's first piece instead.
    #[test]
    fn a_car_hugging_an_obstacle_follows_the_search_when_the_poses_ahead_are_not_clear() {
        let field = Field::new(40.0, 30.0);
        let obstacles = DiskGrid::new(vec![Disk::new(21.98645, 18.19203, 1.0)]);
        let world = CarWorld {
            field: &field,
            obstacles: &obstacles,
            others: &[],
            reach_m: 0.25 + 1e-3,
            margin_m: 1e-3,
        };
        let limits = CarLimits {
            max_step_m: 0.5,
            turning_radius_m: 0.5,
            reverse: true,
        };
        let start = Pose::new(20.71884732049971, 18.156064161682124, 1.5438170820003543);
        let goal = Point::new(24.843056190009495, 19.41040716334562);
        let headings: Vec<f64> = std::iter::once(0.646)
            .chain((0..GOAL_HEADINGS).map(|k| std::f64::consts::TAU * k as f64 / 8.0))
            .chain([start.heading_rad])
            .collect();
        let drive = plan_car_drive(&start, &goal, &headings, 1, &limits, &world)
            .expect("the search finds a way and the car takes it");
        assert!(drive.waypoints.len() >= 2 && !drive.complete);
        let chords = crate::control::kinematics::check_car_move(
            start.heading_rad,
            &drive.waypoints,
            Some(drive.end_heading_rad),
            &limits,
        );
        assert!(
            chords.is_ok_and(|errors| !errors.is_empty()),
            "a drivable move"
        );
        // Clear of the obstacle by its radius all along (exactly, along each arc).
        let touching = CarWorld {
            reach_m: 0.25,
            ..world
        };
        assert!(chords_clear(start.heading_rad, &drive.waypoints, &touching));
        let end = drive.waypoints.last().copied().unwrap_or(start.position());
        assert!((end - start.position()).norm() > 1e-3, "it moves");
    }

    /// The search's window holds the start and the goal with the margin round them
    /// where the field allows, stays inside the field, and starts on the coarse grid.
    #[test]
    fn the_search_window_holds_start_and_goal_with_the_margin_inside_the_field() {
        let field = Field::new(120.0, 80.0);
        let settings = HybridAStarSettings::new(0.5, 0.301, true);
        let grid_m = settings.cell_m * settings.heuristic_downsample as f64;
        for (start, goal) in [
            (Pose::new(60.3, 40.7, 0.0), Pose::new(61.9, 39.2, 1.0)),
            (Pose::new(1.0, 2.0, 0.0), Pose::new(3.0, 0.5, 1.0)),
            (Pose::new(118.0, 79.0, 0.0), Pose::new(117.0, 77.5, 1.0)),
        ] {
            let (origin, window) = search_window(&field, &start, &goal, &settings);
            let margin_m = SEARCH_WINDOW_M.max(SEARCH_WINDOW_TURNS * 0.5);
            assert!(origin.x >= 0.0 && origin.y >= 0.0);
            assert!(origin.x + window.width_m <= field.width_m + 1e-9);
            assert!(origin.y + window.height_m <= field.height_m + 1e-9);
            assert!(((origin.x / grid_m).round() * grid_m - origin.x).abs() < 1e-9);
            assert!(((origin.y / grid_m).round() * grid_m - origin.y).abs() < 1e-9);
            for p in [&start, &goal] {
                let left = p.x_m - origin.x;
                let below = p.y_m - origin.y;
                let right = origin.x + window.width_m - p.x_m;
                let above = origin.y + window.height_m - p.y_m;
                assert!(left >= margin_m.min(p.x_m) - 1e-9, "{p:?}");
                assert!(below >= margin_m.min(p.y_m) - 1e-9, "{p:?}");
                assert!(right >= margin_m.min(field.width_m - p.x_m) - 1e-9, "{p:?}");
                assert!(
                    above >= margin_m.min(field.height_m - p.y_m) - 1e-9,
                    "{p:?}"
                );
            }
            // Much smaller than the field in its middle.
            if start.x_m > 10.0 && start.x_m < 110.0 {
                assert!(window.width_m * window.height_m < 0.05 * 120.0 * 80.0);
            }
        }
    }

    #[test]
    fn the_distance_to_an_arc_is_that_of_its_nearest_point() {
        let field = Field::new(10.0, 10.0);
        for (h, a, b) in [
            (0.0, Point::new(5.0, 5.0), Point::new(5.7, 5.3)),
            (0.7, Point::new(5.0, 5.0), Point::new(5.2, 5.5)),
            (0.0, Point::new(5.0, 5.0), Point::new(4.3, 5.3)),
            (2.0, Point::new(5.0, 5.0), Point::new(5.4, 4.2)),
            (-2.5, Point::new(5.0, 5.0), Point::new(4.9, 4.6)),
        ] {
            let piece = car_piece(h, &a, &b);
            let arc = Arc::of(h, &a, &b, &piece);
            let points = dense(h, &a, &b);
            for k in 0..60 {
                let t = k as f64 * 0.37;
                let q = Point::new(
                    5.0 + 0.9 * t.cos() * (1.0 + 0.1 * k as f64 % 3.0),
                    5.0 + 0.9 * t.sin(),
                );
                let want = points
                    .iter()
                    .map(|p| (p - q).norm())
                    .fold(f64::INFINITY, f64::min);
                let got = arc.distance_m(&q);
                assert!(
                    (got - want).abs() < 1e-4,
                    "h {h} a {a} b {b} q {q}: {got} vs {want}"
                );
            }
            let want = points
                .iter()
                .map(|p| field.signed_inset_m(p))
                .fold(f64::INFINITY, f64::min);
            assert!((arc.least_inset_m(&field) - want).abs() < 1e-6);
        }
    }
}
