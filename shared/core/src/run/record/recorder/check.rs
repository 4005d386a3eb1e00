//! The recorder's own check of one move: plain geometry against the bodies where they
//! stand, the field, the obstacles and polygons, the agent's kinematics, top speed and
//! best point.

use super::Recorder;
use crate::control::kinematics::{CarLimits, UnicycleLimits, check_car_move, unicycle_step_share};
use crate::control::safety::{self, SAFETY_TOLERANCE_M, Violation};
use crate::control::vocabulary::{Kinematics, MAX_WAYPOINTS, Move, MoveStatus};
use crate::geometry::polyline_length_m;

/// How far beyond one step a unicycle's move may go, as a share of the step (rounding).
const UNICYCLE_SHARE_TOLERANCE: f64 = 1e-9;

impl Recorder<'_> {
    /// Check one move against the bodies where they stand (`others`: but those it marks
    /// passing, which move at the same time), the field, the agent's top speed and its
    /// best point.
    pub(super) fn check_alone(
        &self,
        agent: usize,
        mv: &Move,
        others: &safety::Others<'_>,
    ) -> Result<(), Violation> {
        let body = self.world.bodies()[agent];
        let spec = &self.scenario.agents[agent];
        // A car's chords stand for arcs: read them back, and grow each by its bulge.
        let chord_errors_m = match (self.world.headings()[agent], spec.kinematics) {
            (
                Some(heading_rad),
                Kinematics::Car {
                    turning_radius_m,
                    reverse,
                },
            ) => {
                let limits = CarLimits {
                    // Validation gives every car a top speed.
                    max_step_m: spec.max_step_m.unwrap_or(f64::INFINITY),
                    turning_radius_m,
                    reverse,
                };
                check_car_move(heading_rad, &mv.waypoints, mv.end_heading_rad, &limits)?
            }
            _ => Vec::new(),
        };
        safety::check_move_among(
            &self.scenario.field,
            &self.obstacles,
            others,
            agent,
            &body.position,
            &mv.waypoints,
            &chord_errors_m,
            MAX_WAYPOINTS,
        )?;
        safety::check_move_against_moving(
            self.moving_now.disks(),
            body.radius_m,
            &body.position,
            &mv.waypoints,
        )?;
        safety::check_move_against_polygons(&self.scenario.polygons, body.radius_m, &mv.waypoints)?;
        if let Some(max_m) = spec.max_step_m {
            let length_m = polyline_length_m(&mv.waypoints);
            if length_m > max_m + SAFETY_TOLERANCE_M {
                return Err(Violation::TooLong { length_m, max_m });
            }
        }
        if let (
            Some(heading_rad),
            Kinematics::Unicycle {
                max_turn_rad,
                reverse,
            },
        ) = (self.world.headings()[agent], spec.kinematics)
        {
            let Some(end_rad) = mv.end_heading_rad.filter(|h| h.is_finite()) else {
                return Err(Violation::NoHeading);
            };
            // Validation gives every unicycle a top speed.
            let max_step_m = spec.max_step_m.unwrap_or(f64::INFINITY);
            let limits = UnicycleLimits {
                max_step_m,
                max_turn_rad,
                reverse,
            };
            let share = unicycle_step_share(heading_rad, &mv.waypoints, end_rad, &limits);
            if share.is_nan() || share > 1.0 + UNICYCLE_SHARE_TOLERANCE {
                return Err(Violation::TooMuchTurning { share });
            }
        }
        // The last waypoint is where the agent ends up; it must be the best point, unless
        // the agent is under way to it.
        if mv.status != MoveStatus::UnderWay && mv.end() != mv.best {
            return Err(Violation::WrongEnd);
        }
        Ok(())
    }
}
