//! A uniform-grid index over axis-aligned boxes: which boxes meet a query box, each told
//! once, touching only the grid cells the query covers.

use std::ops::ControlFlow;

use super::Point;

/// Axis-aligned boxes `(min, max)` indexed in a uniform grid whose cells are about the
/// size of a box, so that a query near a few boxes looks at a few boxes, however many
/// there are (a map's thousands of pieces).
///
/// ```
/// use std::ops::ControlFlow;
/// use shared::geometry::{BoxIndex, Point};
/// let boxes = [
///     (Point::new(0.0, 0.0), Point::new(1.0, 1.0)),
///     (Point::new(5.0, 5.0), Point::new(6.0, 6.0)),
///     (Point::new(0.5, 0.5), Point::new(5.5, 5.5)),
/// ];
/// let index = BoxIndex::new(&boxes);
/// let mut met = Vec::new();
/// let _ = index.visit(&Point::new(0.9, 0.9), &Point::new(1.1, 1.1), |i| {
///     met.push(i);
///     ControlFlow::<()>::Continue(())
/// });
/// met.sort();
/// assert_eq!(met, [0, 2]);
/// ```
#[derive(Clone, Debug, Default)]
pub struct BoxIndex {
    boxes: Vec<(Point, Point)>,
    origin: Point,
    cell_m: f64,
    columns: usize,
    rows: usize,
    /// `cell_items[cell_start[k]..cell_start[k + 1]]`: the boxes that meet cell `k`.
    cell_start: Vec<u32>,
    cell_items: Vec<u32>,
}

impl BoxIndex {
    /// Index `boxes` (each `(min, max)`, finite, `min <= max`; any other box is never
    /// reported).
    pub fn new(boxes: &[(Point, Point)]) -> Self {
        let usable = |(a, b): &(Point, Point)| {
            a.x.is_finite() && a.y.is_finite() && b.x.is_finite() && b.y.is_finite()
        } && a.x <= b.x
            && a.y <= b.y;
        let mut min = Point::new(f64::INFINITY, f64::INFINITY);
        let mut max = Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        let mut side_sum = 0.0;
        let mut count = 0usize;
        for b in boxes.iter().filter(|b| usable(b)) {
            min = Point::new(min.x.min(b.0.x), min.y.min(b.0.y));
            max = Point::new(max.x.max(b.1.x), max.y.max(b.1.y));
            side_sum += (b.1.x - b.0.x).max(b.1.y - b.0.y);
            count += 1;
        }
        if count == 0 {
            return Self {
                boxes: boxes.to_vec(),
                cell_start: vec![0],
                ..Self::default()
            };
        }
        // Cells of about the mean box size, and not more of them than twice the boxes.
        let (width, height) = (max.x - min.x, max.y - min.y);
        let by_count = (width * height / (2 * count) as f64).sqrt();
        let cell_m = (side_sum / count as f64).max(by_count).max(1e-6);
        let columns = ((width / cell_m) as usize + 1).min(1 << 12);
        let rows = ((height / cell_m) as usize + 1).min(1 << 12);
        let mut index = Self {
            boxes: boxes.to_vec(),
            origin: min,
            cell_m,
            columns,
            rows,
            cell_start: Vec::new(),
            cell_items: Vec::new(),
        };
        let ranges: Vec<Option<[usize; 4]>> = boxes
            .iter()
            .map(|b| usable(b).then(|| index.cells_of(&b.0, &b.1)))
            .collect();
        let (start, items) = super::cell_lists::cell_lists(columns, rows, &ranges);
        index.cell_start = start;
        index.cell_items = items;
        index
    }

    /// How many boxes were indexed.
    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    /// Whether no box was indexed.
    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }

    /// The cells `[c0, r0, c1, r1]` the box `[min, max]` covers, clamped to the grid.
    fn cells_of(&self, min: &Point, max: &Point) -> [usize; 4] {
        let to_cell = |v: f64, o: f64, n: usize| -> usize {
            let k = (v - o) / self.cell_m;
            // At or below 0, and for NaN, the first cell.
            if k > 0.0 { (k as usize).min(n - 1) } else { 0 }
        };
        [
            to_cell(min.x, self.origin.x, self.columns),
            to_cell(min.y, self.origin.y, self.rows),
            to_cell(max.x, self.origin.x, self.columns),
            to_cell(max.y, self.origin.y, self.rows),
        ]
    }

    /// Visit, once each, every box that meets the box `[min, max]` (touching counts), by
    /// its index in the list given to [`BoxIndex::new`]; stops at the first `Break`.
    pub fn visit<B>(
        &self,
        min: &Point,
        max: &Point,
        mut visit: impl FnMut(usize) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        if self.columns == 0 || !(min.x <= max.x && min.y <= max.y) {
            return ControlFlow::Continue(());
        }
        let [c0, r0, c1, r1] = self.cells_of(min, max);
        for r in r0..=r1 {
            for c in c0..=c1 {
                let k = r * self.columns + c;
                let items =
                    &self.cell_items[self.cell_start[k] as usize..self.cell_start[k + 1] as usize];
                for &i in items {
                    let (a, b) = &self.boxes[i as usize];
                    if b.x < min.x || a.x > max.x || b.y < min.y || a.y > max.y {
                        continue;
                    }
                    // Told only from the first cell the box and the query share.
                    let [bc0, br0, _, _] = self.cells_of(a, b);
                    if c == bc0.max(c0) && r == br0.max(r0) {
                        visit(i as usize)?;
                    }
                }
            }
        }
        ControlFlow::Continue(())
    }
}
