//! `[map]`: the occupancy map read, placed, its digest checked, and its blocked cells cut
//! into polygon pieces.

use std::path::Path;

use super::{Checker, MAX_FIELD_SIDE_M, num};
use crate::geometry::{Field, Point, Polygon};
use crate::world::maps::MAX_MAP_CELLS;
use crate::world::maps::OccupancyGrid;
use crate::world::scenario::ScenarioError;
use crate::world::scenario::ScenarioMap;
use crate::world::scenario::file::MapFile;

/// Most polygon pieces a map may be cut into: far more than a building floor at 5 cm
/// (the depot map gives a few hundred), and a bound on the work of every turn.
pub const MAX_MAP_PIECES: usize = 50_000;

impl Checker<'_> {
    /// The map of `raw`: read from its YAML file (relative to the scenario file's
    /// folder), or from its inline cells; placed; its pieces numbered from
    /// `first_piece`.
    pub(super) fn map(
        &self,
        raw: &MapFile,
        first_piece: usize,
    ) -> Result<ScenarioMap, ScenarioError> {
        let origin_m = match &raw.origin_m {
            None => None,
            Some(origin) => {
                let &[x_m, y_m] = origin.as_slice() else {
                    return Err(self.invalid(
                        "map.origin_m",
                        format!("must be a pair [x_m, y_m], got {} value(s)", origin.len()),
                    ));
                };
                Some([
                    self.finite("map.origin_m[0]", x_m)?,
                    self.finite("map.origin_m[1]", y_m)?,
                ])
            }
        };
        let (source, mut grid) = match (&raw.yaml, &raw.cells) {
            (Some(_), Some(_)) => {
                return Err(self.invalid("map.cells", "give the map's yaml or its cells, not both"));
            }
            (None, None) => {
                return Err(self.invalid("map.yaml", "missing: name the map's YAML file"));
            }
            (Some(yaml), None) => {
                if yaml.trim().is_empty() {
                    return Err(self.invalid("map.yaml", "must name the map's YAML file"));
                }
                for key in [
                    ("map.resolution_m", raw.resolution_m.is_some()),
                    ("map.width_cells", raw.width_cells.is_some()),
                    ("map.height_cells", raw.height_cells.is_some()),
                    ("map.source", raw.source.is_some()),
                ] {
                    if key.1 {
                        return Err(self.invalid(key.0, "goes with map.cells, not with map.yaml"));
                    }
                }
                let folder = Path::new(self.file).parent().unwrap_or(Path::new(""));
                // A map error already reads `FILE: FIELD: REASON`, the file being the map's.
                let (_, grid) = OccupancyGrid::load(&folder.join(yaml)).map_err(|e| {
                    ScenarioError::Invalid {
                        file: self.file.to_string(),
                        field: "map.yaml".into(),
                        reason: e.to_string(),
                    }
                })?;
                (yaml.clone(), grid)
            }
            (None, Some(text)) => {
                let need = |name: &str| self.invalid(name, "missing: map.cells needs it");
                let width = raw.width_cells.ok_or_else(|| need("map.width_cells"))?;
                let height = raw.height_cells.ok_or_else(|| need("map.height_cells"))?;
                let resolution_m = raw.resolution_m.ok_or_else(|| need("map.resolution_m"))?;
                let resolution_m =
                    self.positive("map.resolution_m", resolution_m, MAX_FIELD_SIDE_M)?;
                let origin = origin_m.ok_or_else(|| need("map.origin_m"))?;
                if width == 0 || height == 0 || width.saturating_mul(height) > MAX_MAP_CELLS {
                    return Err(self.invalid(
                        "map.width_cells",
                        format!("{width} x {height} cells: at least 1 x 1 and at most {MAX_MAP_CELLS} cells"),
                    ));
                }
                let cells = ScenarioMap::cells_from_text(text, width, height)
                    .map_err(|e| self.invalid("map.cells", e.to_string()))?;
                let grid = OccupancyGrid::from_cells(width, height, resolution_m, origin, cells);
                (raw.source.clone().unwrap_or_default(), grid)
            }
        };
        if let Some(origin) = origin_m {
            grid.origin_m = origin;
        }
        let unknown_free = match raw.unknown.as_deref() {
            None | Some("obstacle") => false,
            Some("free") => true,
            Some(other) => {
                return Err(self.invalid(
                    "map.unknown",
                    format!("{other:?} is neither \"obstacle\" nor \"free\""),
                ));
            }
        };
        Ok(ScenarioMap {
            source,
            unknown_free,
            grid,
            first_piece,
        })
    }

    /// The field a map gives when the scenario has no `[field]`: from (0, 0) to the map's
    /// upper-right corner.
    pub(super) fn field_of_map(&self, map: &ScenarioMap) -> Result<(f64, f64), ScenarioError> {
        let g = &map.grid;
        let [x_m, y_m] = g.origin_m;
        if x_m < 0.0 || y_m < 0.0 {
            return Err(self.invalid(
                "map.yaml",
                format!(
                    "the map starts at ({}, {}), left of or below the field's corner (0, 0), and there is no [field]: place it with [map] origin_m (origin_m = [0.0, 0.0] puts its lower-left corner there), or give a [field] (the cells outside it are left out)",
                    num(x_m),
                    num(y_m)
                ),
            ));
        }
        let top_right = g.corner_point([g.width, g.height]);
        if !(top_right.x > 0.0 && top_right.y > 0.0) {
            return Err(self.invalid(
                "map.yaml",
                format!(
                    "the map ends at ({}, {}), left of or below the field's corner (0, 0): without a [field], give [map] an origin_m that places it",
                    num(top_right.x),
                    num(top_right.y)
                ),
            ));
        }
        Ok((top_right.x, top_right.y))
    }

    /// The map's blocked cells as polygon pieces, those that meet `field` only.
    pub(super) fn map_pieces(
        &self,
        map: &ScenarioMap,
        field: &Field,
    ) -> Result<Vec<Polygon>, ScenarioError> {
        // Pieces wholly outside the field block nothing an agent can reach: not built.
        let meets_field = |(min, max): (Point, Point)| {
            min.x < field.width_m && min.y < field.height_m && max.x > 0.0 && max.y > 0.0
        };
        let pieces = map
            .grid
            .pieces_meeting(|c| map.blocks(c), meets_field, MAX_MAP_PIECES)
            .map_err(|reached| {
                self.invalid(
                    "map.yaml",
                    format!(
                        "the map's blocked cells make over {MAX_MAP_PIECES} pieces in the field (counting stopped at {reached}), beyond the limit"
                    ),
                )
            })?;
        Ok(pieces)
    }
}
