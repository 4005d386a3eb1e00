//! The paper's failed zeroing barrier with a LogSumExp-smoothed max, kept for comparison.

use crate::control::vocabulary::{AgentSpec, Body, CbfSettings, CbfSettingsError, Move};
use crate::geometry::{Disk, Field, Point, Pose, Vector};

use super::*;

/// The paper's failed zeroing barrier (its section IV.C), reproduced for comparison only.
/// **Unsafe by design**: its moves can overlap obstacles; the coordinator's safety monitor
/// rejects them, and the comparison counts how often.
///
/// One barrier for the agent, `h_i = -max_j (r_i + r_j - ||x_i - s_j||)`, over every sensed
/// obstacle and agent (the paper's `Sigma`) and, so that the body stays in the field, the
/// four edges as four more terms `r_i - inset` (with the inward normal as gradient), with
/// the max replaced by the LogSumExp smooth max
/// `(1/k) ln sum_j exp(k g_j)`, `g_j = r_i + r_j - ||x_i - s_j||`, `k` the sharpness.
/// A single constraint `grad h . u >= -gamma h` (i.e. `-grad h . u <= gamma h`), the same
/// nominal velocity, settings and time step as [`CbfController`].
///
/// Why it fails. LogSumExp over-approximates the max, so `h` is a lower bound of the true
/// signed clearance; what breaks is the constraint built from it: `grad h` is the
/// softmax-weighted *average* `sum_j w_j n_j` of the unit directions away from the
/// neighbours, so moving away from the nearest neighbour earns credit that pays for
/// rushing at another one, and `h` (a smoothed minimum of distances) is not convex,
/// so its first-order condition gives no bound along a finite step. A straight step of
/// length `dt |u|` overshoots `h = 0` and enters an obstacle. With one neighbour only it
/// reduces to `h = ||x - s|| - R`, convex, and is safe.
#[derive(Clone, Debug)]
pub struct ZcbfLogSumExpController {
    /// The agent, its field and obstacles, as the safe controller holds them.
    base: CbfController,
    sharpness_per_m: f64,
}

impl ZcbfLogSumExpController {
    /// The controller of agent `spec` in `field` among `obstacles` (true radii), with the
    /// LogSumExp sharpness `sharpness_per_m` (see
    /// [`DEFAULT_LSE_SHARPNESS_PER_M`](crate::control::vocabulary::DEFAULT_LSE_SHARPNESS_PER_M)).
    /// The settings are checked as for [`CbfController`]: it fails even with settings that
    /// make the CBF safe.
    pub fn new(
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
        settings: CbfSettings,
        sharpness_per_m: f64,
    ) -> Result<Self, CbfSettingsError> {
        let base = CbfController::new(field, obstacles, spec, settings)?;
        if !(sharpness_per_m.is_finite() && sharpness_per_m > 0.0) {
            return Err(CbfSettingsError::NotPositive {
                name: "sharpness_per_m",
                value: sharpness_per_m,
            });
        }
        Ok(Self {
            base,
            sharpness_per_m,
        })
    }

    /// This agent's radius, in metres.
    pub fn radius_m(&self) -> f64 {
        self.base.radius_m
    }

    /// The ideal slot when the centre is at `centre`.
    pub fn slot_position(&self, centre: &Pose) -> Point {
        self.base.slot.ideal_position(centre)
    }

    /// The barrier at `me` and its gradient: `(h, grad h)`; `None` when nothing is sensed.
    pub fn barrier(&self, me: &Point, others: &[Body]) -> Option<(f64, Vector)> {
        let sensing_m = self.base.settings.sensing_radius_m;
        // (g_j = overlap depth, unit direction away from j)
        let mut terms: Vec<(f64, Vector)> = Vec::new();
        let edges = [
            (me.x, Vector::new(1.0, 0.0)),
            (self.base.field.width_m - me.x, Vector::new(-1.0, 0.0)),
            (me.y, Vector::new(0.0, 1.0)),
            (self.base.field.height_m - me.y, Vector::new(0.0, -1.0)),
        ];
        for (inset_m, inward) in edges {
            if inset_m <= sensing_m {
                terms.push((self.base.radius_m - inset_m, inward));
            }
        }
        for (centre, radius_m) in sensed(&self.base.obstacles, others, me, sensing_m) {
            let away = me - centre;
            let distance_m = away.norm();
            let direction = if distance_m > 0.0 {
                away / distance_m
            } else {
                Vector::zeros()
            };
            terms.push((self.base.radius_m + radius_m - distance_m, direction));
        }
        let top = terms.iter().map(|t| t.0).fold(f64::NEG_INFINITY, f64::max);
        if terms.is_empty() || !top.is_finite() {
            return None;
        }
        let k = self.sharpness_per_m;
        let weights: Vec<f64> = terms.iter().map(|t| (k * (t.0 - top)).exp()).collect();
        let total: f64 = weights.iter().sum();
        let smooth_max_m = top + total.ln() / k;
        let gradient = terms
            .iter()
            .zip(&weights)
            .fold(Vector::zeros(), |g, (t, w)| g + (w / total) * t.1);
        Some((-smooth_max_m, gradient))
    }

    /// The velocity chosen at `me` towards `slot`: the single-constraint QP's solution,
    /// capped at the maximum speed.
    pub fn velocity(&self, slot: &Point, me: &Point, others: &[Body]) -> Result<Vector, QpError> {
        let u_nom = self.base.settings.nominal(slot, me);
        let rows: Vec<HalfPlane> = self
            .barrier(me, others)
            .map(|(h, gradient)| HalfPlane::new(-gradient, self.base.settings.gamma_per_s * h))
            .into_iter()
            .collect();
        Ok(self.base.settings.capped(solve_qp_2d(&u_nom, &rows)?))
    }

    /// Plan this agent's move (same interface as [`CbfController::plan_move`]). **Unsafe**:
    /// the step may overlap an obstacle or agent.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        let slot = self.slot_position(centre);
        let u = self.velocity(&slot, me, others).ok();
        step_move(slot, me, u, self.base.settings.dt_s)
    }
}
