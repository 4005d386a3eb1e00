//! The occupancy grid: each cell of the map free, occupied or unknown, placed in metres.

use std::path::Path;

use crate::geometry::Point;

use super::outline::{CellCorner, outline_cells};
use super::{MapError, MapMode, MapYaml, Raster};

/// What a cell of the map holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Cell {
    /// Nothing: agents may be there.
    Free,
    /// An obstacle.
    Occupied,
    /// Not mapped (between the thresholds, or not opaque in `scale` mode).
    Unknown,
}

/// A map's cells, placed in metres: cell (x, y) covers
/// `[origin + x * resolution, origin + (x + 1) * resolution]` in each axis, row 0 the
/// bottom one (the image's last row, as the map_server places it).
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    /// Cells per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Side of a cell, metres.
    pub resolution_m: f64,
    /// Lower-left corner of cell (0, 0), metres.
    pub origin_m: [f64; 2],
    /// `width * height` cells, row by row from the bottom one.
    cells: Vec<Cell>,
}

impl OccupancyGrid {
    /// Read the map whose YAML file is at `yaml_path`, and its image.
    ///
    /// ```
    /// use shared::world::maps::{Cell, OccupancyGrid};
    /// let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/maps");
    /// let (yaml, depot) = OccupancyGrid::load(format!("{dir}/depot.yaml").as_ref()).unwrap();
    /// assert_eq!((depot.width, depot.height, yaml.resolution_m), (604, 307, 0.05));
    /// assert!(depot.count(Cell::Occupied) > 0 && depot.count(Cell::Free) > 0);
    /// ```
    pub fn load(yaml_path: &Path) -> Result<(MapYaml, Self), MapError> {
        let yaml = MapYaml::load(yaml_path)?;
        let raster = Raster::read(&yaml.image)?;
        let grid = Self::from_raster(&raster, &yaml);
        Ok((yaml, grid))
    }

    /// The cells of `raster` as the map_server reads them with the settings of `yaml`:
    /// a pixel's shade is the mean of its colour samples (with alpha averaged in, in
    /// `trinary` mode) over the full sample value, its occupancy `1 - shade` (or `shade`
    /// when negated), then thresholded as [`MapMode`] says.
    pub fn from_raster(raster: &Raster, yaml: &MapYaml) -> Self {
        let (width, height) = (raster.width, raster.height);
        let colours = if raster.has_alpha() {
            raster.channels - 1
        } else {
            raster.channels
        };
        let max = f64::from(raster.max_value);
        let mut cells = Vec::with_capacity(width * height);
        for y in 0..height {
            let row = height - 1 - y;
            for x in 0..width {
                let px = raster.pixel(x, row);
                let alpha = raster.has_alpha().then(|| px[raster.channels - 1]);
                let mut sum: f64 = px[..colours].iter().map(|&s| f64::from(s)).sum();
                let mut n = colours as f64;
                if let (MapMode::Trinary, Some(a)) = (yaml.mode, alpha) {
                    sum += f64::from(a);
                    n += 1.0;
                }
                let shade = sum / n / max;
                let occ = if yaml.negate { shade } else { 1.0 - shade };
                let threshold = |occ: f64| {
                    if yaml.occupied_thresh < occ {
                        Cell::Occupied
                    } else if occ < yaml.free_thresh {
                        Cell::Free
                    } else {
                        Cell::Unknown
                    }
                };
                cells.push(match yaml.mode {
                    MapMode::Trinary => threshold(occ),
                    MapMode::Scale if alpha.is_some_and(|a| a != raster.max_value) => Cell::Unknown,
                    MapMode::Scale => threshold(occ),
                    MapMode::Raw => {
                        let percent = (shade * 255.0).round();
                        if percent > 100.0 {
                            Cell::Unknown
                        } else {
                            threshold(percent / 100.0)
                        }
                    }
                });
            }
        }
        Self {
            width,
            height,
            resolution_m: yaml.resolution_m,
            origin_m: yaml.origin_m,
            cells,
        }
    }

    /// A grid of `width` x `height` `cells` (row by row from the bottom one) of
    /// `resolution_m` with cell (0, 0) at `origin_m`.
    ///
    /// # Panics
    /// If `cells` does not hold `width * height` cells.
    pub fn from_cells(
        width: usize,
        height: usize,
        resolution_m: f64,
        origin_m: [f64; 2],
        cells: Vec<Cell>,
    ) -> Self {
        assert_eq!(
            cells.len(),
            width * height,
            "cells of a {width} x {height} grid"
        );
        Self {
            width,
            height,
            resolution_m,
            origin_m,
            cells,
        }
    }

    /// The cell in column `x` and row `y` (row 0 the bottom one).
    ///
    /// # Panics
    /// If `x >= width` or `y >= height`.
    pub fn cell(&self, x: usize, y: usize) -> Cell {
        assert!(
            x < self.width && y < self.height,
            "cell ({x}, {y}) is off the map"
        );
        self.cells[y * self.width + x]
    }

    /// Every cell, row by row from the bottom one.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// How many cells hold `what`.
    pub fn count(&self, what: Cell) -> usize {
        self.cells.iter().filter(|&&c| c == what).count()
    }

    /// The centre of cell (x, y), metres.
    pub fn cell_centre(&self, x: usize, y: usize) -> Point {
        self.corner_point([x, y]) + nalgebra::Vector2::repeat(0.5 * self.resolution_m)
    }

    /// The cell at `p`, if `p` lies on the map (a point on a side between two cells
    /// belongs to the upper or right one).
    pub fn cell_at(&self, p: &Point) -> Option<[usize; 2]> {
        let fx = ((p.x - self.origin_m[0]) / self.resolution_m).floor();
        let fy = ((p.y - self.origin_m[1]) / self.resolution_m).floor();
        (fx >= 0.0 && fy >= 0.0 && fx < self.width as f64 && fy < self.height as f64)
            .then_some([fx as usize, fy as usize])
    }

    /// A cell corner in metres.
    pub fn corner_point(&self, [i, j]: CellCorner) -> Point {
        Point::new(
            self.origin_m[0] + i as f64 * self.resolution_m,
            self.origin_m[1] + j as f64 * self.resolution_m,
        )
    }

    /// The outlines of the cells for which `blocked` holds (occupied ones, and unknown
    /// ones unless they count as free), as [`outline_cells`] gives them, in metres.
    pub fn outlines(&self, blocked: impl Fn(Cell) -> bool) -> Vec<Vec<Point>> {
        outline_cells(self.width, self.height, |x, y| {
            blocked(self.cells[y * self.width + x])
        })
        .iter()
        .map(|ring| ring.iter().map(|&c| self.corner_point(c)).collect())
        .collect()
    }
}
