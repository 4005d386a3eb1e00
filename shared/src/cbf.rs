//! CBF-QP mode: a control barrier function planner for single-integrator agents
//! (`x' = u`), and, for comparison only, a reproduction of the paper's failed zeroing
//! barrier with a LogSumExp-smoothed max (section IV.C of the paper "Collision Avoidance
//! and Formation Control").
//!
//! # The safe planner ([`CbfPlanner`])
//!
//! Each turn the agent picks the velocity closest to a nominal one,
//! `u_nom = gain * (slot - x_i)` saturated at the maximum speed, subject to one linear
//! constraint per sensed neighbour `j` (obstacle or other agent, centre `s_j`):
//!
//! ```text
//! h_ij(x) = ||x - s_j||^2 - (r_i + r_j + m)^2          (m = CBF_MARGIN_M)
//! -2 (x_i - s_j) . u <= gamma * w_j * h_ij(x_i)        (w_j = 1 obstacles, 1/2 agents)
//! ```
//!
//! and one per field edge (`h = x - r_i - m >= 0` gives `-u_x <= gamma * h`, and so on).
//! The quadratic programme is solved exactly by [`solve_qp_2d`], and the agent moves for
//! one time step along the straight segment `x_i -> x_i + dt * u`.
//!
//! **Why the whole segment is safe, not only its end.** Along the segment,
//! `h(x + t u) = h + 2 t (x - s).u + t^2 |u|^2 >= h + 2 t (x - s).u >= h - t gamma w h`,
//! so `h(x + t u) >= h (1 - gamma w t) >= 0` for every `t` in `[0, dt]` as soon as
//! `h >= 0` and `gamma * dt <= 1` (which [`CbfSettings::validate`] enforces). For the
//! edges, `h` is linear and the same bound holds with equality. If the agent starts in the
//! thin band `-m < clearance < 0` of the inflated barrier (`h < 0`, true bodies still
//! apart), the constraint forces `h` to grow and the same inequality gives
//! `h(x + t u) >= h`: the distance never shrinks. The margin `m` absorbs rounding, so
//! rounding never shows up as a violation of the true invariant `||p_a - p_b|| >= r_a + r_b`.
//! Neighbours farther than the sensing radius cannot be reached in one step because the
//! planner refuses a sensing radius shorter than the agent's radius plus one step at
//! maximum speed, and the step never exceeds the maximum speed (a solution faster than
//! it, possible only in the band, is scaled down, which keeps every constraint's
//! guarantee).
//!
//! `u = 0` satisfies every constraint whenever the current state is safe, so the QP is
//! then feasible; an infeasible QP (only from an unsafe or non-finite state) makes the
//! agent stay put with [`MoveStatus::Stayed`].
//!
//! Like every CBF with a nominal controller, this one can *deadlock*: an agent whose slot
//! lies straight behind an obstacle slows down in front of it and stops (see
//! [`is_deadlocked`]); off the axis it slides around the obstacle.
//!
//! # The failed barrier ([`ZcbfLogSumExpPlanner`])
//!
//! The paper used a single barrier `h_i = -max_j (r_i + r_j - ||x_i - s_j||)` with the
//! max replaced by its LogSumExp smoothing. It is kept here, unsafe by design, so that the
//! comparison can show how often its moves break the invariant.

use std::ops::ControlFlow;

use crate::formation::Slot;
use crate::geometry::{Disk, DiskGrid, Field, Point, Pose, Vector};
use crate::vocabulary::{
    AgentSpec, Body, CBF_MARGIN_M, CbfSettings, CbfSettingsError, Move, MoveStatus,
};

/// An agent within this distance of its slot, in metres, is at its slot.
pub const AT_SLOT_TOLERANCE_M: f64 = 1e-9;

/// A move shorter than this, in metres, counts as no motion for [`is_deadlocked`].
pub const DEADLOCK_STEP_M: f64 = 1e-9;

/// Relative slack of the QP's feasibility tests (times `1 + |b| + |u_nom|`, rows
/// normalised to unit normals). It absorbs rounding, about a thousand times
/// the rounding error of the operations involved.
const QP_RELATIVE_TOLERANCE: f64 = 1e-12;

/// A closed half-plane of velocities: `a . u <= b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfPlane {
    /// Normal of the boundary line (any length; zero makes the row `0 <= b`).
    pub a: Vector,
    /// Offset: the row is `a . u <= b`.
    pub b: f64,
}

impl HalfPlane {
    /// The half-plane `a . u <= b`.
    pub fn new(a: Vector, b: f64) -> Self {
        Self { a, b }
    }

    /// How far `u` breaks the row, `a . u - b` (negative or zero when it holds).
    pub fn violation(&self, u: &Vector) -> f64 {
        self.a.dot(u) - self.b
    }
}

/// Why [`solve_qp_2d`] found no solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum QpError {
    /// No velocity satisfies every constraint (including a degenerate row `0 <= b` with
    /// `b < 0`).
    #[error("the constraints admit no common point")]
    Infeasible,
    /// The nominal velocity or a constraint holds NaN or an infinite normal.
    #[error("the problem holds a NaN or an infinite value")]
    NotFinite,
}

/// Minimise `||u - u_nom||^2` subject to `a_k . u <= b_k` for every constraint, exactly.
///
/// In 2-D the optimum is `u_nom` itself, the projection of `u_nom` onto one constraint
/// line, or the intersection of two lines. The method is the incremental one (Seidel's,
/// with the constraints taken in the order given, no randomness, so the result is
/// bit-for-bit reproducible): keep the optimum of the first `k - 1` constraints; when it
/// breaks constraint `k`, the new optimum lies on line `k`, where it is a 1-D problem
/// (clamp the projection of `u_nom` into the interval the earlier constraints leave on
/// the line). Worst case `O(n^2)` for `n` constraints.
///
/// Rows are normalised to unit normals; each row is tested with a slack of
/// `1e-12 * (1 + |b| + |u_nom|)` (`b` normalised), which absorbs rounding: the result
/// breaks no normalised row by more than that. A row with `a = 0` is ignored when
/// `0 <= b` and makes the problem infeasible otherwise; `b = +inf` is ignored.
///
/// ```
/// use shared::cbf::{HalfPlane, solve_qp_2d};
/// use shared::geometry::Vector;
/// // Stay left of x = 1 and below y = 2; the nominal (3, 3) projects onto the corner.
/// let rows = [
///     HalfPlane::new(Vector::new(1.0, 0.0), 1.0),
///     HalfPlane::new(Vector::new(0.0, 1.0), 2.0),
/// ];
/// let u = solve_qp_2d(&Vector::new(3.0, 3.0), &rows).unwrap();
/// assert_eq!(u, Vector::new(1.0, 2.0));
/// ```
pub fn solve_qp_2d(u_nom: &Vector, constraints: &[HalfPlane]) -> Result<Vector, QpError> {
    if !(u_nom.x.is_finite() && u_nom.y.is_finite()) {
        return Err(QpError::NotFinite);
    }
    let nominal_scale = u_nom.x.abs().max(u_nom.y.abs());
    // (unit normal, offset, slack)
    let mut rows: Vec<(Vector, f64, f64)> = Vec::with_capacity(constraints.len());
    for c in constraints {
        if !(c.a.x.is_finite() && c.a.y.is_finite()) || c.b.is_nan() {
            return Err(QpError::NotFinite);
        }
        let largest = c.a.x.abs().max(c.a.y.abs());
        if largest == 0.0 {
            if c.b >= 0.0 {
                continue;
            }
            return Err(QpError::Infeasible);
        }
        // Divide by the largest component first: no overflow or underflow in the norm.
        let (ax, ay, b) = (c.a.x / largest, c.a.y / largest, c.b / largest);
        let norm = ax.hypot(ay);
        let (normal, offset) = (Vector::new(ax / norm, ay / norm), b / norm);
        if offset == f64::INFINITY {
            continue;
        }
        if offset == f64::NEG_INFINITY {
            return Err(QpError::Infeasible);
        }
        let slack = QP_RELATIVE_TOLERANCE * (1.0 + offset.abs() + nominal_scale);
        rows.push((normal, offset, slack));
    }

    let mut u = *u_nom;
    for k in 0..rows.len() {
        let (normal, offset, slack) = rows[k];
        if normal.dot(&u) - offset <= slack {
            continue;
        }
        // The optimum of rows 0..=k lies on line k: p(t) = foot + t * direction, where
        // foot is the projection of u_nom (t = 0 is the unconstrained optimum on the line).
        let foot = u_nom - (normal.dot(u_nom) - offset) * normal;
        let direction = Vector::new(-normal.y, normal.x);
        // The interval the earlier rows leave on the line: exact, and relaxed by their
        // slacks (which decides feasibility, so that rounding never makes it empty).
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        let (mut lo_relaxed, mut hi_relaxed) = (f64::NEG_INFINITY, f64::INFINITY);
        for &(n_j, d_j, s_j) in &rows[..k] {
            // n_j . (foot + t direction) <= d_j (+ s_j)
            let rate = n_j.dot(&direction);
            let room = d_j - n_j.dot(&foot);
            if rate > 0.0 {
                hi = hi.min(room / rate);
                hi_relaxed = hi_relaxed.min((room + s_j) / rate);
            } else if rate < 0.0 {
                lo = lo.max(room / rate);
                lo_relaxed = lo_relaxed.max((room + s_j) / rate);
            } else if room + s_j < 0.0 {
                // Parallel, and line k lies wholly outside row j.
                return Err(QpError::Infeasible);
            }
        }
        if lo_relaxed > hi_relaxed || lo_relaxed.is_nan() || hi_relaxed.is_nan() {
            return Err(QpError::Infeasible);
        }
        let t = if lo <= hi {
            0.0f64.clamp(lo, hi)
        } else {
            // Empty only by rounding: the middle of the gap, within the relaxed interval.
            (0.5 * (lo + hi)).clamp(lo_relaxed, hi_relaxed)
        };
        u = foot + t * direction;
    }
    Ok(u)
}

// The nominal controller of the barrier planners, private to them.
impl CbfSettings {
    /// The nominal velocity towards `slot` from `me`, saturated at the maximum speed.
    fn nominal(&self, slot: &Point, me: &Point) -> Vector {
        let u = self.gain_per_s * (slot - me);
        let speed = u.norm();
        if speed > self.max_speed_m_per_s {
            u * (self.max_speed_m_per_s / speed)
        } else {
            u
        }
    }

    /// Cap a chosen velocity at the maximum speed (scaling towards zero).
    fn capped(&self, u: Vector) -> Vector {
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
/// [`AT_SLOT_TOLERANCE_M`]). Works for moves of any planner.
pub fn is_deadlocked(mv: &Move, me: &Point) -> bool {
    (mv.best - me).norm() <= DEADLOCK_STEP_M && (mv.slot - mv.best).norm() > AT_SLOT_TOLERANCE_M
}

/// The move of an agent at `me` with velocity `u` (or staying when `u` is `None`).
fn step_move(slot: Point, me: &Point, u: Option<Vector>, dt_s: f64) -> Move {
    let best = match u {
        Some(u) if u != Vector::zeros() => me + dt_s * u,
        _ => *me,
    };
    let status = if (slot - best).norm() <= AT_SLOT_TOLERANCE_M {
        MoveStatus::AtSlot
    } else if best == *me {
        MoveStatus::Stayed
    } else {
        MoveStatus::Deviated
    };
    let waypoints = if best == *me {
        vec![*me]
    } else {
        vec![*me, best]
    };
    Move {
        slot,
        best,
        status,
        waypoints,
    }
}

/// The obstacles and other agents sensed from `me`: every body with a point within
/// `sensing_radius_m` of `me`, obstacles first (in grid order), then `others` (in order),
/// with whether it is an agent.
fn sensed(
    obstacles: &DiskGrid,
    others: &[Body],
    me: &Point,
    sensing_radius_m: f64,
) -> Vec<(Point, f64, bool)> {
    let mut out = Vec::new();
    let _ = obstacles.visit_near(me, sensing_radius_m, |_, d| {
        if (me - d.centre).norm() - d.radius_m <= sensing_radius_m {
            out.push((d.centre, d.radius_m, false));
        }
        ControlFlow::<()>::Continue(())
    });
    for o in others {
        if (me - o.position).norm() - o.radius_m <= sensing_radius_m {
            out.push((o.position, o.radius_m, true));
        }
    }
    out
}

/// The CBF-QP planner of one agent: one barrier constraint per sensed neighbour and per
/// field edge, an exact QP, one straight step of `dt` (see the module documentation for
/// the safety argument). Same turn interface as [`crate::turn::BestPointPlanner`].
#[derive(Clone, Debug)]
pub struct CbfPlanner {
    field: Field,
    slot: Slot,
    radius_m: f64,
    /// Static obstacles, true radii.
    obstacles: DiskGrid,
    settings: CbfSettings,
}

impl CbfPlanner {
    /// The planner of agent `spec` in `field` among `obstacles` (true radii), after
    /// checking `settings` for this agent ([`CbfSettings::validate_for_agent`]).
    pub fn new(
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
        settings: CbfSettings,
    ) -> Result<Self, CbfSettingsError> {
        settings.validate_for_agent(spec.radius_m)?;
        Ok(Self {
            field,
            slot: spec.slot,
            radius_m: spec.radius_m,
            obstacles: DiskGrid::new(obstacles.to_vec()),
            settings,
        })
    }

    /// This agent's radius, in metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The settings in use.
    pub fn settings(&self) -> &CbfSettings {
        &self.settings
    }

    /// The ideal slot when the centre is at `centre`.
    pub fn slot_position(&self, centre: &Pose) -> Point {
        self.slot.ideal_position(centre)
    }

    /// The safety constraints on the velocity of the agent at `me` (rows `a . u <= b`):
    /// the four field edges, then every sensed obstacle, then every sensed agent of
    /// `others` (half responsibility).
    pub fn constraints(&self, me: &Point, others: &[Body]) -> Vec<HalfPlane> {
        let gamma = self.settings.gamma_per_s;
        let inset_m = self.radius_m + CBF_MARGIN_M;
        let mut rows = vec![
            HalfPlane::new(Vector::new(-1.0, 0.0), gamma * (me.x - inset_m)),
            HalfPlane::new(
                Vector::new(1.0, 0.0),
                gamma * (self.field.width_m - inset_m - me.x),
            ),
            HalfPlane::new(Vector::new(0.0, -1.0), gamma * (me.y - inset_m)),
            HalfPlane::new(
                Vector::new(0.0, 1.0),
                gamma * (self.field.height_m - inset_m - me.y),
            ),
        ];
        for (centre, radius_m, is_agent) in
            sensed(&self.obstacles, others, me, self.settings.sensing_radius_m)
        {
            let away = me - centre;
            let reach_m = self.radius_m + radius_m + CBF_MARGIN_M;
            let distance_m = away.norm();
            // (d - R)(d + R) keeps its precision near the boundary, unlike d^2 - R^2.
            let h = (distance_m - reach_m) * (distance_m + reach_m);
            let share = if is_agent { 0.5 } else { 1.0 };
            rows.push(HalfPlane::new(-2.0 * away, gamma * share * h));
        }
        rows
    }

    /// The velocity chosen at `me` towards `slot`: the QP's solution, capped at the
    /// maximum speed.
    pub fn velocity(&self, slot: &Point, me: &Point, others: &[Body]) -> Result<Vector, QpError> {
        let u_nom = self.settings.nominal(slot, me);
        let u = solve_qp_2d(&u_nom, &self.constraints(me, others))?;
        Ok(self.settings.capped(u))
    }

    /// Plan this agent's move while every `other` body stands still: one step of `dt`
    /// at the CBF-QP velocity; stays put ([`MoveStatus::Stayed`]) when the QP is
    /// infeasible (only possible from an unsafe or non-finite state).
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        let slot = self.slot_position(centre);
        let u = self.velocity(&slot, me, others).ok();
        step_move(slot, me, u, self.settings.dt_s)
    }
}

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
/// nominal velocity, settings and time step as [`CbfPlanner`].
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
pub struct ZcbfLogSumExpPlanner {
    field: Field,
    slot: Slot,
    radius_m: f64,
    obstacles: DiskGrid,
    settings: CbfSettings,
    sharpness_per_m: f64,
}

impl ZcbfLogSumExpPlanner {
    /// The planner of agent `spec` in `field` among `obstacles` (true radii), with the
    /// LogSumExp sharpness `sharpness_per_m` (see
    /// [`DEFAULT_LSE_SHARPNESS_PER_M`](crate::vocabulary::DEFAULT_LSE_SHARPNESS_PER_M)).
    /// The settings are checked as for [`CbfPlanner`]: it fails even with settings that
    /// make the CBF safe.
    pub fn new(
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
        settings: CbfSettings,
        sharpness_per_m: f64,
    ) -> Result<Self, CbfSettingsError> {
        settings.validate_for_agent(spec.radius_m)?;
        if !(sharpness_per_m.is_finite() && sharpness_per_m > 0.0) {
            return Err(CbfSettingsError::NotPositive {
                name: "sharpness_per_m",
                value: sharpness_per_m,
            });
        }
        Ok(Self {
            field,
            slot: spec.slot,
            radius_m: spec.radius_m,
            obstacles: DiskGrid::new(obstacles.to_vec()),
            settings,
            sharpness_per_m,
        })
    }

    /// This agent's radius, in metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The ideal slot when the centre is at `centre`.
    pub fn slot_position(&self, centre: &Pose) -> Point {
        self.slot.ideal_position(centre)
    }

    /// The barrier at `me` and its gradient: `(h, grad h)`; `None` when nothing is sensed.
    pub fn barrier(&self, me: &Point, others: &[Body]) -> Option<(f64, Vector)> {
        let sensing_m = self.settings.sensing_radius_m;
        // (g_j = overlap depth, unit direction away from j)
        let mut terms: Vec<(f64, Vector)> = Vec::new();
        let edges = [
            (me.x, Vector::new(1.0, 0.0)),
            (self.field.width_m - me.x, Vector::new(-1.0, 0.0)),
            (me.y, Vector::new(0.0, 1.0)),
            (self.field.height_m - me.y, Vector::new(0.0, -1.0)),
        ];
        for (inset_m, inward) in edges {
            if inset_m <= sensing_m {
                terms.push((self.radius_m - inset_m, inward));
            }
        }
        for (centre, radius_m, _) in sensed(&self.obstacles, others, me, sensing_m) {
            let away = me - centre;
            let distance_m = away.norm();
            let direction = if distance_m > 0.0 {
                away / distance_m
            } else {
                Vector::zeros()
            };
            terms.push((self.radius_m + radius_m - distance_m, direction));
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
        let u_nom = self.settings.nominal(slot, me);
        let rows: Vec<HalfPlane> = self
            .barrier(me, others)
            .map(|(h, gradient)| HalfPlane::new(-gradient, self.settings.gamma_per_s * h))
            .into_iter()
            .collect();
        Ok(self.settings.capped(solve_qp_2d(&u_nom, &rows)?))
    }

    /// Plan this agent's move (same interface as [`CbfPlanner::plan_move`]). **Unsafe**:
    /// the step may overlap an obstacle or agent.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        let slot = self.slot_position(centre);
        let u = self.velocity(&slot, me, others).ok();
        step_move(slot, me, u, self.settings.dt_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_rows_are_ignored_or_infeasible() {
        let u = Vector::new(1.0, -2.0);
        let ok = [HalfPlane::new(Vector::zeros(), 0.0)];
        assert_eq!(solve_qp_2d(&u, &ok), Ok(u));
        let bad = [HalfPlane::new(Vector::zeros(), -1e-300)];
        assert_eq!(solve_qp_2d(&u, &bad), Err(QpError::Infeasible));
        let nan = [HalfPlane::new(Vector::new(f64::NAN, 1.0), 0.0)];
        assert_eq!(solve_qp_2d(&u, &nan), Err(QpError::NotFinite));
    }

    #[test]
    fn parallel_rows_and_single_point_sets() {
        let u = Vector::new(3.0, 3.0);
        // 1 <= x <= 1 and y <= 0: the set is a half-line.
        let rows = [
            HalfPlane::new(Vector::new(1.0, 0.0), 1.0),
            HalfPlane::new(Vector::new(-2.0, 0.0), -2.0),
            HalfPlane::new(Vector::new(0.0, 5.0), 0.0),
        ];
        assert_eq!(solve_qp_2d(&u, &rows), Ok(Vector::new(1.0, 0.0)));
        let empty = [
            HalfPlane::new(Vector::new(1.0, 0.0), 1.0),
            HalfPlane::new(Vector::new(-1.0, 0.0), -1.5),
        ];
        assert_eq!(solve_qp_2d(&u, &empty), Err(QpError::Infeasible));
    }
}
