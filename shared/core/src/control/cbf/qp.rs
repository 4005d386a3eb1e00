//! The exact 2-D quadratic programme of the barrier controllers: the velocity closest to a
//! nominal one inside a set of half-planes.

use crate::geometry::Vector;

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
/// use shared::control::cbf::{HalfPlane, solve_qp_2d};
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
