//! A map's blocked cells as simple polygons without holes ("pieces"), which the exact
//! geometry of grown polygons takes as they are.
//!
//! The outlines of a whole map are rings with holes (a building's outer wall with its
//! free floor inside), which a simple polygon cannot be. So the map is cut into square
//! tiles of [`PIECE_TILE_CELLS`] cells and each tile's blocked cells are outlined on their
//! own; a tile whose outline has a hole is cut in four, down to single cells if need be
//! (a cell has no hole). The pieces cover exactly the blocked cells, their interiors are
//! disjoint, and they meet only along cell sides. A union of polygons grown by a radius is
//! the union grown by it, so the free space round the pieces is exactly the free space
//! round the blocked cells: cutting adds corners inside the union (where a corner circle
//! of one piece lies within the growth of its neighbour) but changes no free point. Those
//! corners are marked as seams ([`Polygon::seams`]), so that no path searches round them.

use crate::geometry::{Point, Polygon};

use super::outline::{CellCorner, outline_cells, ring_area2_cells};
use super::{Cell, OccupancyGrid};

/// The side of the square tiles a map is cut into before outlining, in cells.
pub const PIECE_TILE_CELLS: usize = 16;

impl OccupancyGrid {
    /// The cells for which `blocked` holds, as simple anticlockwise polygons without
    /// holes, in metres: exactly the blocked cells, tile by tile (see the module's doc).
    ///
    /// ```
    /// use shared::world::maps::{Cell, OccupancyGrid};
    /// let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/maps");
    /// let (_, depot) = OccupancyGrid::load(format!("{dir}/depot.yaml").as_ref()).unwrap();
    /// let pieces = depot.pieces(|c| c != Cell::Free);
    /// let cell_m2 = depot.resolution_m * depot.resolution_m;
    /// let blocked_m2 = (depot.width * depot.height - depot.count(Cell::Free)) as f64 * cell_m2;
    /// let area_m2: f64 = pieces.iter().map(|p| p.area_m2()).sum();
    /// assert!((area_m2 - blocked_m2).abs() < 1e-6 * blocked_m2);
    /// ```
    pub fn pieces(&self, blocked: impl Fn(Cell) -> bool) -> Vec<Polygon> {
        let everywhere = |_: (Point, Point)| true;
        // No count passes usize::MAX: never the default.
        self.pieces_meeting(blocked, everywhere, usize::MAX)
            .unwrap_or_default()
    }

    /// [`Self::pieces`], only those whose bounding box (in metres, its corners' least and
    /// greatest coordinates) `meets`, built tile by tile and counted as they are: more
    /// than `max_pieces` is `Err` with the count reached, before the rest of the map is
    /// outlined (a checkerboard map makes a piece of every other cell: millions, which
    /// are never built). A tile whose bounding box `meets` not is skipped: `meets` must
    /// hold of a box if it holds of a box inside it.
    pub fn pieces_meeting(
        &self,
        blocked: impl Fn(Cell) -> bool,
        meets: impl Fn((Point, Point)) -> bool,
        max_pieces: usize,
    ) -> Result<Vec<Polygon>, usize> {
        let blocked_at = |x: usize, y: usize| blocked(self.cell(x, y));
        let corners_box =
            |lo: CellCorner, hi: CellCorner| (self.corner_point(lo), self.corner_point(hi));
        let mut rings = Vec::new();
        for y0 in (0..self.height).step_by(PIECE_TILE_CELLS) {
            for x0 in (0..self.width).step_by(PIECE_TILE_CELLS) {
                let w = PIECE_TILE_CELLS.min(self.width - x0);
                let h = PIECE_TILE_CELLS.min(self.height - y0);
                if !meets(corners_box([x0, y0], [x0 + w, y0 + h])) {
                    continue;
                }
                let before = rings.len();
                tile_rings(&blocked_at, [x0, y0], [w, h], &mut rings);
                let mut kept = before;
                for k in before..rings.len() {
                    let ring: &Vec<CellCorner> = &rings[k];
                    let lo = ring
                        .iter()
                        .fold([usize::MAX; 2], |m, c| [m[0].min(c[0]), m[1].min(c[1])]);
                    let hi = ring
                        .iter()
                        .fold([0; 2], |m, c| [m[0].max(c[0]), m[1].max(c[1])]);
                    if meets(corners_box(lo, hi)) {
                        rings.swap(kept, k);
                        kept += 1;
                    }
                }
                rings.truncate(kept);
                if rings.len() > max_pieces {
                    return Err(rings.len());
                }
            }
        }
        // A corner where the blocked cells round it make no convex corner of their union
        // (two side by side, three, or four) is a seam: the obstacle goes on beyond it.
        let at = |x: usize, y: usize, dx: usize, dy: usize| {
            x >= dx
                && y >= dy
                && x - dx < self.width
                && y - dy < self.height
                && blocked_at(x - dx, y - dy)
        };
        let seam = |[i, j]: CellCorner| {
            let [ll, lr, ul, ur] = [
                at(i, j, 1, 1),
                at(i, j, 0, 1),
                at(i, j, 1, 0),
                at(i, j, 0, 0),
            ];
            let count = [ll, lr, ul, ur].iter().filter(|&&b| b).count();
            let diagonal = count == 2 && ll == ur;
            !(count == 1 || diagonal)
        };
        Ok(rings
            .iter()
            .map(|ring| {
                let corners = ring.iter().map(|&c| self.corner_point(c)).collect();
                Polygon::new_trusted_simple(corners, |k| seam(ring[k]))
            })
            .collect())
    }
}

/// Push the outlines of the blocked cells of the tile at `origin` of `size` cells onto
/// `rings` (in the map's cell corners), cutting the tile in four while an outline has a
/// hole.
fn tile_rings(
    blocked: &impl Fn(usize, usize) -> bool,
    origin: [usize; 2],
    size: [usize; 2],
    rings: &mut Vec<Vec<CellCorner>>,
) {
    let ([x0, y0], [w, h]) = (origin, size);
    let tile = outline_cells(w, h, |x, y| blocked(x0 + x, y0 + y));
    let has_hole = tile.iter().any(|ring| ring_area2_cells(ring) < 0);
    if has_hole && (w > 1 || h > 1) {
        let (w0, h0) = (w.div_ceil(2), h.div_ceil(2));
        for (dx, cw) in [(0, w0), (w0, w - w0)] {
            for (dy, ch) in [(0, h0), (h0, h - h0)] {
                if cw > 0 && ch > 0 {
                    tile_rings(blocked, [x0 + dx, y0 + dy], [cw, ch], rings);
                }
            }
        }
        return;
    }
    rings.extend(
        tile.into_iter()
            .map(|ring| ring.into_iter().map(|[i, j]| [x0 + i, y0 + j]).collect()),
    );
}
