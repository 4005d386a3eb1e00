//! The regions a map's walls close off are a sound proof of unreachability: on random
//! grids, a goal they set apart from the start has no path (the search without them,
//! run to the end, finds none), and with them every shortest path is the same, bit for
//! bit, as without them.

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use shared::best_point::nearest_free_point;
use shared::disk_path::{PathError, shortest_path};
use shared::geometry::{DiskGrid, Field, FreeSpace, InflatedPolygon, Point, PolygonLayer, Vector};
use shared::occupancy::{Cell, OccupancyGrid};

const CELLS: usize = 10;
const CELL_M: f64 = 0.5;
const RADIUS_M: f64 = 0.2;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn goals_set_apart_by_the_regions_have_no_path(
        seed in any::<u64>(),
        density in 0.15f64..0.45,
        s in (0.0..5.0f64, 0.0..5.0f64),
        t in (0.0..5.0f64, 0.0..5.0f64),
    ) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let cells: Vec<Cell> = (0..CELLS * CELLS)
            .map(|_| if rng.random_bool(density) { Cell::Occupied } else { Cell::Free })
            .collect();
        let grid = OccupancyGrid::from_cells(CELLS, CELLS, CELL_M, [0.0, 0.0], cells);
        let blocked = |c: Cell| c == Cell::Occupied;
        let pieces = PolygonLayer::new(
            grid.pieces(blocked)
                .into_iter()
                .map(|p| InflatedPolygon::from_polygon(p, RADIUS_M))
                .collect(),
        );
        let regions = grid.regions(blocked, RADIUS_M - shared::disk_path::FREE_TOLERANCE_M, Vector::zeros());
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
