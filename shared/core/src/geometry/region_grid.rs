//! Free regions of a grid that cannot reach each other ([`RegionGrid`]): a quick and sound
//! proof that a goal is unreachable, before any search.

use super::Point;

/// Cells of a uniform grid labelled by region: a point in one region cannot reach a
/// point in another without crossing a cell labelled 0 (surely blocked), so two points
/// in different regions are in different components of the free space. Made from a map
/// by [`OccupancyGrid::regions`](crate::world::maps::OccupancyGrid::regions).
///
/// ```
/// use shared::geometry::{Point, RegionGrid};
/// // A strip of four 1 m cells, its third surely blocked.
/// let regions = RegionGrid::from_labels(4, 1, 1.0, Point::new(0.0, 0.0), vec![1, 1, 0, 2]);
/// assert!(regions.apart(&Point::new(0.5, 0.5), &Point::new(3.5, 0.5)));
/// assert!(!regions.apart(&Point::new(0.5, 0.5), &Point::new(1.5, 0.5)));
/// // A point touching a blocked cell proves nothing.
/// assert!(!regions.apart(&Point::new(2.0, 0.5), &Point::new(3.5, 0.5)));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct RegionGrid {
    width: usize,
    height: usize,
    resolution_m: f64,
    origin: Point,
    /// Per cell (row by row from the bottom): 0 surely blocked, else its region.
    label: Vec<u32>,
}

impl RegionGrid {
    /// The grid of `width` x `height` cells of `resolution_m`, cell (0, 0) at `origin`,
    /// with `label` per cell row by row from the bottom one: 0 surely blocked, else its
    /// region. A label list of another length labels every cell 0 (proves nothing).
    pub fn from_labels(
        width: usize,
        height: usize,
        resolution_m: f64,
        origin: Point,
        label: Vec<u32>,
    ) -> Self {
        let label = match label.len() == width.saturating_mul(height) {
            true => label,
            false => vec![0; width.saturating_mul(height)],
        };
        Self {
            width,
            height,
            resolution_m,
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
