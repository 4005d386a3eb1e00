//! Cost of the exact best point (Theorem 1) as the field fills up.
//!
//! Fields hold disks of radius 1.3 m (already inflated) at uniformly random seeded
//! positions, at a realistic density of one disk per 100 m^2 (8 disks in 28.3 m x 28.3 m,
//! 100 in 100 m x 100 m, 10 000 in 1000 m x 1000 m), plus a crowded field of 10 000 disks
//! in 300 m x 300 m (one per 9 m^2, about 45 % of the field covered, heavy overlaps).
//! Queries either land inside a disk (the non-trivial case) or are free.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::best_point::nearest_free_point;
use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point, Vector};

/// Radius of every (inflated) disk, in metres.
const DISK_RADIUS_M: f64 = 1.3;
/// Queries per kind, cycled through by the benchmark loop.
const QUERY_COUNT: usize = 1024;

/// A seeded splitmix64 generator: reproducible fields without a `rand` dependency.
struct SplitMix64(u64);

impl SplitMix64 {
    /// A uniform number in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (z ^ (z >> 31)) as f64 / (u64::MAX as f64 + 1.0)
    }
}

/// A field of `count` disks, queries inside disks, and free queries.
struct Workload {
    field: Field,
    grid: DiskGrid,
    inside_queries: Vec<Point>,
    free_queries: Vec<Point>,
}

fn workload(count: usize, side_m: f64, seed: u64) -> Workload {
    let mut rng = SplitMix64(seed);
    let field = Field::new(side_m, side_m);
    let disks: Vec<Disk> = (0..count)
        .map(|_| Disk::new(rng.unit() * side_m, rng.unit() * side_m, DISK_RADIUS_M))
        .collect();
    let inside_queries = (0..QUERY_COUNT)
        .map(|_| {
            let disk = disks[(rng.unit() * count as f64) as usize % count];
            // Uniform over the disk area.
            let r = DISK_RADIUS_M * rng.unit().sqrt();
            let a = std::f64::consts::TAU * rng.unit();
            disk.center + r * Vector::new(a.cos(), a.sin())
        })
        .collect();
    let grid = DiskGrid::new(disks);
    let mut free_queries = Vec::with_capacity(QUERY_COUNT);
    {
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        while free_queries.len() < QUERY_COUNT {
            let p = Point::new(rng.unit() * side_m, rng.unit() * side_m);
            if space.is_free(&p, 0.0) {
                free_queries.push(p);
            }
        }
    }
    Workload {
        field,
        grid,
        inside_queries,
        free_queries,
    }
}

fn bench_best_point(c: &mut Criterion) {
    let cases = [
        ("8_disks_28m", 8, 8f64.sqrt() * 10.0),
        ("100_disks_100m", 100, 100.0),
        ("10000_disks_1000m", 10_000, 1000.0),
        ("10000_disks_300m_crowded", 10_000, 300.0),
    ];
    let mut group = c.benchmark_group("nearest_free_point");
    for (seed, (name, count, side_m)) in cases.into_iter().enumerate() {
        let work = workload(count, side_m, 0x5eed + seed as u64);
        let layers = [&work.grid];
        let space = FreeSpace::new(work.field, &layers);
        for (kind, queries) in [
            ("inside", &work.inside_queries),
            ("free", &work.free_queries),
        ] {
            let mut next = 0;
            group.bench_function(format!("{name}/{kind}"), |b| {
                b.iter(|| {
                    next = (next + 1) % queries.len();
                    black_box(nearest_free_point(&space, black_box(&queries[next])))
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_best_point);
criterion_main!(benches);
