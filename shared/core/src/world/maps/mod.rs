//! Occupancy-grid maps as ROS's map_server stores them: a YAML file naming a PGM or PNG
//! image, read into cells and merged into exact polygon outlines.
//!
//! One concept per file:
//! - [`yaml`]: the YAML file and its checks ([`MapYaml`], [`MapMode`]);
//! - [`raster`]: the image, PGM read here or PNG, checked against its header ([`Raster`]);
//! - [`grid`]: the cells, free, occupied or unknown, placed in metres ([`OccupancyGrid`]);
//! - [`outline`]: blocked cells merged into rectilinear polygons along the cells' own
//!   sides ([`outline_cells`]);
//! - [`pieces`]: the blocked cells as simple polygons without holes, tile by tile, the
//!   obstacles a scenario's map adds ([`OccupancyGrid::pieces`]);
//! - [`regions`]: the free regions a map's walls close off from each other, a quick proof
//!   that a goal is unreachable ([`OccupancyGrid::regions`]);
//! - [`error`]: why a map was refused ([`MapError`], `FILE: FIELD: REASON`).
//!
//! A rotated map (an `origin` yaw other than 0) is refused; the map's frame is the
//! scenario's, so a cell's corners are `origin + index * resolution`.
//!
//! ```
//! use shared::world::maps::{Cell, OccupancyGrid, ring_area2_cells, outline_cells};
//! let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/maps");
//! let (_, depot) = OccupancyGrid::load(format!("{dir}/depot.yaml").as_ref()).unwrap();
//! // The outlines of the blocked cells enclose exactly their area.
//! let blocked = |x: usize, y: usize| depot.cell(x, y) != Cell::Free;
//! let rings = outline_cells(depot.width, depot.height, blocked);
//! let area2: i64 = rings.iter().map(|r| ring_area2_cells(r)).sum();
//! let cells = depot.width * depot.height - depot.count(Cell::Free);
//! assert_eq!(area2, 2 * cells as i64);
//! ```

pub mod error;
pub mod grid;
pub mod outline;
pub mod pieces;
pub mod raster;
pub mod regions;
pub mod yaml;

#[cfg(test)]
mod tests;

pub use error::MapError;
pub use grid::{Cell, OccupancyGrid};
pub use outline::{CellCorner, outline_cells, ring_area2_cells};
pub use pieces::PIECE_TILE_CELLS;
pub use raster::{MAX_IMAGE_BYTES, Raster};
pub use yaml::{MAX_MAP_YAML_BYTES, MapMode, MapYaml};

/// Most cells of a map (4096 x 4096): a larger image is refused before it is decoded.
pub const MAX_MAP_CELLS: usize = 4096 * 4096;
