//! Which free places of a map cannot reach each other ([`CellRegions`]): a quick and
//! sound proof that a goal is unreachable, before any search.

use crate::geometry::{Point, Vector};

use super::{Cell, OccupancyGrid};

/// The free regions of a map for a point agent that keeps `clearance_m` from every
/// blocked cell: the cells that are surely blocked (every point of them nearer than the
/// clearance to a blocked cell, blocked cells included) wall the others off into
/// regions, labelled by a flood fill across cell sides.
///
/// Two points in different regions are in different components of the free space: a
/// path between them would cross a surely blocked cell, or pass a corner where two such
/// cells meet, and every point there is blocked. So [`CellRegions::apart`] proves a goal
/// unreachable without a search (other obstacles only take more of the space away);
/// points it does not set apart may still be, and go to the search.
///
/// ```
/// use shared::geometry::{Point, Vector};
/// use shared::occupancy::{Cell, CellRegions, OccupancyGrid};
/// // A 10 x 1 strip of 1 m cells with a wall in its middle cell.
/// let cells = (0..10).map(|x| if x == 5 { Cell::Occupied } else { Cell::Free }).collect();
/// let grid = OccupancyGrid::from_cells(10, 1, 1.0, [0.0, 0.0], cells);
/// let regions = CellRegions::new(&grid, |c| c == Cell::Occupied, 0.25, Vector::zeros());
/// assert!(regions.apart(&Point::new(1.0, 0.5), &Point::new(8.0, 0.5)));
/// assert!(!regions.apart(&Point::new(1.0, 0.5), &Point::new(4.0, 0.5)));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CellRegions {
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Point,
    /// Per cell (row by row from the bottom): 0 surely blocked, else its region.
    label: Vec<u32>,
}

impl CellRegions {
    /// The regions of `grid` (its cells for which `blocked` holds are obstacles) for an
    /// agent that keeps `clearance_m` from them, in a frame where the map's origin lies
    /// at `grid.origin_m + shift`.
    pub fn new(
        grid: &OccupancyGrid,
        blocked: impl Fn(Cell) -> bool,
        clearance_m: f64,
        shift: Vector,
    ) -> Self {
        let (w, h, res) = (grid.width, grid.height, grid.resolution_m);
        let mut sure = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                sure[y * w + x] = blocked(grid.cell(x, y));
            }
        }
        // A cell is surely blocked when its farthest point is nearer than the clearance to
        // a blocked cell: its centre's distance to that cell's square plus half its
        // diagonal is below the clearance.
        let half_diagonal_m = res * std::f64::consts::FRAC_1_SQRT_2;
        let reach = ((clearance_m / res).ceil() as isize + 1).max(0);
        let mut offsets = Vec::new();
        if clearance_m.is_finite() && res > 0.0 {
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    let gap = |d: isize| ((d.abs() as f64) - 0.5).max(0.0) * res;
                    if gap(dx).hypot(gap(dy)) + half_diagonal_m < clearance_m {
                        offsets.push((dx, dy));
                    }
                }
            }
        }
        let blocked_cells = sure.clone();
        for y in 0..h {
            for x in 0..w {
                if !blocked_cells[y * w + x] || !has_free_neighbour(&blocked_cells, w, h, x, y) {
                    continue;
                }
                for &(dx, dy) in &offsets {
                    let (tx, ty) = (x as isize + dx, y as isize + dy);
                    if tx >= 0 && ty >= 0 && (tx as usize) < w && (ty as usize) < h {
                        sure[ty as usize * w + tx as usize] = true;
                    }
                }
            }
        }
        // Regions: flood fill across cell sides.
        let mut label = vec![0u32; w * h];
        let mut next = 0u32;
        let mut stack = Vec::new();
        for start in 0..w * h {
            if sure[start] || label[start] != 0 {
                continue;
            }
            next += 1;
            label[start] = next;
            stack.push(start);
            while let Some(k) = stack.pop() {
                let (x, y) = (k % w, k / w);
                let mut visit = |n: usize| {
                    if !sure[n] && label[n] == 0 {
                        label[n] = next;
                        stack.push(n);
                    }
                };
                if x > 0 {
                    visit(k - 1);
                }
                if x + 1 < w {
                    visit(k + 1);
                }
                if y > 0 {
                    visit(k - w);
                }
                if y + 1 < h {
                    visit(k + w);
                }
            }
        }
        let origin = Point::new(grid.origin_m[0], grid.origin_m[1]) + shift;
        Self {
            width: w,
            height: h,
            resolution_m: res,
            origin,
            label,
        }
    }

    /// The region of every cell `p` lies in (on a side or a corner, each cell touching
    /// it): `None` when `p` is off the map or touches a surely blocked cell.
    fn region(&self, p: &Point) -> Option<u32> {
        let fx = (p.x - self.origin.x) / self.resolution_m;
        let fy = (p.y - self.origin.y) / self.resolution_m;
        if !(fx >= 0.0 && fy >= 0.0 && fx <= self.width as f64 && fy <= self.height as f64) {
            return None;
        }
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        // The cells whose closed squares hold p: one, two on a side, four at a corner.
        let xs = if fx == x0 as f64 && x0 > 0 {
            [x0 - 1, x0]
        } else {
            [x0, x0]
        };
        let ys = if fy == y0 as f64 && y0 > 0 {
            [y0 - 1, y0]
        } else {
            [y0, y0]
        };
        let mut region = None;
        for y in ys {
            for x in xs {
                let l = *self.label.get(
                    y.min(self.height.saturating_sub(1)) * self.width
                        + x.min(self.width.saturating_sub(1)),
                )?;
                if l == 0 || region.is_some_and(|r| r != l) {
                    return None;
                }
                region = Some(l);
            }
        }
        region
    }

    /// Whether `a` and `b` lie in different regions, so that no path joins them (`false`
    /// says nothing).
    pub fn apart(&self, a: &Point, b: &Point) -> bool {
        match (self.region(a), self.region(b)) {
            (Some(ra), Some(rb)) => ra != rb,
            _ => false,
        }
    }
}

/// Whether the blocked cell (x, y) has a free cell beside it (only such cells can make
/// others surely blocked that are not so already).
fn has_free_neighbour(blocked: &[bool], w: usize, h: usize, x: usize, y: usize) -> bool {
    (x > 0 && !blocked[y * w + x - 1])
        || (x + 1 < w && !blocked[y * w + x + 1])
        || (y > 0 && !blocked[(y - 1) * w + x])
        || (y + 1 < h && !blocked[(y + 1) * w + x])
}
