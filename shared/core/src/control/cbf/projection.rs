//! The barrier controller for a differential-drive agent, the Robotarium's way: the
//! single-integrator barrier on a point a projection distance ahead of the robot, mapped
//! to a forward speed and a turn rate at once.
//!
//! A unicycle at `x` facing `theta` drives at speed `v` and turns at rate `w`. The point
//! `p = x + l e` a distance `l` ahead of it (`e = (cos theta, sin theta)`,
//! `n = (-sin theta, cos theta)`) moves at `p' = v e + l w n`: any velocity `u` of `p`
//! is driven by `v = u . e`, `w = u . n / l`. So the single-integrator barrier applies to
//! `p` as it does to a holonomic agent ([`CbfController`]), for a disk round `p` of the
//! agent's radius plus `l` (which holds the whole robot). Written in the coordinates
//! `(v, l w)` (a rotation of `u`, so the QP's distance is the same), `v >= 0` is one more
//! half-plane for a robot that may not reverse, and `u = 0` stays feasible.
//!
//! The projection distance is the agent's radius (the Robotarium's GRITSbots: 0.05 m for
//! a radius of 0.055 m). The nominal velocity is the one the robot's centre should have,
//! `gain (slot - x)`, so the centre (not the projected point) settles on its slot. The
//! pair `(v, w)` is scaled down, both together, until the step fits the agent's limits
//! (driving and turning share the step: [`crate::control::kinematics::unicycle_step_share`]), which
//! keeps every barrier row satisfied. The robot then drives the arc of `(v, w)` for one
//! step, published as chords turning at most [`ARC_CHORD_TURN_RAD`] each, which a
//! differential drive follows exactly (turning in place at each vertex by as much as the
//! arc turns between chords); the safety checks read those chords.
//!
//! With `align_heading`, a robot within the projection distance of its slot turns in
//! place towards the centre's heading instead (as far as a step allows; turning in place
//! sweeps nothing new): the point ahead cannot settle the heading, and so close the
//! position error is already below the robot's radius.
//!
//! The barrier's guarantee holds in continuous time; over a step the projected point
//! moves along a curve, not the straight segment the holonomic argument covers, so a
//! move may cut into a margin: the recorder and the safety monitor check every move and
//! refuse those, as for any controller.

use crate::control::kinematics::UnicycleLimits;
use crate::control::vocabulary::{Body, Move};
use crate::geometry::{Point, Pose, Vector, wrap_angle_rad};

use super::{CbfController, HalfPlane, solve_qp_2d, step_status};

/// The most the arc of a unicycle's barrier step turns along one published chord,
/// radians: its chords come within `c/2 tan(a/4)` of the arc (about 1 % of the chord).
pub const ARC_CHORD_TURN_RAD: f64 = std::f64::consts::PI / 32.0;

/// How much of the step a barrier move may take at most: below 1 by far more than the
/// rounding of the check that reads it back.
const STEP_SHARE: f64 = 1.0 - 1e-9;

impl CbfController {
    /// Plan the move of a unicycle agent standing at `me` facing `heading_rad` while every
    /// `other` body stands still: the barrier on its projected point, mapped to a speed
    /// and a turn rate, for one step within `limits` (see the module documentation). It
    /// stays ([`crate::control::vocabulary::MoveStatus::Stayed`]) when the QP is infeasible. With
    /// `align` (the centre's heading, for `align_heading`), within the projection
    /// distance of its slot it turns in place towards `align` instead.
    pub fn plan_unicycle_move(
        &self,
        centre: &Pose,
        me: &Point,
        heading_rad: f64,
        others: &[Body],
        limits: &UnicycleLimits,
        align: Option<f64>,
    ) -> Move {
        let slot = self.slot_position(centre);
        let (drive_m, turn_rad) = match align {
            Some(goal_rad) if (slot - me).norm() <= self.radius_m => {
                let most_rad = STEP_SHARE * limits.max_turn_rad;
                (
                    0.0,
                    wrap_angle_rad(goal_rad - heading_rad).clamp(-most_rad, most_rad),
                )
            }
            _ => self
                .unicycle_step(&slot, me, heading_rad, others, limits)
                .unwrap_or((0.0, 0.0)),
        };
        let waypoints = unicycle_arc(me, heading_rad, drive_m, turn_rad);
        let best = waypoints.last().copied().unwrap_or(*me);
        Move {
            end_heading_rad: Some(wrap_angle_rad(heading_rad + turn_rad)),
            slot,
            best,
            status: step_status(&slot, me, &best),
            waypoints,
        }
    }

    /// The distance driven (negative: backwards) and the turn of one step, or `None`
    /// when the QP is infeasible.
    fn unicycle_step(
        &self,
        slot: &Point,
        me: &Point,
        heading_rad: f64,
        others: &[Body],
        limits: &UnicycleLimits,
    ) -> Option<(f64, f64)> {
        let projection_m = self.radius_m;
        let e = Vector::new(heading_rad.cos(), heading_rad.sin());
        let n = Vector::new(-e.y, e.x);
        let ahead = me + projection_m * e;
        // In the frame (e, n): w = (v, l w).
        let in_frame = |u: &Vector| Vector::new(u.dot(&e), u.dot(&n));
        let mut rows: Vec<HalfPlane> = self
            .constraints_for_disk(&ahead, self.radius_m + projection_m, others)
            .iter()
            .map(|row| HalfPlane::new(in_frame(&row.a), row.b))
            .collect();
        if !limits.reverse {
            rows.push(HalfPlane::new(Vector::new(-1.0, 0.0), 0.0));
        }
        let nominal = in_frame(&self.settings.nominal(slot, me));
        let w = solve_qp_2d(&nominal, &rows).ok()?;
        let dt_s = self.settings.dt_s;
        let (drive_m, turn_rad) = (w.x * dt_s, w.y / projection_m * dt_s);
        let share = drive_m.abs() / limits.max_step_m + turn_rad.abs() / limits.max_turn_rad;
        let scale = if share > STEP_SHARE {
            STEP_SHARE / share
        } else {
            1.0
        };
        Some((drive_m * scale, turn_rad * scale))
    }
}

/// The points of the arc a unicycle drives from `from` facing `heading_rad`, `drive_m`
/// along (negative: backwards) while turning by `turn_rad`, as chords of at most
/// [`ARC_CHORD_TURN_RAD`] each; just `from` when it does not drive.
///
/// ```
/// use shared::control::cbf::unicycle_arc;
/// use shared::geometry::Point;
/// // A quarter circle of radius 1 to the left, from facing +x.
/// let pi_2 = std::f64::consts::FRAC_PI_2;
/// let arc = unicycle_arc(&Point::new(0.0, 0.0), 0.0, pi_2, pi_2);
/// assert_eq!(arc.len(), 17, "16 chords of pi/32");
/// let end = arc.last().unwrap();
/// assert!((end - Point::new(1.0, 1.0)).norm() < 1e-12);
/// ```
pub fn unicycle_arc(from: &Point, heading_rad: f64, drive_m: f64, turn_rad: f64) -> Vec<Point> {
    if drive_m == 0.0 || !drive_m.is_finite() || !turn_rad.is_finite() {
        return vec![*from];
    }
    let chords = (turn_rad.abs() / ARC_CHORD_TURN_RAD).ceil().max(1.0) as usize;
    let mut points = Vec::with_capacity(chords + 1);
    points.push(*from);
    for k in 1..=chords {
        let t = k as f64 / chords as f64;
        // The chord from `from` to the arc's point at `t`: it turns half as much as the
        // arc, and is `sinc` of that shorter than the arc (no division by a small turn).
        let half_rad = 0.5 * turn_rad * t;
        let sinc = if half_rad.abs() < 1e-4 {
            1.0 - half_rad * half_rad / 6.0
        } else {
            half_rad.sin() / half_rad
        };
        let (sin, cos) = (heading_rad + half_rad).sin_cos();
        let offset = Vector::new(cos, sin) * (drive_m * t * sinc);
        points.push(from + offset);
    }
    points
}
