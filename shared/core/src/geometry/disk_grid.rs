//! A set of disks with a uniform-grid index.

use std::ops::ControlFlow;

use super::{Disk, Point, Vector};

/// A set of disks with a uniform-grid index, so that local queries cost what is local,
/// not what is in the whole field.
///
/// Each disk is registered in every cell its bounding box overlaps. Box queries visit each
/// disk once (a disk is reported only from the first cell where its box and the query box
/// meet), so no scratch memory is needed and the grid can be shared read-only.
#[derive(Clone, Debug)]
pub struct DiskGrid {
    disks: Vec<Disk>,
    origin: Point,
    cell_m: f64,
    columns: usize,
    rows: usize,
    /// `cell_start[c]..cell_start[c + 1]` indexes `cell_items` for cell `c`.
    cell_start: Vec<u32>,
    cell_items: Vec<u32>,
    max_radius_m: f64,
}

impl DiskGrid {
    /// Index `disks`. The cell size adapts to the disks' sizes and density.
    pub fn new(disks: Vec<Disk>) -> Self {
        if disks.is_empty() {
            return Self {
                disks,
                origin: Point::origin(),
                cell_m: 1.0,
                columns: 0,
                rows: 0,
                cell_start: vec![0],
                cell_items: Vec::new(),
                max_radius_m: 0.0,
            };
        }
        let (mut min, mut max) = (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        let mut max_radius_m: f64 = 0.0;
        for d in &disks {
            min.x = min.x.min(d.centre.x - d.radius_m);
            min.y = min.y.min(d.centre.y - d.radius_m);
            max.x = max.x.max(d.centre.x + d.radius_m);
            max.y = max.y.max(d.centre.y + d.radius_m);
            max_radius_m = max_radius_m.max(d.radius_m);
        }
        let area = ((max.x - min.x) * (max.y - min.y)).max(f64::MIN_POSITIVE);
        // About two disks' worth of cell per disk, never smaller than a disk's diameter.
        let by_density = (area / disks.len() as f64).sqrt();
        let cell_m = (2.0 * max_radius_m).max(by_density).max(1e-6);
        let columns = (((max.x - min.x) / cell_m).floor() as usize + 1).min(1 << 14);
        let rows = (((max.y - min.y) / cell_m).floor() as usize + 1).min(1 << 14);
        let mut grid = Self {
            disks,
            origin: min,
            cell_m,
            columns,
            rows,
            cell_start: Vec::new(),
            cell_items: Vec::new(),
            max_radius_m,
        };
        let ranges: Vec<Option<[usize; 4]>> = grid
            .disks
            .iter()
            .map(|d| {
                let (c0, r0, c1, r1) = grid.cell_range(&d.centre, d.radius_m, d.radius_m);
                Some([c0, r0, c1, r1])
            })
            .collect();
        let (start, items) = super::cell_lists::cell_lists(columns, rows, &ranges);
        grid.cell_start = start;
        grid.cell_items = items;
        grid
    }

    /// The indexed disks, in the order given to [`DiskGrid::new`].
    pub fn disks(&self) -> &[Disk] {
        &self.disks
    }

    /// Largest radius among the disks (0 when empty).
    pub fn max_radius_m(&self) -> f64 {
        self.max_radius_m
    }

    /// Cell column/row range covering the box `centre ± (half_w, half_h)`, clamped.
    fn cell_range(&self, centre: &Point, half_w: f64, half_h: f64) -> (usize, usize, usize, usize) {
        let to_cell = |v: f64, o: f64, n: usize| -> usize {
            let k = (v - o) / self.cell_m;
            // Truncation is the floor above 0 (and spares a call to libm's `floor`,
            // which most of the grid's construction went to); at or below 0, and for
            // NaN, the first cell.
            if k > 0.0 { (k as usize).min(n - 1) } else { 0 }
        };
        (
            to_cell(centre.x - half_w, self.origin.x, self.columns),
            to_cell(centre.y - half_h, self.origin.y, self.rows),
            to_cell(centre.x + half_w, self.origin.x, self.columns),
            to_cell(centre.y + half_h, self.origin.y, self.rows),
        )
    }

    /// Visit once each disk whose bounding box meets the axis-aligned box `[min, max]`
    /// (a superset of the disks that meet the box). `visit` gets the disk's index and the
    /// disk, and may stop the walk by returning `ControlFlow::Break`.
    pub fn visit_box<B>(
        &self,
        min: &Point,
        max: &Point,
        mut visit: impl FnMut(usize, &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        if self.disks.is_empty() || !(min.x <= max.x && min.y <= max.y) {
            return ControlFlow::Continue(());
        }
        let centre = nalgebra::center(min, max);
        let (c0, r0, c1, r1) =
            self.cell_range(&centre, 0.5 * (max.x - min.x), 0.5 * (max.y - min.y));
        for r in r0..=r1 {
            for c in c0..=c1 {
                let k = r * self.columns + c;
                for &i in
                    &self.cell_items[self.cell_start[k] as usize..self.cell_start[k + 1] as usize]
                {
                    let d = &self.disks[i as usize];
                    if d.centre.x + d.radius_m < min.x
                        || d.centre.x - d.radius_m > max.x
                        || d.centre.y + d.radius_m < min.y
                        || d.centre.y - d.radius_m > max.y
                    {
                        continue;
                    }
                    // Report the disk only from the first cell shared by its box and the query's.
                    let (dc0, dr0, _, _) = self.cell_range(&d.centre, d.radius_m, d.radius_m);
                    if c == dc0.max(c0) && r == dr0.max(r0) {
                        visit(i as usize, d)?;
                    }
                }
            }
        }
        ControlFlow::Continue(())
    }

    /// Whether `keep` holds for every disk that may come within `reach_m` of `p` (a
    /// superset of those that do, as [`DiskGrid::visit_near`]); stops at the first disk
    /// for which it does not.
    pub fn all_near(&self, p: &Point, reach_m: f64, mut keep: impl FnMut(&Disk) -> bool) -> bool {
        self.visit_near(p, reach_m, |_, d| {
            if keep(d) {
                ControlFlow::Continue(())
            } else {
                ControlFlow::Break(())
            }
        })
        .is_continue()
    }

    /// Visit once each disk that may come within `reach_m` of `p` (a superset).
    pub fn visit_near<B>(
        &self,
        p: &Point,
        reach_m: f64,
        visit: impl FnMut(usize, &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        let d = Vector::new(reach_m, reach_m);
        self.visit_box(&(p - d), &(p + d), visit)
    }
}
