//! Maps on random grids, their blocked cells cut into pieces:
//! - the best point is exactly the nearest free point: free, and no free point of a fine
//!   grid (checked against the plain cells, not the grown pieces) is nearer the query;
//! - the regions a map's walls close off are a sound proof of unreachability: a goal they
//!   set apart from the start has no path (the search without them, run to the end, finds
//!   none), and with them every shortest path is the same, bit for bit, as without them.

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use shared::control::best_point::nearest_free_point;
use shared::geometry::{DiskGrid, Field, FreeSpace, InflatedPolygon, Point, PolygonLayer, Vector};
use shared::paths::disk_path::{PathError, shortest_path};
use shared::world::maps::{Cell, OccupancyGrid};

const CELLS: usize = 10;
const CELL_M: f64 = 0.5;
const RADIUS_M: f64 = 0.2;

/// A random `CELLS` x `CELLS` grid of `CELL_M` cells, each occupied with `density`.
fn random_grid(seed: u64, density: f64) -> OccupancyGrid {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let cells: Vec<Cell> = (0..CELLS * CELLS)
        .map(|_| {
            if rng.random_bool(density) {
                Cell::Occupied
            } else {
                Cell::Free
            }
        })
        .collect();
    OccupancyGrid::from_cells(CELLS, CELLS, CELL_M, [0.0, 0.0], cells)
}

/// Distance from `p` to the nearest occupied cell of `grid` (0 inside one), in plain
/// geometry: each cell a square.
fn distance_to_cells_m(grid: &OccupancyGrid, p: &Point) -> f64 {
    let mut best = f64::INFINITY;
    for y in 0..grid.height {
        for x in 0..grid.width {
            if grid.cell(x, y) != Cell::Occupied {
                continue;
            }
            let (x0, y0) = (x as f64 * CELL_M, y as f64 * CELL_M);
            let dx = (x0 - p.x).max(p.x - (x0 + CELL_M)).max(0.0);
            let dy = (y0 - p.y).max(p.y - (y0 + CELL_M)).max(0.0);
            best = best.min(dx.hypot(dy));
        }
    }
    best
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn the_best_point_among_a_maps_cells_beats_a_fine_grid(
        seed in any::<u64>(),
        density in 0.1f64..0.5,
        q in (0.0..5.0f64, 0.0..5.0f64),
    ) {
        let grid = random_grid(seed, density);
        let pieces = PolygonLayer::new(
            grid.pieces(|c| c == Cell::Occupied)
                .into_iter()
                .map(|p| InflatedPolygon::from_polygon(p, RADIUS_M))
                .collect(),
        );
        let field = Field::new(CELLS as f64 * CELL_M, CELLS as f64 * CELL_M);
        let none = DiskGrid::new(Vec::new());
        let layers = [&none];
        let space = FreeSpace::new(field, &layers).with_polygons(&pieces);
        let query = Point::new(q.0, q.1);
        let Ok(best) = nearest_free_point(&space, &query) else {
            // Then no point of the fine grid is free either.
            for i in 0..=100 {
                for j in 0..=100 {
                    let g = Point::new(i as f64 * 0.05, j as f64 * 0.05);
                    prop_assert!(distance_to_cells_m(&grid, &g) < RADIUS_M, "{g:?} is free");
                }
            }
            return Ok(());
        };
        // Free, checked against the plain cells.
        prop_assert!(distance_to_cells_m(&grid, &best) >= RADIUS_M - 1e-9, "{best:?}");
        prop_assert!(field.contains(&best, 1e-9));
        let d_best = (best - query).norm();
        for i in 0..=100 {
            for j in 0..=100 {
                let g = Point::new(i as f64 * 0.05, j as f64 * 0.05);
                if distance_to_cells_m(&grid, &g) >= RADIUS_M {
                    prop_assert!((g - query).norm() >= d_best - 1e-9,
                        "{g:?} is free and nearer {query:?} than {best:?}");
                }
            }
        }
    }

}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn goals_set_apart_by_the_regions_have_no_path(
        seed in any::<u64>(),
        density in 0.15f64..0.45,
        s in (0.0..5.0f64, 0.0..5.0f64),
        t in (0.0..5.0f64, 0.0..5.0f64),
    ) {
        let grid = random_grid(seed, density);
        let blocked = |c: Cell| c == Cell::Occupied;
        let pieces = PolygonLayer::new(
            grid.pieces(blocked)
                .into_iter()
                .map(|p| InflatedPolygon::from_polygon(p, RADIUS_M))
                .collect(),
        );
        let regions = grid.regions(blocked, RADIUS_M - shared::paths::disk_path::FREE_TOLERANCE_M, Vector::zeros());
        let field = Field::new(CELLS as f64 * CELL_M, CELLS as f64 * CELL_M);
        let none = DiskGrid::new(Vec::new());
        let layers = [&none];
        let plain = FreeSpace::new(field, &layers).with_polygons(&pieces);
        let with_regions = plain.with_regions(Some(&regions));
        // Free end points: the nearest free points to the random ones.
        let free = |p: (f64, f64)| nearest_free_point(&plain, &Point::new(p.0, p.1));
        let (Ok(s), Ok(t)) = (free(s), free(t)) else {
            return Ok(());
        };
        let without = shortest_path(&plain, &s, &t);
        if regions.apart(&s, &t) {
            prop_assert!(
                matches!(without, Err(PathError::Unreachable | PathError::StartNotFree | PathError::GoalNotFree)),
                "set apart, yet a path: {without:?}"
            );
        }
        let with = shortest_path(&with_regions, &s, &t);
        prop_assert_eq!(format!("{with:?}"), format!("{without:?}"));
    }
}
