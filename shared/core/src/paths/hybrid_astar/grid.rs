//! The square grids the heuristic works on: cells of a side tiling the field from the
//! origin, their 8-neighbours and the integer step costs between them.

use crate::geometry::Point;

/// Grid step costs: 1000 per straight step, 1414 per diagonal (rounded down, so never an
/// overestimate).
pub(super) const STRAIGHT_COST: u32 = 1000;

pub(super) const DIAGONAL_COST: u32 = 1414;

/// Up to eight grid neighbours with their step costs.
pub(super) struct Neighbours {
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

/// Square cells of side `cell_m` tiling the field from the origin, row by row.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grid {
    pub(super) columns: usize,
    pub(super) rows: usize,
    pub(super) cell_m: f64,
}

impl Grid {
    pub(super) fn len(&self) -> usize {
        self.columns * self.rows
    }

    pub(super) fn column_row(&self, cell: usize) -> (usize, usize) {
        (cell % self.columns, cell / self.columns)
    }

    pub(super) fn cell_of(&self, p: &Point) -> usize {
        let to_cell = |v: f64, n: usize| ((v / self.cell_m).floor().max(0.0) as usize).min(n - 1);
        to_cell(p.y, self.rows) * self.columns + to_cell(p.x, self.columns)
    }

    /// The 8-neighbours of `cell` that are not blocked, with their step costs. A diagonal
    /// step between two blocked cells is refused: their shared corner is not free.
    pub(super) fn neighbours(&self, cell: usize, blocked: &[bool]) -> Neighbours {
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

    /// Whether the step between the neighbouring cells `a` and `b` is one of
    /// [`Grid::neighbours`]' moves: both open, and a diagonal not squeezed between two
    /// blocked cells.
    pub(super) fn step_open(&self, a: usize, b: usize, blocked: &[bool]) -> bool {
        if blocked[a] || blocked[b] {
            return false;
        }
        let ((ca, ra), (cb, rb)) = (self.column_row(a), self.column_row(b));
        if ca == cb || ra == rb {
            return true;
        }
        !(blocked[ra * self.columns + cb] && blocked[rb * self.columns + ca])
    }
}
