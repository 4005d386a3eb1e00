//! The cone programme of `coordinator bound` (the module's doc says what it bounds):
//! one agent's least summed or largest deviation under its top speed and the floors, by
//! Clarabel.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use shared::geometry::Point;

use super::BoundError;

/// What is minimised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Objective {
    /// The summed deviation over the steps.
    Sum,
    /// The largest deviation of a step.
    Max,
}

/// The optimal track of one agent that starts at `start` and moves at most `max_step_m`
/// a step, its slot at step `k + 1` being `slots[k]` and its deviation there at least
/// `floors_m[k]` (none where the slice ends): the optimal value of `objective` (metres:
/// summed or largest deviation) and the track (`x_1 .. x_T`).
pub fn optimal_track(
    start: &Point,
    slots: &[Point],
    floors_m: &[f64],
    max_step_m: f64,
    objective: Objective,
) -> Result<(f64, Vec<Point>), BoundError> {
    if !(max_step_m.is_finite() && max_step_m > 0.0) {
        return Err(BoundError::BadSpeed(max_step_m));
    }
    let t = slots.len();
    if t == 0 {
        return Ok((0.0, Vec::new()));
    }
    // Variables: x_1, y_1, ..., x_T, y_T, then the deviations (T of them for a sum, one
    // for a maximum).
    let deviations = match objective {
        Objective::Sum => t,
        Objective::Max => 1,
    };
    let n = 2 * t + deviations;
    let dev_var = |k: usize| match objective {
        Objective::Sum => 2 * t + k,
        Objective::Max => 2 * t,
    };
    let mut q = vec![0.0; n];
    for v in q.iter_mut().skip(2 * t) {
        *v = 1.0;
    }
    // Rows: per step a deviation cone (t_k, x_k - s_k) and a speed cone
    // (c, x_k - x_(k-1)), each s = b - A z in the second-order cone of dimension 3.
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    let mut b = Vec::with_capacity(6 * t);
    let mut cones = Vec::with_capacity(2 * t);
    let mut entry = |r: usize, c: usize, v: f64| {
        rows.push(r);
        cols.push(c);
        vals.push(v);
    };
    for (k, s) in slots.iter().enumerate() {
        let r = 6 * k;
        entry(r, dev_var(k), -1.0);
        entry(r + 1, 2 * k, -1.0);
        entry(r + 2, 2 * k + 1, -1.0);
        b.extend([0.0, -s.x, -s.y]);
        entry(r + 4, 2 * k, -1.0);
        entry(r + 5, 2 * k + 1, -1.0);
        if k == 0 {
            b.extend([max_step_m, -start.x, -start.y]);
        } else {
            entry(r + 4, 2 * (k - 1), 1.0);
            entry(r + 5, 2 * (k - 1) + 1, 1.0);
            b.extend([max_step_m, 0.0, 0.0]);
        }
        cones.push(SupportedConeT::SecondOrderConeT(3));
        cones.push(SupportedConeT::SecondOrderConeT(3));
    }
    // Then the floors, t_k - f_k >= 0 (one row each, in the non-negative cone).
    let floors: Vec<(usize, f64)> = floors_m
        .iter()
        .take(t)
        .copied()
        .enumerate()
        .filter(|(_, f)| *f > 0.0)
        .collect();
    for (row, (k, floor_m)) in floors.iter().enumerate() {
        entry(6 * t + row, dev_var(*k), -1.0);
        b.push(-floor_m);
    }
    if !floors.is_empty() {
        cones.push(SupportedConeT::NonnegativeConeT(floors.len()));
    }
    let a = CscMatrix::new_from_triplets(6 * t + floors.len(), n, rows, cols, vals);
    let p = CscMatrix::zeros((n, n));
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .map_err(|e| BoundError::NotSolved(e.to_string()))?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| BoundError::NotSolved(format!("{e:?}")))?;
    solver.solve();
    let sol = &solver.solution;
    if sol.status != SolverStatus::Solved {
        return Err(BoundError::NotSolved(format!("{:?}", sol.status)));
    }
    let track = (0..t)
        .map(|k| Point::new(sol.x[2 * k], sol.x[2 * k + 1]))
        .collect();
    // The dual objective bounds the optimum from below; at an optimum the two agree
    // to the solver's tolerance, and the lower one is reported.
    Ok((sol.obj_val.min(sol.obj_val_dual).max(0.0), track))
}
