//! Property tests for polygon obstacles (grown by the agent's radius) beside disks,
//! checked by brute force independently of the grown-polygon geometry under test:
//!
//! - the best point is free, no free point of a fine grid (0.05 m) is nearer to the
//!   query, and a step from it towards the query enters an obstacle;
//! - the shortest path keeps clear of every polygon and disk on dense samples, is never
//!   longer than a path found by Dijkstra on a fine grid whose every edge is proven free,
//!   and is `Unreachable` only when that grid finds nothing either;
//! - a segment's distance to a grown polygon is the least distance of its points.
//!
//! "Independently" means through the polygon's plain distance ([`Polygon::distance_m`],
//! tested on its own), never through [`InflatedPolygon`], its offset sides or its
//! corner circles.

use proptest::prelude::*;
use proptest::test_runner::Config;
use shared::control::best_point::nearest_free_point;
use shared::geometry::{
    Disk, DiskGrid, Field, FreeSpace, InflatedPolygon, Point, Polygon, PolygonLayer,
};
use shared::paths::disk_path::{PathError, shortest_path};

const FIELD_M: f64 = 10.0;

/// A small deterministic generator, so one proptest seed gives one whole world.
struct Rng(u64);

impl Rng {
    fn next_unit(&mut self) -> f64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_unit()
    }
}

/// A random world: a few star-shaped polygons (convex or not) and disks, every one
/// grown by the same agent radius.
struct World {
    field: Field,
    polygons: Vec<(Polygon, f64)>,
    disks: Vec<Disk>,
}

impl World {
    fn random(seed: u64) -> Self {
        let mut rng = Rng(seed | 1);
        let radius_m = rng.range(0.05, 0.6);
        let mut polygons = Vec::new();
        let count = 1 + (rng.next_unit() * 3.0) as usize;
        while polygons.len() < count {
            let centre = Point::new(rng.range(1.0, 9.0), rng.range(1.0, 9.0));
            let n = 3 + (rng.next_unit() * 6.0) as usize;
            let gaps: Vec<f64> = (0..n).map(|_| rng.range(0.2, 1.0)).collect();
            let total: f64 = gaps.iter().sum();
            let mut angle = rng.range(0.0, std::f64::consts::TAU);
            let vertices = gaps
                .iter()
                .map(|gap| {
                    angle += gap / total * std::f64::consts::TAU;
                    let r = rng.range(0.3, 2.2);
                    centre + r * nalgebra::Vector2::new(angle.cos(), angle.sin())
                })
                .collect();
            if let Ok(polygon) = Polygon::new(vertices) {
                polygons.push((polygon, radius_m));
            }
        }
        let disks = (0..(rng.next_unit() * 4.0) as usize)
            .map(|_| {
                Disk::new(
                    rng.range(0.0, FIELD_M),
                    rng.range(0.0, FIELD_M),
                    rng.range(0.2, 1.2) + radius_m,
                )
            })
            .collect();
        Self {
            field: Field::new(FIELD_M, FIELD_M),
            polygons,
            disks,
        }
    }

    fn grown(&self) -> Vec<InflatedPolygon> {
        self.polygons
            .iter()
            .map(|(p, r)| InflatedPolygon::from_polygon(p.clone(), *r))
            .collect()
    }

    /// Signed clearance of `p` from every obstacle and the field edges, by brute force.
    fn clearance_m(&self, p: &Point) -> f64 {
        let to_edges = p.x.min(p.y).min(FIELD_M - p.x).min(FIELD_M - p.y);
        let to_disks = self
            .disks
            .iter()
            .map(|d| (p - d.centre).norm() - d.radius_m)
            .fold(f64::INFINITY, f64::min);
        let to_polygons = self
            .polygons
            .iter()
            .map(|(polygon, r)| polygon.distance_m(p) - r)
            .fold(f64::INFINITY, f64::min);
        to_edges.min(to_disks).min(to_polygons)
    }
}

/// Dijkstra on an 8-connected grid of step `h_m` plus the two end points, every edge
/// proven free (the clearance at its middle is at least half its length, and clearance
/// changes no faster than distance): the length of a genuinely free path, or `None`.
fn grid_path_length_m(world: &World, from: &Point, to: &Point, h_m: f64) -> Option<f64> {
    let n = (FIELD_M / h_m).round() as i64 + 1;
    let node_point = |i: i64| Point::new((i % n) as f64 * h_m, (i / n) as f64 * h_m);
    let (start, goal) = (n * n, n * n + 1);
    let point = |i: i64| match i {
        i if i == start => *from,
        i if i == goal => *to,
        i => node_point(i),
    };
    let edge_is_free = |a: &Point, b: &Point| {
        let middle = nalgebra::center(a, b);
        world.clearance_m(&middle) >= 0.5 * (b - a).norm()
    };
    // The grid nodes near an end point, which it joins directly.
    let near = |p: &Point| -> Vec<i64> {
        let (cx, cy) = ((p.x / h_m).round() as i64, (p.y / h_m).round() as i64);
        let mut out = Vec::new();
        for y in cy - 2..=cy + 2 {
            for x in cx - 2..=cx + 2 {
                if (0..n).contains(&x) && (0..n).contains(&y) {
                    out.push(y * n + x);
                }
            }
        }
        out
    };
    let (near_from, near_to) = (near(from), near(to));
    let scale = 1e9;
    let successors = |&i: &i64| -> Vec<(i64, u64)> {
        let p = point(i);
        let mut next: Vec<i64> = Vec::new();
        if i == start {
            next.extend(&near_from);
        } else if i != goal {
            let (x, y) = (i % n, i / n);
            for (dx, dy) in [
                (1, 0),
                (-1, 0),
                (0, 1),
                (0, -1),
                (1, 1),
                (1, -1),
                (-1, 1),
                (-1, -1),
            ] {
                let (nx, ny) = (x + dx, y + dy);
                if (0..n).contains(&nx) && (0..n).contains(&ny) {
                    next.push(ny * n + nx);
                }
            }
            if near_to.contains(&i) {
                next.push(goal);
            }
        }
        next.into_iter()
            .filter(|&j| edge_is_free(&p, &point(j)))
            .map(|j| (j, ((point(j) - p).norm() * scale).ceil() as u64))
            .collect()
    };
    pathfinding::prelude::dijkstra(&start, successors, |&i| i == goal)
        .map(|(_, cost)| cost as f64 / scale)
}

proptest! {
    #![proptest_config(Config { cases: 256, failure_persistence: None, ..Config::default() })]

    #[test]
    fn best_point_beats_a_fine_grid_and_sits_on_the_obstacles(seed in any::<u64>(), qx in 0.0..FIELD_M, qy in 0.0..FIELD_M) {
        let world = World::random(seed);
        let grid = DiskGrid::new(world.disks.clone());
        let layers = [&grid];
        let grown = world.grown();
        let grown = PolygonLayer::new(grown);
        let space = FreeSpace::new(world.field, &layers).with_polygons(&grown);
        let query = Point::new(qx, qy);

        let h_m = 0.05;
        let steps = (FIELD_M / h_m).round() as i64;
        let mut grid_best_m = f64::INFINITY;
        for y in 0..=steps {
            for x in 0..=steps {
                let p = Point::new(x as f64 * h_m, y as f64 * h_m);
                if world.clearance_m(&p) >= 0.0 {
                    grid_best_m = grid_best_m.min((p - query).norm());
                }
            }
        }
        match nearest_free_point(&space, &query) {
            Err(_) => prop_assert!(grid_best_m.is_infinite(), "no best point, but the grid has a free point {grid_best_m} m away"),
            Ok(best) => {
                prop_assert!(world.clearance_m(&best) >= -1e-9, "best point {best:?} is not free: {}", world.clearance_m(&best));
                let best_m = (best - query).norm();
                prop_assert!(best_m <= grid_best_m + 1e-9, "best point {best_m} m away, a grid point {grid_best_m} m");
                if best_m > 1e-6 {
                    let nearer = best + (query - best) * (1e-6 / best_m);
                    prop_assert!(world.clearance_m(&nearer) < 0.0, "a step from {best:?} towards the query is still free");
                }
            }
        }
    }

    #[test]
    fn shortest_path_is_clear_and_never_longer_than_a_proven_grid_path(seed in any::<u64>(), s in (0.0..FIELD_M, 0.0..FIELD_M), t in (0.0..FIELD_M, 0.0..FIELD_M)) {
        let world = World::random(seed);
        let grid = DiskGrid::new(world.disks.clone());
        let layers = [&grid];
        let grown = world.grown();
        let grown = PolygonLayer::new(grown);
        let space = FreeSpace::new(world.field, &layers).with_polygons(&grown);
        // Free end points: the best points of random queries.
        let (Ok(from), Ok(to)) = (
            nearest_free_point(&space, &Point::new(s.0, s.1)),
            nearest_free_point(&space, &Point::new(t.0, t.1)),
        ) else {
            return Ok(());
        };
        let grid_m = grid_path_length_m(&world, &from, &to, 0.1);
        match shortest_path(&space, &from, &to) {
            Ok(path) => {
                prop_assert_eq!((path.start(), path.end()), (from, to));
                for p in path.sample(1e-3) {
                    prop_assert!(world.clearance_m(&p) >= -1e-7, "path point {p:?} has clearance {}", world.clearance_m(&p));
                }
                if let Some(grid_m) = grid_m {
                    prop_assert!(path.length_m() <= grid_m + 1e-9, "path {} m, a proven grid path {grid_m} m", path.length_m());
                }
            }
            Err(PathError::Unreachable) => prop_assert!(grid_m.is_none(), "unreachable, but the grid found {grid_m:?} m"),
            Err(e) => prop_assert!(false, "free end points refused: {e}"),
        }
    }

    #[test]
    fn segment_distance_is_the_least_distance_of_its_points(seed in any::<u64>(), a in (0.0..FIELD_M, 0.0..FIELD_M), b in (0.0..FIELD_M, 0.0..FIELD_M)) {
        let world = World::random(seed);
        let (a, b) = (Point::new(a.0, a.1), Point::new(b.0, b.1));
        for (polygon, r) in &world.polygons {
            let grown = InflatedPolygon::from_polygon(polygon.clone(), *r);
            let exact = grown.signed_distance_to_segment_m(&a, &b);
            let samples = 2000;
            let least = (0..=samples)
                .map(|i| a + (b - a) * (i as f64 / samples as f64))
                .map(|p| polygon.distance_m(&p) - r)
                .fold(f64::INFINITY, f64::min);
            // Both blocked, or equal within the sample spacing.
            let spacing_m = (b - a).norm() / samples as f64;
            if least > 0.0 || exact > 0.0 {
                prop_assert!(exact <= least + 1e-12 && exact >= least - spacing_m, "segment {exact}, samples {least}");
            } else {
                prop_assert!(exact <= 0.0);
            }
        }
    }
}
