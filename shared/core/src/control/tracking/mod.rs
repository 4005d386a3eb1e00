//! Tracking a moving slot under a top speed: where an agent aims this turn, knowing where
//! its slot will be over the next steps.
//!
//! The centre's path is planned before the formation moves (the paper's Assumption 7),
//! so an agent knows where its slot will be at each of the next steps. An agent with a
//! top speed `c` that cannot keep up (the formation turns and the outer slots sweep
//! faster than `c`) does better than chasing where its slot is now: it heads for where
//! the slot will be, cuts the corner and starts early. The least summed deviation over
//! the next steps,
//!
//! ```text
//! minimise   sum_j |x_j - s_j|          j = 0 .. n-1 (s_j: the slot j steps after this one)
//! subject to |x_j - x_(j-1)| <= c        x_(-1): where the agent stands
//! ```
//!
//! is a convex problem; [`lead_point`] solves it approximately (a fixed number of ADMM
//! iterations, so the answer depends on the inputs alone, bit for bit) and returns the
//! first move's end `x_0`: the point the agent aims at this turn. The aim only chooses a
//! goal: the agent still moves to the best point of that goal along a collision-free
//! path, cut at its top speed, so safety does not depend on it.

use crate::geometry::{Point, Vector};

mod lattice;
mod round_obstacles;

pub use lattice::{Lattice, best_track_on_lattice};
pub use round_obstacles::{
    LaterSpaces, ROUND_FIRST_SPACING_RADII, ROUND_SPACING_RADII, ROUND_WINDOW_RADII,
    first_move_round_obstacles, round_lattice_for, track_round_obstacles,
};

/// The largest look-ahead, in steps, a scenario may ask for (`[formation]
/// horizon_steps`): the turn message carries this many future centre poses at most.
pub const MAX_HORIZON_STEPS: usize = 32;

/// The look-ahead, in steps, of a scenario that does not set `[formation]
/// horizon_steps`.
pub const DEFAULT_HORIZON_STEPS: usize = 10;

/// ADMM iterations of [`lead_point`]: enough for the first move to settle within a few
/// millimetres on the scenarios measured (it only picks a goal).
const ADMM_ITERATIONS: usize = 150;

/// The point an agent standing at `me` with top speed `max_step_m` aims at this turn,
/// when its slot will be at `slots[j]` after `j + 1` moves (`slots[0]`: this turn's
/// slot).
///
/// When the agent can follow its slot exactly (it reaches `slots[0]` this turn and no
/// later slot moves farther than `max_step_m` in a step), this is `slots[0]` itself, bit
/// for bit; otherwise it is the first point of the least-deviation track over the
/// slots, at most `max_step_m` from `me`. Without slots, or with a top speed that is not
/// a positive finite number, it is `slots[0]` (or `me`).
///
/// ```
/// use shared::geometry::Point;
/// use shared::control::tracking::lead_point;
/// // The slot turns a corner faster than the agent can move: from (0, 0) it goes up,
/// // then right at 1 m a step; the agent (0.6 m a step) cuts the corner.
/// let slots: Vec<Point> =
///     [(0.0, 1.0), (1.0, 1.0), (2.0, 1.0), (3.0, 1.0)].map(|(x, y)| Point::new(x, y)).to_vec();
/// let me = Point::new(0.0, 0.0);
/// let aim = lead_point(&me, &slots, 0.6);
/// assert!((aim - me).norm() <= 0.6 + 1e-9);
/// assert!(aim.x > 0.05, "it leans towards where the slot is going: {aim}");
/// // A slot it can follow is aimed at exactly.
/// let easy = [Point::new(0.3, 0.0), Point::new(0.6, 0.0)];
/// assert_eq!(lead_point(&me, &easy, 0.5), easy[0]);
/// ```
pub fn lead_point(me: &Point, slots: &[Point], max_step_m: f64) -> Point {
    let Some(&first) = slots.first() else {
        return *me;
    };
    if !(max_step_m.is_finite() && max_step_m > 0.0) {
        return first;
    }
    let followable = (first - me).norm() <= max_step_m
        && slots.windows(2).all(|w| (w[1] - w[0]).norm() <= max_step_m);
    if followable {
        return first;
    }
    let track = least_deviation_track(me, slots, max_step_m, ADMM_ITERATIONS);
    // Kept a hair inside the top speed, so that rounding never takes it beyond.
    track.first().map_or(first, |x| {
        me + clamp_norm(x - me, max_step_m * (1.0 - 1e-9))
    })
}

/// An approximately least-deviation track from `me` through `slots` (see the module
/// documentation): `iterations` rounds of ADMM on the splitting `e_j = x_j - s_j` (cost
/// `|e_j|`), `d_j = x_j - x_(j-1)` (kept in the disk of radius `max_step_m`); each
/// point of the answer is `x_(j-1) + d_j`, so every step of it is within the top speed.
pub fn least_deviation_track(
    me: &Point,
    slots: &[Point],
    max_step_m: f64,
    iterations: usize,
) -> Vec<Point> {
    let n = slots.len();
    if n == 0 {
        return Vec::new();
    }
    // The penalty: about one over the distances at play.
    let rho = 1.0 / max_step_m;
    let zero = Vector::zeros();
    // Start from the slots, clamped to the speed (a feasible track).
    let mut x: Vec<Point> = Vec::with_capacity(n);
    let mut prev = *me;
    for s in slots {
        let p = prev + clamp_norm(s - prev, max_step_m);
        x.push(p);
        prev = p;
    }
    let mut e: Vec<Vector> = x.iter().zip(slots).map(|(p, s)| p - s).collect();
    let mut d: Vec<Vector> = (0..n)
        .map(|j| x[j] - if j == 0 { *me } else { x[j - 1] })
        .collect();
    let mut u = vec![zero; n];
    let mut w = vec![zero; n];
    let solver = Tridiagonal::new(n);
    let mut rhs = vec![zero; n];
    for _ in 0..iterations {
        // x: the least squares (I + D'D) x = (s + e - u) + D'(d - w), x_(-1) = me.
        for j in 0..n {
            let a = slots[j].coords + e[j] - u[j];
            let here = d[j] - w[j];
            let next = if j + 1 < n { d[j + 1] - w[j + 1] } else { zero };
            rhs[j] = a + here - next;
        }
        rhs[0] += me.coords;
        let solved = solver.solve(&rhs);
        for (p, v) in x.iter_mut().zip(&solved) {
            *p = Point::from(*v);
        }
        for j in 0..n {
            let before = if j == 0 { *me } else { x[j - 1] };
            e[j] = shrink(x[j] - slots[j] + u[j], 1.0 / rho);
            d[j] = clamp_norm(x[j] - before + w[j], max_step_m);
            u[j] += x[j] - slots[j] - e[j];
            w[j] += x[j] - before - d[j];
        }
    }
    // The feasible track the step variables describe.
    let mut track = Vec::with_capacity(n);
    let mut prev = *me;
    for dj in &d {
        prev += *dj;
        track.push(prev);
    }
    track
}

/// The summed deviation `sum_j |track_j - slots_j|`.
pub fn track_deviation_m(track: &[Point], slots: &[Point]) -> f64 {
    track.iter().zip(slots).map(|(p, s)| (p - s).norm()).sum()
}

/// `v` shortened to at most `max` long.
fn clamp_norm(v: Vector, max: f64) -> Vector {
    let len = v.norm();
    if len > max { v * (max / len) } else { v }
}

/// The proximal step of the Euclidean norm: `v` shortened by `by` (zero when shorter).
fn shrink(v: Vector, by: f64) -> Vector {
    let len = v.norm();
    if len > by {
        v * (1.0 - by / len)
    } else {
        Vector::zeros()
    }
}

/// The factored matrix `I + D'D` of the track's least squares: 3 on the diagonal (2 in
/// the last row, which has no step after it), -1 beside it.
struct Tridiagonal {
    /// The modified upper diagonal of the Thomas algorithm.
    upper: Vec<f64>,
    /// The inverse of each modified pivot.
    pivot_inv: Vec<f64>,
}

impl Tridiagonal {
    fn new(n: usize) -> Self {
        let diag = |j: usize| if j + 1 < n { 3.0 } else { 2.0 };
        let mut upper = vec![0.0; n];
        let mut pivot_inv = vec![0.0; n];
        let mut prev_upper = 0.0;
        for j in 0..n {
            // Row j: -1 x_(j-1) + diag x_j - 1 x_(j+1); the sub-diagonal -1 times the
            // previous modified upper entry comes off the diagonal.
            let pivot = diag(j) + prev_upper;
            pivot_inv[j] = 1.0 / pivot;
            upper[j] = if j + 1 < n { -pivot_inv[j] } else { 0.0 };
            prev_upper = upper[j];
        }
        Self { upper, pivot_inv }
    }

    fn solve(&self, rhs: &[Vector]) -> Vec<Vector> {
        let n = rhs.len();
        let mut y = Vec::with_capacity(n);
        let mut prev = Vector::zeros();
        for (r, inv) in rhs.iter().zip(&self.pivot_inv) {
            // Forward: y_j = (r_j + y_(j-1)) / pivot_j (the sub-diagonal is -1).
            let v = (r + prev) * *inv;
            y.push(v);
            prev = v;
        }
        for j in (0..n.saturating_sub(1)).rev() {
            let next = y[j + 1];
            y[j] -= next * self.upper[j];
        }
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The track's least squares is solved exactly: (I + D'D) x = rhs.
    #[test]
    fn the_tridiagonal_solve_inverts_the_matrix() {
        for n in 1..8 {
            let rhs: Vec<Vector> = (0..n)
                .map(|j| Vector::new(j as f64 * 0.7 - 1.0, (j * j) as f64 * 0.1))
                .collect();
            let x = Tridiagonal::new(n).solve(&rhs);
            for j in 0..n {
                let diag = if j + 1 < n { 3.0 } else { 2.0 };
                let mut back = x[j] * diag;
                if j > 0 {
                    back -= x[j - 1];
                }
                if j + 1 < n {
                    back -= x[j + 1];
                }
                assert!((back - rhs[j]).norm() < 1e-12, "n {n} row {j}");
            }
        }
    }

    /// A slot running away faster than the agent: the best track runs straight after it
    /// at full speed, and the lead point is a full step towards it.
    #[test]
    fn a_runaway_slot_is_chased_at_full_speed() {
        let me = Point::new(0.0, 0.0);
        let slots: Vec<Point> = (1..=6).map(|j| Point::new(2.0 * j as f64, 0.0)).collect();
        let aim = lead_point(&me, &slots, 0.5);
        assert!((aim - Point::new(0.5, 0.0)).norm() < 1e-3, "{aim}");
    }

    /// Every step of the track keeps the top speed, and its deviation is no worse than
    /// chasing the slot greedily.
    #[test]
    fn the_track_keeps_the_speed_and_beats_the_chase() {
        let me = Point::new(0.0, 0.0);
        // A slot on a circle of radius 5 m, 0.3 rad a step: 1.5 m a step, cap 0.8 m.
        let slots: Vec<Point> = (1..=12)
            .map(|j| {
                let a = 0.3 * j as f64;
                Point::new(5.0 * a.cos() - 5.0, 5.0 * a.sin())
            })
            .collect();
        let track = least_deviation_track(&me, &slots, 0.8, ADMM_ITERATIONS);
        let mut prev = me;
        for p in &track {
            assert!((p - prev).norm() <= 0.8 + 1e-12);
            prev = *p;
        }
        let mut chase = Vec::new();
        let mut at = me;
        for s in &slots {
            at += clamp_norm(s - at, 0.8);
            chase.push(at);
        }
        let (ours, greedy) = (
            track_deviation_m(&track, &slots),
            track_deviation_m(&chase, &slots),
        );
        assert!(ours < greedy, "track {ours} against the chase {greedy}");
    }
}
