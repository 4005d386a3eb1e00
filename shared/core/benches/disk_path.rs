//! Benchmark of `shortest_path` for typical agent moves: obstacles of inflated radius 1.3 m
//! scattered at random (about 15 % of the field covered), start and goal 0.5-5 m apart,
//! in a field of 100 and one of 10 000 obstacles (same density, so the larger field tests
//! that a query costs what is local). Moves are split into those whose straight segment is
//! free (the fast path) and those that must go around obstacles. Every generator is seeded:
//! the same moves are timed on every run.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};
use shared::paths::disk_path::{PathError, shortest_path};

const RADIUS_M: f64 = 1.3;
/// Field area per obstacle, in square metres (about 15 % covered).
const AREA_PER_OBSTACLE_M2: f64 = 36.0;
const MOVES_PER_KIND: usize = 200;

struct Scene {
    field: Field,
    grid: DiskGrid,
    visible: Vec<(Point, Point)>,
    blocked: Vec<(Point, Point)>,
}

fn scene(obstacles: usize, seed: u64) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let side_m = (obstacles as f64 * AREA_PER_OBSTACLE_M2).sqrt();
    let field = Field::new(side_m, side_m);
    let disks = (0..obstacles)
        .map(|_| {
            Disk::new(
                rng.random::<f64>() * side_m,
                rng.random::<f64>() * side_m,
                RADIUS_M,
            )
        })
        .collect();
    let grid = DiskGrid::new(disks);
    let (mut visible, mut blocked) = (Vec::new(), Vec::new());
    {
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        while visible.len() < MOVES_PER_KIND || blocked.len() < MOVES_PER_KIND {
            let start = Point::new(rng.random::<f64>() * side_m, rng.random::<f64>() * side_m);
            let angle = rng.random::<f64>() * std::f64::consts::TAU;
            let dist_m = 0.5 + 4.5 * rng.random::<f64>();
            let goal = start + dist_m * nalgebra::Vector2::new(angle.cos(), angle.sin());
            if !space.is_free(&start, 0.0) || !space.is_free(&goal, 0.0) {
                continue;
            }
            if space.is_segment_free(&start, &goal, 0.0) {
                if visible.len() < MOVES_PER_KIND {
                    visible.push((start, goal));
                }
            } else if blocked.len() < MOVES_PER_KIND && shortest_path(&space, &start, &goal).is_ok()
            {
                blocked.push((start, goal));
            }
        }
    }
    Scene {
        field,
        grid,
        visible,
        blocked,
    }
}

/// A goal enclosed by a ring of overlapping obstacles, in the middle of the scene.
fn enclosed(scene: &Scene) -> (Vec<Disk>, Point, Point) {
    let c = Point::new(0.5 * scene.field.width_m, 0.5 * scene.field.height_m);
    let ring: Vec<Disk> = (0..10)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 10.0;
            Disk::new(c.x + 3.5 * a.cos(), c.y + 3.5 * a.sin(), RADIUS_M)
        })
        .collect();
    // A free start just outside the ring.
    let layers = [&scene.grid];
    let space = FreeSpace::new(scene.field, &layers);
    let mut start = c;
    for k in 0..400 {
        let a = k as f64 * 0.37;
        let p = c + (6.0 + 0.02 * k as f64) * nalgebra::Vector2::new(a.cos(), a.sin());
        if space.is_free(&p, 0.0) {
            start = p;
            break;
        }
    }
    // Clear the inside of the ring of scene obstacles so the goal is free.
    let mut cleared = Vec::new();
    for d in scene.grid.disks() {
        if (d.centre - c).norm() > 3.0 + RADIUS_M {
            cleared.push(*d);
        }
    }
    cleared.extend(ring);
    (cleared, start, c)
}

fn bench_disk_path(c: &mut Criterion) {
    let mut group = c.benchmark_group("disk_path");
    for (obstacles, seed) in [(100usize, 1u64), (10_000, 2)] {
        let scene = scene(obstacles, seed);
        let layers = [&scene.grid];
        let space = FreeSpace::new(scene.field, &layers);
        for (kind, moves) in [("visible", &scene.visible), ("blocked", &scene.blocked)] {
            let mut i = 0usize;
            group.bench_function(format!("{kind}/{obstacles}"), |b| {
                b.iter(|| {
                    let (s, t) = &moves[i % moves.len()];
                    i += 1;
                    black_box(shortest_path(&space, black_box(s), black_box(t)))
                })
            });
        }
        let (disks, start, goal) = enclosed(&scene);
        let grid = DiskGrid::new(disks);
        let layers = [&grid];
        let space = FreeSpace::new(scene.field, &layers);
        assert_eq!(
            shortest_path(&space, &start, &goal),
            Err(PathError::Unreachable)
        );
        group.bench_function(format!("unreachable/{obstacles}"), |b| {
            b.iter(|| black_box(shortest_path(&space, black_box(&start), black_box(&goal))))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_disk_path);
criterion_main!(benches);
