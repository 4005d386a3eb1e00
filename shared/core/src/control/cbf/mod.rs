//! CBF-QP mode: a control barrier function controller for single-integrator agents
//! (`x' = u`), and, for comparison only, a reproduction of the paper's failed zeroing
//! barrier with a LogSumExp-smoothed max (section IV.C of the paper "Collision Avoidance
//! and Formation Control").
//!
//! # The safe controller ([`CbfController`])
//!
//! Each turn the agent picks the velocity closest to a nominal one,
//! `u_nom = gain * (slot - x_i)` saturated at the maximum speed, subject to one linear
//! constraint per sensed neighbour `j` (obstacle or other agent, centre `s_j`):
//!
//! ```text
//! h_ij(x) = ||x - s_j||^2 - (r_i + r_j + m)^2          (m = CBF_MARGIN_M)
//! -2 (x_i - s_j) . u <= gamma * h_ij(x_i)
//! ```
//!
//! (the whole responsibility for every body, mates included: they stand still during the
//! turn, or cannot reach the agent within the step in a parallel group).
//!
//! and one per field edge (`h = x - r_i - m >= 0` gives `-u_x <= gamma * h`, and so on).
//! The quadratic programme is solved exactly by [`solve_qp_2d`], and the agent moves along
//! the straight segment `x_i -> x_i + dt * u` (a turn is [`CbfSettings::substeps`] such
//! pieces, each solved again where the last ended).
//!
//! **Why the whole segment is safe, not only its end.** Along the segment,
//! `h(x + t u) = h + 2 t (x - s).u + t^2 |u|^2 >= h + 2 t (x - s).u >= h - t gamma h`,
//! so `h(x + t u) >= h (1 - gamma t) >= 0` for every `t` in `[0, dt]` as soon as
//! `h >= 0` and `gamma * dt <= 1` (which [`CbfSettings::validate`] enforces). For the
//! edges, `h` is linear and the same bound holds with equality. If the agent starts in the
//! thin band `-m < clearance < 0` of the inflated barrier (`h < 0`, true bodies still
//! apart), the constraint forces `h` to grow and the same inequality gives
//! `h(x + t u) >= h`: the distance never shrinks. The margin `m` absorbs rounding, so
//! rounding never shows up as a violation of the true invariant `||p_a - p_b|| >= r_a + r_b`.
//! Neighbours farther than the sensing radius cannot be reached in one step because the
//! controller refuses a sensing radius shorter than the agent's radius plus one step at
//! maximum speed, and the step never exceeds the maximum speed (a solution faster than
//! it, possible only in the band, is scaled down, which keeps every constraint's
//! guarantee).
//!
//! `u = 0` satisfies every constraint whenever the current state is safe, so the QP is
//! then feasible; an infeasible QP (only from an unsafe or non-finite state) makes the
//! agent stay put with [`MoveStatus::Stayed`].
//!
//! Like every CBF with a nominal controller, the plain filter can *deadlock*: an agent whose
//! slot lies straight behind an obstacle slows down in front of it and stops (see
//! [`is_deadlocked`]); off the axis it slides around the obstacle. The deadlock escape
//! ([`CbfSettings::deadlock_escape`], on by default) takes it round: a piece stalled
//! under [`CBF_STALL_SHARE`](crate::control::vocabulary::CBF_STALL_SHARE) of the nominal speed
//! solves the same QP again for the nominal turned a quarter turn clockwise and moves that
//! way if it is faster. Any solution of these rows keeps the guarantee above, so the
//! escape is as safe. An agent whose slot lies inside an obstacle keeps sliding round the
//! obstacle's edge instead of resting in front of it (the deviation is the same; a guard
//! against it, no escape where the slot cannot be stood on, took the benefit away too:
//! capped dense 0.137 -> 7.50 m mean deviation, as the formation's slots pass through
//! obstacles and come out the other side).
//!
//! # Differential-drive agents (`projection.rs`)
//!
//! For a unicycle agent the same barrier acts on a point a projection distance ahead of
//! the robot, whose velocity maps to a forward speed and a turn rate at once (the
//! Robotarium's way: [`CbfController::plan_unicycle_move`]).
//!
//! # The failed barrier ([`ZcbfLogSumExpController`])
//!
//! The paper used a single barrier `h_i = -max_j (r_i + r_j - ||x_i - s_j||)` with the
//! max replaced by its LogSumExp smoothing. It is kept here, unsafe by design, so that the
//! comparison can show how often its moves break the invariant.

mod controller;
mod logsumexp;
mod projection;
mod qp;

pub use controller::CbfController;
pub use logsumexp::ZcbfLogSumExpController;
pub use projection::{ARC_CHORD_TURN_RAD, unicycle_arc};
pub use qp::{HalfPlane, QpError, solve_qp_2d};

use std::ops::ControlFlow;

use crate::control::vocabulary::{Body, CbfSettings, Move, MoveStatus};
use crate::geometry::{DiskGrid, Point, Vector};

/// An agent within this distance of its slot, in metres, is at its slot.
pub const AT_SLOT_TOLERANCE_M: f64 = 1e-9;

/// A move shorter than this, in metres, counts as no motion for [`is_deadlocked`].
pub const DEADLOCK_STEP_M: f64 = 1e-9;

// The nominal controller of the barrier controllers, private to them.
impl CbfSettings {
    /// The nominal velocity towards `slot` from `me`, saturated at the maximum speed.
    pub(super) fn nominal(&self, slot: &Point, me: &Point) -> Vector {
        let u = self.gain_per_s * (slot - me);
        let speed = u.norm();
        if speed > self.max_speed_m_per_s {
            u * (self.max_speed_m_per_s / speed)
        } else {
            u
        }
    }

    /// Cap a chosen velocity at the maximum speed (scaling towards zero).
    pub(super) fn capped(&self, u: Vector) -> Vector {
        let speed = u.norm();
        if speed > self.max_speed_m_per_s {
            u * (self.max_speed_m_per_s / speed)
        } else {
            u
        }
    }
}

/// Whether an agent standing at `me` that made move `mv` is deadlocked: it neither moved
/// (by more than [`DEADLOCK_STEP_M`]) nor is at its slot (within
/// [`AT_SLOT_TOLERANCE_M`]). Works for moves of any controller.
pub fn is_deadlocked(mv: &Move, me: &Point) -> bool {
    (mv.best - me).norm() <= DEADLOCK_STEP_M && (mv.slot - mv.best).norm() > AT_SLOT_TOLERANCE_M
}

/// The status of a barrier step from `me` to `best` towards `slot`: at the slot, stayed
/// (no motion), or deviated.
pub(super) fn step_status(slot: &Point, me: &Point, best: &Point) -> MoveStatus {
    if (slot - best).norm() <= AT_SLOT_TOLERANCE_M {
        MoveStatus::AtSlot
    } else if best == me {
        MoveStatus::Stayed
    } else {
        MoveStatus::Deviated
    }
}

/// The move of an agent at `me` with velocity `u` (or staying when `u` is `None`).
pub(super) fn step_move(slot: Point, me: &Point, u: Option<Vector>, dt_s: f64) -> Move {
    let best = match u {
        Some(u) if u != Vector::zeros() => me + dt_s * u,
        _ => *me,
    };
    let status = step_status(&slot, me, &best);
    let waypoints = if best == *me {
        vec![*me]
    } else {
        vec![*me, best]
    };
    Move {
        end_heading_rad: None,
        slot,
        best,
        status,
        waypoints,
    }
}

/// The obstacles and other agents sensed from `me`: every body with a point within
/// `sensing_radius_m` of `me`, obstacles first (in grid order), then `others` (in order),
/// as (centre, radius).
pub(super) fn sensed(
    obstacles: &DiskGrid,
    others: &[Body],
    me: &Point,
    sensing_radius_m: f64,
) -> Vec<(Point, f64)> {
    let mut out = Vec::new();
    let _ = obstacles.visit_near(me, sensing_radius_m, |_, d| {
        if (me - d.centre).norm() - d.radius_m <= sensing_radius_m {
            out.push((d.centre, d.radius_m));
        }
        ControlFlow::<()>::Continue(())
    });
    for o in others {
        if (me - o.position).norm() - o.radius_m <= sensing_radius_m {
            out.push((o.position, o.radius_m));
        }
    }
    out
}

#[cfg(test)]
mod tests;
