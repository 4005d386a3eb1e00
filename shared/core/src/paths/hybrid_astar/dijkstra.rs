//! A lazy Dijkstra over a grid from one source cell that can be repaired in place when
//! cells become blocked, instead of being started over.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::grid::Grid;

const NONE: u32 = u32::MAX;

/// Grid distances (sums of [`Grid::neighbours`]' integer step costs) from a source cell,
/// settled lazily, as far as the queries need.
///
/// Cells only ever become blocked (obstacles are added, never removed), so distances only
/// grow: [`GridDijkstra::block`] keeps every settled cell whose shortest-path tree branch
/// avoids the newly blocked cells and steps (its distance is unchanged), forgets the rest,
/// re-seeds the forgotten cells from their kept neighbours and lets the lazy search settle
/// them again on demand. Every distance it answers is the exact grid distance in the
/// current grid, the same as a search started over would give.
#[derive(Clone)]
pub(super) struct GridDijkstra {
    grid: Grid,
    blocked: Vec<bool>,
    /// Tentative distance (final once settled), `u32::MAX` when not reached.
    cost: Vec<u32>,
    /// The neighbour the distance came through, `NONE` for the source and unreached cells.
    parent: Vec<u32>,
    settled: Vec<bool>,
    /// Settled cells in the order they were settled (a parent before its children).
    order: Vec<u32>,
    /// Open entries (distance, cell); stale ones are skipped when popped.
    open: BinaryHeap<Reverse<(u32, u32)>>,
}

impl GridDijkstra {
    /// Distances from `source` over the open cells of `grid` (`blocked` has one entry per
    /// cell). Nothing is settled yet.
    pub(super) fn new(grid: Grid, blocked: Vec<bool>, source: usize) -> Self {
        let n = grid.len();
        let mut dijkstra = Self {
            grid,
            blocked,
            cost: vec![u32::MAX; n],
            parent: vec![NONE; n],
            settled: vec![false; n],
            order: Vec::new(),
            open: BinaryHeap::new(),
        };
        if !dijkstra.blocked[source] {
            dijkstra.cost[source] = 0;
            dijkstra.open.push(Reverse((0, source as u32)));
        }
        dijkstra
    }

    /// The grid distance from the source to `cell`, `None` when no open path joins them.
    pub(super) fn distance(&mut self, cell: usize) -> Option<u32> {
        while !self.settled[cell] {
            let Reverse((cost, v)) = self.open.pop()?;
            let v = v as usize;
            if self.settled[v] || cost != self.cost[v] {
                continue; // stale entry
            }
            self.settled[v] = true;
            self.order.push(v as u32);
            for (u, step) in self.grid.neighbours(v, &self.blocked) {
                let u = u as usize;
                let via = cost + step;
                if !self.settled[u] && via < self.cost[u] {
                    self.cost[u] = via;
                    self.parent[u] = v as u32;
                    self.open.push(Reverse((via, u as u32)));
                }
            }
        }
        Some(self.cost[cell])
    }

    /// Block `cells` (already blocked ones are ignored) and repair the distances.
    pub(super) fn block(&mut self, cells: &[usize]) {
        let mut changed = false;
        for &c in cells {
            changed |= !self.blocked[c];
            self.blocked[c] = true;
        }
        if !changed {
            return;
        }
        let n = self.grid.len();
        // Settled cells whose tree branch lost a cell or a step: forget them.
        let mut forgotten = vec![false; n];
        let grid = self.grid;
        let blocked = &self.blocked;
        let step_lost = |p: u32, v: usize, forgotten: &[bool]| {
            forgotten[p as usize] || !grid.step_open(p as usize, v, blocked)
        };
        let mut kept = Vec::with_capacity(self.order.len());
        for &v in &self.order {
            let v = v as usize;
            let p = self.parent[v];
            if self.blocked[v] || (p != NONE && step_lost(p, v, &forgotten)) {
                forgotten[v] = true;
                self.settled[v] = false;
                self.cost[v] = u32::MAX;
                self.parent[v] = NONE;
            } else {
                kept.push(v as u32);
            }
        }
        self.order = kept;
        // Open cells reached through a forgotten cell or a lost step: reset them too. The
        // others keep their tentative distance (still the best over their settled
        // neighbours, a subset of the former ones that holds their parent).
        let mut reseed = Vec::new();
        for v in 0..n {
            if self.settled[v] || self.blocked[v] {
                if self.blocked[v] && !self.settled[v] {
                    self.cost[v] = u32::MAX;
                    self.parent[v] = NONE;
                }
                continue;
            }
            if forgotten[v] {
                reseed.push(v);
            } else if self.cost[v] != u32::MAX {
                let p = self.parent[v];
                if p != NONE && step_lost(p, v, &forgotten) {
                    self.cost[v] = u32::MAX;
                    self.parent[v] = NONE;
                    reseed.push(v);
                }
            }
        }
        // Re-seed from the settled neighbours.
        for v in reseed {
            for (u, step) in self.grid.neighbours(v, &self.blocked) {
                let u = u as usize;
                if self.settled[u] && self.cost[u] + step < self.cost[v] {
                    self.cost[v] = self.cost[u] + step;
                    self.parent[v] = u as u32;
                }
            }
            if self.cost[v] != u32::MAX {
                self.open.push(Reverse((self.cost[v], v as u32)));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        /// After cells are blocked, every distance (lazily settled before or not) is the
        /// one a fresh search gives, in rounds.
        #[test]
        fn repaired_distances_equal_fresh_ones(
            columns in 1usize..24,
            rows in 1usize..24,
            seed_blocked in prop::collection::vec(any::<u16>(), 0..80),
            rounds in prop::collection::vec(
                (prop::collection::vec(any::<u16>(), 1..40), prop::collection::vec(any::<u16>(), 0..10)),
                1..4,
            ),
        ) {
            let grid = Grid { columns, rows, cell_m: 1.0 };
            let n = grid.len();
            let source = n / 2;
            let mut blocked = vec![false; n];
            for c in seed_blocked {
                blocked[c as usize % n] = true;
            }
            let mut repaired = GridDijkstra::new(grid, blocked.clone(), source);
            for (to_block, queries) in rounds {
                // Settle part of the grid lazily before blocking.
                for q in queries {
                    let _ = repaired.distance(q as usize % n);
                }
                let cells: Vec<usize> = to_block.iter().map(|c| *c as usize % n).collect();
                for &c in &cells {
                    blocked[c] = true;
                }
                repaired.block(&cells);
                let mut fresh = GridDijkstra::new(grid, blocked.clone(), source);
                for cell in 0..n {
                    prop_assert_eq!(repaired.distance(cell), fresh.distance(cell), "cell {}", cell);
                }
            }
        }
    }
}
