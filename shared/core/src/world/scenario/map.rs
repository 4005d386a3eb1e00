//! The occupancy map a scenario's obstacles come from (`[map]`): the cells as read, where
//! the scenario places them, written inline in a resolved scenario, and the copy of it a
//! run keeps for the map tools.

use std::path::Path;

use crate::output_file::{real_folder, write_replacing};
use crate::world::maps::{Cell, OccupancyGrid};

/// The occupancy map a scenario's obstacles come from (`[map]`).
///
/// Its blocked cells (occupied ones, and unknown ones unless `unknown = "free"`) are the
/// scenario's polygon obstacles from [`ScenarioMap::first_piece`] on
/// ([`OccupancyGrid::pieces`]), so every part that plans round polygons or checks moves
/// against them works on the map as it is, cell side by cell side.
///
/// A resolved scenario (the run's `scenario.toml`, the agents' mission, the run log)
/// holds the cells themselves ([`ScenarioMap::cells_text`]), so it loads alone, in any
/// process, with nothing beside it.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioMap {
    /// Where the cells were read from: the map's YAML file as the scenario names it.
    pub source: String,
    /// Whether unknown cells are free (`unknown = "free"`); else they are obstacles.
    pub unknown_free: bool,
    /// The cells, placed where the scenario puts them (the YAML's origin, or the
    /// scenario's `origin_m`).
    pub grid: OccupancyGrid,
    /// The index in [`Scenario::polygons`](super::Scenario::polygons) of the map's first
    /// piece: the polygons of `[[obstacles.polygon]]` come first, then the map's.
    pub first_piece: usize,
}

/// Why the inline cells of a `[map]` cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CellsTextError {
    /// A run that is not a count followed by `f`, `o` or `u`.
    #[error("run {run}: {reason}")]
    BadRun {
        /// The run, from 0.
        run: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// The runs do not add up to the grid's cells.
    #[error("the runs hold {found} cells, the {width} x {height} map {expected}")]
    WrongCount {
        /// Cells per row.
        width: usize,
        /// Rows.
        height: usize,
        /// `width * height`.
        expected: usize,
        /// What the runs hold (at least the expected count plus one when over).
        found: usize,
    },
}

impl ScenarioMap {
    /// Whether a cell holding `cell` is an obstacle.
    pub fn blocks(&self, cell: Cell) -> bool {
        match cell {
            Cell::Free => false,
            Cell::Occupied => true,
            Cell::Unknown => !self.unknown_free,
        }
    }

    /// The cells as text, run-length encoded row by row from the bottom row: each run a
    /// count and a letter, `f` free, `o` occupied, `u` unknown (`604o1f...`).
    ///
    /// ```
    /// use shared::world::maps::{Cell, OccupancyGrid};
    /// use shared::world::scenario::ScenarioMap;
    /// let cells = vec![Cell::Occupied, Cell::Occupied, Cell::Free, Cell::Unknown];
    /// let grid = OccupancyGrid::from_cells(2, 2, 0.5, [0.0, 0.0], cells);
    /// assert_eq!(ScenarioMap::cells_text(&grid), "2o1f1u");
    /// assert_eq!(ScenarioMap::cells_from_text("2o1f1u", 2, 2).unwrap(), grid.cells());
    /// assert!(ScenarioMap::cells_from_text("2o1f", 2, 2).is_err());
    /// ```
    pub fn cells_text(grid: &OccupancyGrid) -> String {
        let mut out = String::new();
        let mut run: Option<(Cell, usize)> = None;
        for &cell in grid.cells() {
            run = match run {
                Some((c, n)) if c == cell => Some((c, n + 1)),
                Some((c, n)) => {
                    push_run(&mut out, c, n);
                    Some((cell, 1))
                }
                None => Some((cell, 1)),
            };
        }
        if let Some((c, n)) = run {
            push_run(&mut out, c, n);
        }
        out
    }

    /// The `width * height` cells of `text` ([`ScenarioMap::cells_text`]), every run
    /// checked.
    pub fn cells_from_text(
        text: &str,
        width: usize,
        height: usize,
    ) -> Result<Vec<Cell>, CellsTextError> {
        let expected = width.saturating_mul(height);
        let mut cells = Vec::with_capacity(expected.min(crate::world::maps::MAX_MAP_CELLS));
        let mut count: usize = 0;
        let mut run = 0;
        let mut digits = 0;
        for ch in text.chars() {
            if let Some(d) = ch.to_digit(10) {
                count = count
                    .checked_mul(10)
                    .and_then(|c| c.checked_add(d as usize))
                    .filter(|&c| c <= expected)
                    .ok_or(CellsTextError::WrongCount {
                        width,
                        height,
                        expected,
                        found: expected + 1,
                    })?;
                digits += 1;
                continue;
            }
            let cell = match ch {
                'f' => Cell::Free,
                'o' => Cell::Occupied,
                'u' => Cell::Unknown,
                other => {
                    return Err(CellsTextError::BadRun {
                        run,
                        reason: format!("{other:?} is not a cell (f, o or u)"),
                    });
                }
            };
            if digits == 0 || count == 0 {
                return Err(CellsTextError::BadRun {
                    run,
                    reason: "a run needs a count of at least 1 before its letter".into(),
                });
            }
            if cells.len() + count > expected {
                return Err(CellsTextError::WrongCount {
                    width,
                    height,
                    expected,
                    found: cells.len() + count,
                });
            }
            cells.extend(std::iter::repeat_n(cell, count));
            (count, digits) = (0, 0);
            run += 1;
        }
        if digits > 0 {
            return Err(CellsTextError::BadRun {
                run,
                reason: "a count without its letter at the end".into(),
            });
        }
        if cells.len() != expected {
            return Err(CellsTextError::WrongCount {
                width,
                height,
                expected,
                found: cells.len(),
            });
        }
        Ok(cells)
    }

    /// Write a copy of the map into `dir` (`map/map.yaml` and its image `map/map.pgm`),
    /// for the map tools: a map_server map whose cells read back as these cells, at the
    /// same place. Each file is written under a temporary name and renamed, never through a
    /// symbolic link ([`crate::output_file`]).
    pub fn write_copy(&self, dir: &Path) -> std::io::Result<()> {
        let g = &self.grid;
        let folder = dir.join("map");
        // The run folder may be someone else's (`render`, `run --resume`): a link at
        // `map` is refused, never followed.
        real_folder(&folder)?;
        let mut pgm = format!("P5\n{} {}\n255\n", g.width, g.height).into_bytes();
        pgm.reserve(g.width * g.height);
        // The image's first row is the map's top row.
        for y in (0..g.height).rev() {
            pgm.extend((0..g.width).map(|x| shade(g.cell(x, y))));
        }
        let yaml = format!(
            "# The cells of the scenario's map as run: 0 occupied, 255 free, 128 unknown.\n\
             image: map.pgm\nmode: trinary\nresolution: {:?}\norigin: [{:?}, {:?}, 0.0]\n\
             negate: 0\noccupied_thresh: 0.9\nfree_thresh: 0.1\n",
            g.resolution_m, g.origin_m[0], g.origin_m[1]
        );
        write_replacing(&folder.join("map.pgm"), &pgm)?;
        write_replacing(&folder.join("map.yaml"), yaml.as_bytes())
    }
}

/// Append the run of `n` cells `c`.
fn push_run(out: &mut String, c: Cell, n: usize) {
    use std::fmt::Write as _;
    let letter = match c {
        Cell::Free => 'f',
        Cell::Occupied => 'o',
        Cell::Unknown => 'u',
    };
    let _ = write!(out, "{n}{letter}");
}

/// A cell's shade in the copy's image, which its YAML's thresholds (occupied above 0.9,
/// free below 0.1) read back as the same cell.
fn shade(cell: Cell) -> u8 {
    match cell {
        Cell::Free => 255,
        Cell::Occupied => 0,
        Cell::Unknown => 128,
    }
}
