//! Which free places of a map cannot reach each other ([`OccupancyGrid::regions`]): a
//! quick and sound proof that a goal is unreachable, before any search.

use crate::geometry::{Point, RegionGrid, Vector};

use super::{Cell, OccupancyGrid};

impl OccupancyGrid {
    /// The free regions of this map for a point agent that keeps `clearance_m` from every
    /// blocked cell (those for which `blocked` holds), in a frame where the map's origin
    /// lies at `origin_m + shift`: the cells that are surely blocked (every point of them
    /// nearer than the clearance to a blocked cell, blocked cells included) wall the
    /// others off into regions, labelled by a flood fill across cell sides.
    ///
    /// Two points in different regions are in different components of the free space: a
    /// path between them would cross a surely blocked cell, or pass a corner where two
    /// such cells meet, and every point there is blocked. Other obstacles only take more
    /// of the space away.
    ///
    /// ```
    /// use shared::geometry::{Point, Vector};
    /// use shared::world::maps::{Cell, OccupancyGrid};
    /// // A 10 x 1 strip of 1 m cells with a wall in its middle cell.
    /// let cells = (0..10).map(|x| if x == 5 { Cell::Occupied } else { Cell::Free }).collect();
    /// let grid = OccupancyGrid::from_cells(10, 1, 1.0, [0.0, 0.0], cells);
    /// let regions = grid.regions(|c| c == Cell::Occupied, 0.25, Vector::zeros());
    /// assert!(regions.apart(&Point::new(1.0, 0.5), &Point::new(8.0, 0.5)));
    /// assert!(!regions.apart(&Point::new(1.0, 0.5), &Point::new(4.0, 0.5)));
    /// ```
    pub fn regions(
        &self,
        blocked: impl Fn(Cell) -> bool,
        clearance_m: f64,
        shift: Vector,
    ) -> RegionGrid {
        let (w, h, res) = (self.width, self.height, self.resolution_m);
        let mut sure = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                sure[y * w + x] = blocked(self.cell(x, y));
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
        let origin = Point::new(self.origin_m[0], self.origin_m[1]) + shift;
        RegionGrid::from_labels(w, h, res, origin, label)
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
