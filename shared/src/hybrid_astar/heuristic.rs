//! The holonomic-with-obstacles heuristic: a lower bound on the remaining length from a
//! lazy Dijkstra over a grid of the field, and the flood fill that tells which cells can
//! reach the goal at all.

use std::f64::consts::{PI, SQRT_2};
use std::ops::ControlFlow;

use pathfinding::directed::dijkstra::{DijkstraReachable, dijkstra_reach};

use super::collision::Checker;
use super::settings::HybridAStarSettings;
use crate::geometry::{Field, Point, Pose, Vector};

/// Up to eight grid neighbours with their step costs.
struct Neighbours {
    items: [(u32, u32); 8],
    len: usize,
    next: usize,
}

impl Iterator for Neighbours {
    type Item = (u32, u32);
    fn next(&mut self) -> Option<(u32, u32)> {
        (self.next < self.len).then(|| {
            self.next += 1;
            self.items[self.next - 1]
        })
    }
}

/// Grid step costs: 1000 per straight step, 1414 per diagonal (rounded down, so never an
/// overestimate).
const STRAIGHT_COST: u32 = 1000;

const DIAGONAL_COST: u32 = 1414;

/// A fine cell is blocked when each of its `COVER_SPLIT x COVER_SPLIT` sub-squares lies
/// inside one obstacle.
const COVER_SPLIT: usize = 4;

/// Largest number of cells of the connectivity grid.
pub(super) const MAX_GRID_CELLS: f64 = (1u64 << 24) as f64;

/// Square cells of side `cell_m` tiling the field from the origin, row by row.
#[derive(Clone, Copy, Debug)]
struct Grid {
    columns: usize,
    rows: usize,
    cell_m: f64,
}

impl Grid {
    fn column_row(&self, cell: usize) -> (usize, usize) {
        (cell % self.columns, cell / self.columns)
    }

    fn cell_of(&self, p: &Point) -> usize {
        let to_cell = |v: f64, n: usize| ((v / self.cell_m).floor().max(0.0) as usize).min(n - 1);
        to_cell(p.y, self.rows) * self.columns + to_cell(p.x, self.columns)
    }

    /// The 8-neighbours of `cell` that are not blocked, with their step costs. A diagonal
    /// step between two blocked cells is refused: their shared corner is not free.
    fn neighbours(&self, cell: usize, blocked: &[bool]) -> Neighbours {
        let (c, r) = self.column_row(cell);
        let mut out = Neighbours {
            items: [(0, 0); 8],
            len: 0,
            next: 0,
        };
        for (dc, dr) in [
            (-1i64, -1i64),
            (0, -1),
            (1, -1),
            (-1, 0),
            (1, 0),
            (-1, 1),
            (0, 1),
            (1, 1),
        ] {
            let (nc, nr) = (c as i64 + dc, r as i64 + dr);
            if nc < 0 || nr < 0 || nc >= self.columns as i64 || nr >= self.rows as i64 {
                continue;
            }
            let (nc, nr) = (nc as usize, nr as usize);
            let n = nr * self.columns + nc;
            let diagonal = dc != 0 && dr != 0;
            if blocked[n]
                || (diagonal && blocked[r * self.columns + nc] && blocked[nr * self.columns + c])
            {
                continue;
            }
            let step = if diagonal {
                DIAGONAL_COST
            } else {
                STRAIGHT_COST
            };
            out.items[out.len] = (n as u32, step);
            out.len += 1;
        }
        out
    }
}

type Successors = Box<dyn FnMut(&u32) -> Neighbours>;

/// The obstacle-aware lower bound, on two grids.
///
/// The fine grid (cells of `cell_m`) blocks only the cells no free point can occupy: wholly
/// outside the inset field, or covered by the inflated obstacles. Every free path therefore
/// crosses free cells only, from each to an 8-neighbour, so the flood fill of the free cells
/// from the goal's cell holds every point from which the goal can be reached: a pose
/// outside it has no path (`NoPath` at once, rather than an exhausted search).
///
/// The coarse grid (`heuristic_downsample` fine cells a side, as Smac downsamples its
/// costmap) opens the cells holding a reachable fine cell, and a lazy Dijkstra
/// (`pathfinding::dijkstra_reach`) grows from the goal's cell as far as the queries need.
pub(super) struct Holonomic {
    fine: Grid,
    coarse: Grid,
    downsample: usize,
    /// Fine cells from which the goal's cell can be reached.
    reachable: Vec<bool>,
    /// Coarse grid cost from the goal cell, `u32::MAX` while not yet reached.
    cost: Vec<u32>,
    reach: DijkstraReachable<u32, u32, Successors>,
    exhausted: bool,
}

impl Holonomic {
    pub(super) fn new(
        field: &Field,
        checker: &Checker,
        goal: &Pose,
        settings: &HybridAStarSettings,
    ) -> Self {
        let cell_m = settings.cell_m;
        let fine = Grid {
            columns: ((field.width_m / cell_m).ceil() as usize).max(1),
            rows: ((field.height_m / cell_m).ceil() as usize).max(1),
            cell_m,
        };
        let blocked = Self::blocked_cells(field, checker, &fine);

        let goal_cell = fine.cell_of(&goal.position());
        let reachable = Self::flood_fill(&fine, &blocked, goal_cell);

        let downsample = settings.heuristic_downsample;
        let coarse = Grid {
            columns: fine.columns.div_ceil(downsample),
            rows: fine.rows.div_ceil(downsample),
            cell_m: cell_m * downsample as f64,
        };
        let mut coarse_blocked = vec![true; coarse.columns * coarse.rows];
        for (cell, _) in reachable.iter().enumerate().filter(|(_, r)| **r) {
            let (c, r) = fine.column_row(cell);
            coarse_blocked[(r / downsample) * coarse.columns + c / downsample] = false;
        }
        let coarse_goal = Self::coarse_cell(&fine, &coarse, downsample, goal_cell) as u32;
        let successors: Successors =
            Box::new(move |&cell: &u32| coarse.neighbours(cell as usize, &coarse_blocked));
        Self {
            fine,
            coarse,
            downsample,
            reachable,
            cost: vec![u32::MAX; coarse.columns * coarse.rows],
            reach: dijkstra_reach(&coarse_goal, successors),
            exhausted: false,
        }
    }

    fn coarse_cell(fine: &Grid, coarse: &Grid, downsample: usize, fine_cell: usize) -> usize {
        let (c, r) = fine.column_row(fine_cell);
        (r / downsample) * coarse.columns + c / downsample
    }

    /// The cells reachable from `from` through free cells (8-connected, no corner cutting,
    /// the same moves as [`Grid::neighbours`]).
    fn flood_fill(grid: &Grid, blocked: &[bool], from: usize) -> Vec<bool> {
        // A copy with a blocked border, so that the loop needs no bounds checks.
        let w = grid.columns + 2;
        let mut free = vec![false; w * (grid.rows + 2)];
        for r in 0..grid.rows {
            for c in 0..grid.columns {
                free[(r + 1) * w + c + 1] = !blocked[r * grid.columns + c];
            }
        }
        let mut reached = vec![false; free.len()];
        let (c, r) = grid.column_row(from);
        let first = (r + 1) * w + c + 1;
        let mut stack = Vec::new();
        if free[first] {
            reached[first] = true;
            stack.push(first);
        }
        while let Some(i) = stack.pop() {
            for n in [i - 1, i + 1, i - w, i + w] {
                if free[n] && !reached[n] {
                    reached[n] = true;
                    stack.push(n);
                }
            }
            for (x, y) in [
                (i - 1, i - w),
                (i + 1, i - w),
                (i - 1, i + w),
                (i + 1, i + w),
            ] {
                let n = x + y - i;
                if free[n] && !reached[n] && (free[x] || free[y]) {
                    reached[n] = true;
                    stack.push(n);
                }
            }
        }
        let mut reachable = vec![false; blocked.len()];
        for r in 0..grid.rows {
            for c in 0..grid.columns {
                reachable[r * grid.columns + c] = reached[(r + 1) * w + c + 1];
            }
        }
        reachable
    }

    /// The fine cells no free point can occupy.
    fn blocked_cells(field: &Field, checker: &Checker, fine: &Grid) -> Vec<bool> {
        let cell_m = fine.cell_m;
        let bounds = |cell: usize| {
            let (c, r) = fine.column_row(cell);
            (
                Point::new(c as f64 * cell_m, r as f64 * cell_m),
                Point::new(
                    ((c + 1) as f64 * cell_m).min(field.width_m),
                    ((r + 1) as f64 * cell_m).min(field.height_m),
                ),
            )
        };
        // Columns and rows wholly outside the inset field.
        let outside = |i: usize, max_v: f64, lo_v: f64, hi_v: f64| {
            let (a, b) = (i as f64 * cell_m, ((i + 1) as f64 * cell_m).min(max_v));
            b < lo_v || a > hi_v
        };
        let column_out: Vec<bool> = (0..fine.columns)
            .map(|c| outside(c, field.width_m, checker.min.x, checker.max.x))
            .collect();
        let row_out: Vec<bool> = (0..fine.rows)
            .map(|r| outside(r, field.height_m, checker.min.y, checker.max.y))
            .collect();
        let mut blocked = vec![false; fine.columns * fine.rows];
        for (r, row) in blocked.chunks_mut(fine.columns).enumerate() {
            for (c, b) in row.iter_mut().enumerate() {
                *b = row_out[r] || column_out[c];
            }
        }
        // Cells that some obstacle touches, visited in index order (deterministic).
        let mut touched = vec![false; blocked.len()];
        for d in checker.grid.disks() {
            let r = Vector::new(d.radius_m, d.radius_m);
            let (c0, r0) = fine.column_row(fine.cell_of(&(d.centre - r)));
            let (c1, r1) = fine.column_row(fine.cell_of(&(d.centre + r)));
            for row in r0..=r1 {
                touched[row * fine.columns + c0..=row * fine.columns + c1].fill(true);
            }
        }
        // A touched cell is blocked when each of its sub-squares lies wholly inside one
        // obstacle, so that the union of the obstacles covers it.
        let mut candidates = Vec::new();
        for cell in 0..blocked.len() {
            if !touched[cell] || blocked[cell] {
                continue;
            }
            let (lo, hi) = bounds(cell);
            candidates.clear();
            let _ = checker.grid.visit_box(&lo, &hi, |_, d| {
                candidates.push(*d);
                ControlFlow::<()>::Continue(())
            });
            let step = (hi - lo) / COVER_SPLIT as f64;
            blocked[cell] = (0..COVER_SPLIT * COVER_SPLIT).all(|k| {
                let a = lo
                    + Vector::new(
                        (k % COVER_SPLIT) as f64 * step.x,
                        (k / COVER_SPLIT) as f64 * step.y,
                    );
                let corners = [
                    a,
                    a + step,
                    a + Vector::new(step.x, 0.0),
                    a + Vector::new(0.0, step.y),
                ];
                candidates
                    .iter()
                    .any(|d| corners.iter().all(|p| (p - d.centre).norm() < d.radius_m))
            });
        }
        blocked
    }

    /// A lower bound on the length of a free path from `p` to the goal, in metres;
    /// infinite when the grid shows none exists.
    pub(super) fn lower_bound_m(&mut self, p: &Point) -> f64 {
        let fine_cell = self.fine.cell_of(p);
        if !self.reachable[fine_cell] {
            return f64::INFINITY;
        }
        let cell = Self::coarse_cell(&self.fine, &self.coarse, self.downsample, fine_cell);
        while self.cost[cell] == u32::MAX && !self.exhausted {
            match self.reach.next() {
                Some(item) => self.cost[item.node as usize] = item.total_cost,
                None => self.exhausted = true,
            }
        }
        match self.cost[cell] {
            u32::MAX => f64::INFINITY,
            cost => {
                // An 8-connected grid path is at most sec(pi/8) times a straight line, plus a
                // cell diagonal for where the point lies in its cell.
                let cell_m = self.coarse.cell_m;
                let grid_m = cost as f64 / STRAIGHT_COST as f64 * cell_m;
                (grid_m * (PI / 8.0).cos() - SQRT_2 * cell_m).max(0.0)
            }
        }
    }
}
