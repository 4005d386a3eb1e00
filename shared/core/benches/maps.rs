//! Cost of reading a real map: the depot of the Navigation2 project (604 x 307 cells at
//! 0.05 m), its YAML and PGM read and classified, its blocked cells merged into outlines
//! and cut into the polygon pieces a scenario's `[map]` plans round, and the regions its
//! walls close off for one agent.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::geometry::Vector;
use shared::world::maps::{Cell, OccupancyGrid};

fn depot() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/maps/depot.yaml"
    ))
}

fn bench(c: &mut Criterion) {
    let yaml = depot();
    let (_, grid) = OccupancyGrid::load(&yaml).expect("the depot map");
    let rings = grid.outlines(|cell| cell != Cell::Free);
    eprintln!(
        "depot: {} x {} cells, {} outlines, {} corners",
        grid.width,
        grid.height,
        rings.len(),
        rings.iter().map(Vec::len).sum::<usize>()
    );
    c.bench_function("maps/load_depot", |b| {
        b.iter(|| OccupancyGrid::load(black_box(&yaml)).expect("the depot map"))
    });
    c.bench_function("maps/outline_depot", |b| {
        b.iter(|| black_box(&grid).outlines(|cell| cell != Cell::Free))
    });
    c.bench_function("maps/load_and_outline_depot", |b| {
        b.iter(|| {
            let (_, grid) = OccupancyGrid::load(black_box(&yaml)).expect("the depot map");
            grid.outlines(|cell| cell != Cell::Free)
        })
    });
    eprintln!(
        "depot: {} pieces",
        grid.pieces(|cell| cell != Cell::Free).len()
    );
    c.bench_function("maps/load_and_cut_depot_into_pieces", |b| {
        b.iter(|| {
            let (_, grid) = OccupancyGrid::load(black_box(&yaml)).expect("the depot map");
            grid.pieces(|cell| cell != Cell::Free)
        })
    });
    c.bench_function("maps/regions_depot", |b| {
        b.iter(|| black_box(&grid).regions(|cell| cell != Cell::Free, 0.23, Vector::zeros()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
