//! Obstacles that move: a disk driven along a polyline of waypoints at a constant speed,
//! back and forth or round a loop, and where it is at every step.
//!
//! # When they move
//!
//! Time is counted in steps. At step 0 a moving obstacle stands at its first waypoint.
//! Step `k` begins with every moving obstacle driving `speed_m_per_step` along its route,
//! from where it stood at step `k - 1` to [`MovingObstacle::position_at`]`(k)`, while every
//! agent stands still; only then does the formation centre move on and do the agents take
//! their turns, with the obstacles standing still. So an obstacle's motion is the polyline
//! [`MovingObstacle::sweep`]`(k)` (its route's corners included), and between two turns of
//! an agent every moving obstacle moves exactly once, by at most its speed: it stays
//! within [`MovingObstacle::reach_disk_at`] of where the agent last saw it. (Before the
//! first turns, at step 1, the agents have seen nothing: validation refuses an obstacle
//! whose first motion reaches the formation at the start pose.)
//!
//! ```
//! use shared::geometry::Point;
//! use shared::world::moving_obstacle::{MovingObstacle, Route};
//! let patrol = MovingObstacle::new(
//!     0.5,
//!     vec![Point::new(0.0, 0.0), Point::new(2.0, 0.0)],
//!     0.75,
//!     Route::BackAndForth,
//! );
//! assert_eq!(patrol.position_at(0), Point::new(0.0, 0.0));
//! assert_eq!(patrol.position_at(2), Point::new(1.5, 0.0));
//! // Step 3 drives to the end of the route and back a quarter metre.
//! assert_eq!(patrol.sweep(3), vec![Point::new(1.5, 0.0), Point::new(2.0, 0.0), Point::new(1.75, 0.0)]);
//! assert_eq!(patrol.position_at(3), Point::new(1.75, 0.0));
//! ```

use serde::{Deserialize, Serialize};

use crate::geometry::{Disk, Point, polyline_length_m};

/// How a moving obstacle goes round its waypoints.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Route {
    /// First waypoint to last, then back to the first, and so on.
    #[default]
    BackAndForth,
    /// First waypoint to last, then straight back to the first, and round again.
    Loop,
}

impl Route {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Route::BackAndForth => "back-and-forth",
            Route::Loop => "loop",
        }
    }
}

/// A disk driven along a route at a constant speed (see the module documentation for when
/// it moves).
#[derive(Clone, Debug, PartialEq)]
pub struct MovingObstacle {
    /// Its radius, in metres.
    pub radius_m: f64,
    /// The waypoints, at least two; it starts at the first.
    pub waypoints_m: Vec<Point>,
    /// Distance driven per step along the route, in metres.
    pub speed_m_per_step: f64,
    /// Back and forth, or round a loop.
    pub route: Route,
    /// One lap of the route as a closed walk: the corners in the order driven, from the
    /// first waypoint back to it.
    lap: Vec<Point>,
    /// Distance along the lap to each corner of `lap`, in metres.
    lap_at_m: Vec<f64>,
}

impl MovingObstacle {
    /// An obstacle of `radius_m` driven along `waypoints_m` (at least two, else it stands
    /// at the one it has) at `speed_m_per_step`.
    pub fn new(
        radius_m: f64,
        waypoints_m: Vec<Point>,
        speed_m_per_step: f64,
        route: Route,
    ) -> Self {
        let mut lap = waypoints_m.clone();
        match route {
            Route::BackAndForth => lap.extend(waypoints_m.iter().rev().skip(1)),
            Route::Loop => lap.extend(waypoints_m.first()),
        }
        let mut lap_at_m = Vec::with_capacity(lap.len());
        let mut at_m = 0.0;
        for (i, p) in lap.iter().enumerate() {
            if i > 0 {
                at_m += (p - lap[i - 1]).norm();
            }
            lap_at_m.push(at_m);
        }
        Self {
            radius_m,
            waypoints_m,
            speed_m_per_step,
            route,
            lap,
            lap_at_m,
        }
    }

    /// Length of one lap of the route, in metres (twice the polyline back and forth; the
    /// polyline and its closing segment round a loop).
    pub fn lap_length_m(&self) -> f64 {
        self.lap_at_m.last().copied().unwrap_or(0.0)
    }

    /// Where it stands at `step`.
    pub fn position_at(&self, step: usize) -> Point {
        self.point_at_lap_m(self.lap_distance_m(step)).0
    }

    /// Its disk at `step`.
    pub fn disk_at(&self, step: usize) -> Disk {
        let c = self.position_at(step);
        Disk {
            centre: c,
            radius_m: self.radius_m,
        }
    }

    /// Every place it can be from `step` until the end of step `step + 1`'s motion, as
    /// seen by an agent that knows only where it is and how fast it goes: its disk at
    /// `step` grown by its speed.
    pub fn reach_disk_at(&self, step: usize) -> Disk {
        self.disk_at(step).inflated(self.speed_m_per_step)
    }

    /// Its motion at the start of step `step` (from where it stood at `step - 1` to where it
    /// stands at `step`), as a polyline through the route's corners passed on the way; step
    /// 0 has no motion (its position alone).
    pub fn sweep(&self, step: usize) -> Vec<Point> {
        let to = self.position_at(step);
        if step == 0 || self.lap_length_m() <= 0.0 {
            return vec![to];
        }
        let from_m = self.lap_distance_m(step - 1);
        let (from, mut corner) = self.point_at_lap_m(from_m);
        let mut points = vec![from];
        // Corners strictly between the two lap distances, going round the lap.
        let mut left_m = self.speed_m_per_step;
        let mut at_m = from_m;
        let corners = self.lap.len() - 1;
        for _ in 0..=2 * corners {
            let next = corner + 1;
            let to_corner_m = self.lap_at_m[next] - at_m;
            if to_corner_m >= left_m {
                break;
            }
            left_m -= to_corner_m;
            points.push(self.lap[next]);
            (corner, at_m) = if next == corners {
                (0, 0.0)
            } else {
                (next, self.lap_at_m[next])
            };
        }
        points.push(to);
        points.dedup();
        points
    }

    /// Length of [`Self::sweep`]`(step)`, in metres (its speed, but for rounding).
    pub fn sweep_length_m(&self, step: usize) -> f64 {
        polyline_length_m(&self.sweep(step))
    }

    /// How far along one lap it is at `step`, in metres.
    fn lap_distance_m(&self, step: usize) -> f64 {
        let lap_m = self.lap_length_m();
        if lap_m <= 0.0 {
            return 0.0;
        }
        (step as f64 * self.speed_m_per_step).rem_euclid(lap_m)
    }

    /// The point `at_m` along the lap, and the index of the lap segment it lies on.
    fn point_at_lap_m(&self, at_m: f64) -> (Point, usize) {
        let Some(&first) = self.lap.first() else {
            return (Point::origin(), 0);
        };
        let segments = self.lap.len().saturating_sub(1);
        if segments == 0 {
            return (first, 0);
        }
        // The segment [lap_at_m[i], lap_at_m[i + 1]) holding `at_m`.
        let i = self
            .lap_at_m
            .partition_point(|&m| m <= at_m)
            .saturating_sub(1)
            .min(segments - 1);
        let (a, b) = (self.lap[i], self.lap[i + 1]);
        let length_m = self.lap_at_m[i + 1] - self.lap_at_m[i];
        if length_m <= 0.0 {
            return (a, i);
        }
        let t = ((at_m - self.lap_at_m[i]) / length_m).clamp(0.0, 1.0);
        (a + (b - a) * t, i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_loop() -> MovingObstacle {
        MovingObstacle::new(
            0.5,
            vec![
                Point::new(0.0, 0.0),
                Point::new(4.0, 0.0),
                Point::new(4.0, 4.0),
                Point::new(0.0, 4.0),
            ],
            1.5,
            Route::Loop,
        )
    }

    #[test]
    fn a_loop_closes_back_to_its_first_waypoint() {
        let o = square_loop();
        assert_eq!(o.lap_length_m(), 16.0);
        assert_eq!(o.position_at(0), Point::new(0.0, 0.0));
        assert_eq!(o.position_at(3), Point::new(4.0, 0.5));
        // 15 m along: on the closing segment, 1 m above the first waypoint.
        assert_eq!(o.position_at(10), Point::new(0.0, 1.0));
        assert_eq!(
            o.sweep(11),
            vec![
                Point::new(0.0, 1.0),
                Point::new(0.0, 0.0),
                Point::new(0.5, 0.0)
            ]
        );
    }

    #[test]
    fn every_sweep_runs_from_the_last_position_to_the_next_at_its_speed() {
        let routes = [
            square_loop(),
            MovingObstacle::new(
                1.0,
                vec![
                    Point::new(1.0, 1.0),
                    Point::new(1.3, 1.0),
                    Point::new(1.3, 2.0),
                ],
                0.7,
                Route::BackAndForth,
            ),
            // Faster than the whole route: a sweep wraps round.
            MovingObstacle::new(
                1.0,
                vec![Point::new(1.0, 1.0), Point::new(1.2, 1.0)],
                0.5,
                Route::BackAndForth,
            ),
        ];
        for o in routes {
            for step in 1..200 {
                let sweep = o.sweep(step);
                assert_eq!(sweep.first(), Some(&o.position_at(step - 1)));
                assert_eq!(sweep.last(), Some(&o.position_at(step)));
                let length_m = polyline_length_m(&sweep);
                assert!(
                    length_m <= o.speed_m_per_step + 1e-9,
                    "{length_m} at {step}"
                );
                // Within its reach disk as seen from the step before.
                let before = o.position_at(step - 1);
                assert!(
                    sweep
                        .iter()
                        .all(|p| (p - before).norm() <= o.speed_m_per_step + 1e-9)
                );
                if o.lap_length_m() > o.speed_m_per_step {
                    assert!(
                        (length_m - o.speed_m_per_step).abs() < 1e-9,
                        "{length_m} at {step}"
                    );
                }
            }
        }
    }

    #[test]
    fn back_and_forth_turns_round_at_both_ends() {
        let o = MovingObstacle::new(
            0.5,
            vec![Point::new(0.0, 0.0), Point::new(3.0, 0.0)],
            1.0,
            Route::BackAndForth,
        );
        let xs: Vec<f64> = (0..8).map(|k| o.position_at(k).x).collect();
        assert_eq!(xs, [0.0, 1.0, 2.0, 3.0, 2.0, 1.0, 0.0, 1.0]);
    }
}
