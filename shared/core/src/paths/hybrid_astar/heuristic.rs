//! The holonomic-with-obstacles heuristic: a lower bound on the remaining length from a
//! lazy Dijkstra over a grid of the field, and the flood fill that tells which cells can
//! reach the goal at all.

use std::f64::consts::{PI, SQRT_2};
use std::ops::ControlFlow;

use super::collision::Checker;
use super::dijkstra::GridDijkstra;
use super::grid::{Grid, STRAIGHT_COST};
use super::settings::HybridAStarSettings;
use crate::geometry::{Disk, Field, Point, Pose, Vector};

/// A fine cell is blocked when each of its `COVER_SPLIT x COVER_SPLIT` sub-squares lies
/// inside one obstacle.
const COVER_SPLIT: usize = 4;

/// Largest number of cells of the connectivity grid.
pub(super) const MAX_GRID_CELLS: f64 = (1u64 << 24) as f64;

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
/// ([`GridDijkstra`]) grows from the goal's cell as far as the queries need.
///
/// Nothing here depends on the start, so one `Holonomic` serves any number of searches to
/// the same goal; [`Holonomic::add_obstacles`] brings it up to date when obstacles are
/// added, to the same state a rebuild would reach.
#[derive(Clone)]
pub(super) struct Holonomic {
    fine: Grid,
    coarse: Grid,
    downsample: usize,
    /// The goal's fine cell.
    goal_cell: usize,
    /// Fine cells no free point can occupy.
    blocked: Vec<bool>,
    /// Fine cells from which the goal's cell can be reached.
    reachable: Vec<bool>,
    /// Coarse grid distances from the goal's coarse cell.
    distances: GridDijkstra,
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
        let mut blocked = Self::outside_cells(field, checker, &fine);
        Self::block_covered(field, checker, &fine, checker.grid.disks(), &mut blocked);

        let goal_cell = fine.cell_of(&goal.position());
        let reachable = Self::flood_fill(&fine, &blocked, goal_cell);

        let downsample = settings.heuristic_downsample;
        let coarse = Grid {
            columns: fine.columns.div_ceil(downsample),
            rows: fine.rows.div_ceil(downsample),
            cell_m: cell_m * downsample as f64,
        };
        let mut coarse_blocked = vec![true; coarse.len()];
        for (cell, _) in reachable.iter().enumerate().filter(|(_, r)| **r) {
            coarse_blocked[Self::coarse_cell(&fine, &coarse, downsample, cell)] = false;
        }
        let coarse_goal = Self::coarse_cell(&fine, &coarse, downsample, goal_cell);
        Self {
            fine,
            coarse,
            downsample,
            goal_cell,
            blocked,
            reachable,
            distances: GridDijkstra::new(coarse, coarse_blocked, coarse_goal),
        }
    }

    /// Bring the bound up to date after `added` (inflated, like `checker`'s) joined the
    /// obstacles; `checker` holds all of them, old and added. Only the fine cells the added
    /// disks touch are tested again; the flood fill is redone only when one of them was
    /// reachable and is now blocked; the coarse distances are repaired
    /// ([`GridDijkstra::block`]) only when coarse cells lost their last reachable fine
    /// cell. The result is the state [`Holonomic::new`] would build with all obstacles.
    pub(super) fn add_obstacles(&mut self, field: &Field, checker: &Checker, added: &[Disk]) {
        let newly = Self::block_covered(field, checker, &self.fine, added, &mut self.blocked);
        if !newly.iter().any(|&c| self.reachable[c]) {
            // A free cell next to a reachable one is reachable itself, so blocking cells
            // that were not reachable changes no other cell's reachability.
            return;
        }
        let reachable = Self::flood_fill(&self.fine, &self.blocked, self.goal_cell);
        let mut lost = Vec::new();
        for (cell, (was, is)) in self.reachable.iter().zip(&reachable).enumerate() {
            if *was && !*is {
                let coarse = Self::coarse_cell(&self.fine, &self.coarse, self.downsample, cell);
                if lost.last() != Some(&coarse) {
                    lost.push(coarse);
                }
            }
        }
        self.reachable = reachable;
        lost.sort_unstable();
        lost.dedup();
        // A coarse cell is blocked once none of its fine cells is reachable.
        lost.retain(|&coarse| {
            let (c, r) = self.coarse.column_row(coarse);
            let d = self.downsample;
            let rows = r * d..((r + 1) * d).min(self.fine.rows);
            !rows.into_iter().any(|fr| {
                let row = fr * self.fine.columns;
                self.reachable[row + c * d..row + ((c + 1) * d).min(self.fine.columns)]
                    .iter()
                    .any(|r| *r)
            })
        });
        self.distances.block(&lost);
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

    /// The fine cells wholly outside the field inset by the clearance.
    fn outside_cells(field: &Field, checker: &Checker, fine: &Grid) -> Vec<bool> {
        let cell_m = fine.cell_m;
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
        let mut blocked = vec![false; fine.len()];
        for (r, row) in blocked.chunks_mut(fine.columns).enumerate() {
            for (c, b) in row.iter_mut().enumerate() {
                *b = row_out[r] || column_out[c];
            }
        }
        blocked
    }

    /// Block the fine cells, among those the disks `touching` touch, that `checker`'s
    /// inflated obstacles cover; return the cells newly blocked, in index order.
    fn block_covered(
        field: &Field,
        checker: &Checker,
        fine: &Grid,
        touching: &[Disk],
        blocked: &mut [bool],
    ) -> Vec<usize> {
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
        // Cells that some disk touches, visited in index order (deterministic).
        let mut touched = vec![false; blocked.len()];
        for d in touching {
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
        let mut newly = Vec::new();
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
            let covered = (0..COVER_SPLIT * COVER_SPLIT).all(|k| {
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
            if covered {
                blocked[cell] = true;
                newly.push(cell);
            }
        }
        newly
    }

    /// A lower bound on the length of a free path from `p` to the goal, in metres;
    /// infinite when the grid shows none exists.
    pub(super) fn lower_bound_m(&mut self, p: &Point) -> f64 {
        let fine_cell = self.fine.cell_of(p);
        if !self.reachable[fine_cell] {
            return f64::INFINITY;
        }
        let cell = Self::coarse_cell(&self.fine, &self.coarse, self.downsample, fine_cell);
        match self.distances.distance(cell) {
            None => f64::INFINITY,
            Some(cost) => {
                // An 8-connected grid path is at most sec(pi/8) times a straight line, plus a
                // cell diagonal for where the point lies in its cell.
                let cell_m = self.coarse.cell_m;
                let grid_m = cost as f64 / STRAIGHT_COST as f64 * cell_m;
                (grid_m * (PI / 8.0).cos() - SQRT_2 * cell_m).max(0.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Adding obstacles in place gives the heuristic a rebuild gives, everywhere.
        #[test]
        fn added_obstacles_give_the_rebuilt_heuristic(
            disks in prop::collection::vec((0.0..30.0f64, 0.0..20.0f64, 0.0..3.0f64), 0..40),
            split in 0usize..40,
            queries in prop::collection::vec((0.0..30.0f64, 0.0..20.0f64), 0..20),
            downsample in 1usize..4,
        ) {
            let field = Field::new(30.0, 20.0);
            let mut settings = HybridAStarSettings::new(2.5, 0.5, true);
            settings.heuristic_downsample = downsample;
            let goal = Pose::new(15.0, 10.0, 0.0);
            let obstacles: Vec<Disk> = disks.iter().map(|&(x, y, r)| Disk::new(x, y, r)).collect();
            let split = split.min(obstacles.len());
            let before = Checker::new(&field, &obstacles[..split], &settings);
            let mut updated = Holonomic::new(&field, &before, &goal, &settings);
            for (x, y) in queries {
                let _ = updated.lower_bound_m(&Point::new(x, y));
            }
            let after = Checker::new(&field, &obstacles, &settings);
            updated.add_obstacles(&field, &after, &after.grid.disks()[split..]);
            let mut rebuilt = Holonomic::new(&field, &after, &goal, &settings);
            prop_assert_eq!(&updated.blocked, &rebuilt.blocked);
            prop_assert_eq!(&updated.reachable, &rebuilt.reachable);
            for cell in 0..updated.fine.len() {
                let (c, r) = updated.fine.column_row(cell);
                let p = Point::new((c as f64 + 0.5) * settings.cell_m, (r as f64 + 0.5) * settings.cell_m);
                prop_assert_eq!(
                    updated.lower_bound_m(&p).to_bits(),
                    rebuilt.lower_bound_m(&p).to_bits(),
                    "cell {}", cell
                );
            }
        }
    }
}
