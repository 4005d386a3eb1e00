//! Cost of the search an agent with a top speed runs when its slot's way crosses an
//! obstacle (`first_move_round_obstacles`), on the narrow passage's wall.
//!
//! The wall of `scenarios/narrow.toml`: 18 disks of radius 0.7 m at x = 20 m, y = 0..8
//! and 12..20 m, a gap between. An agent of radius 0.3 m and top speed 0.5 m whose slot
//! runs along y = 13 m at 0.25 m a step (the centre's step) into the wall, looking ten
//! steps ahead, from each of the places it stands as it nears the wall and goes round it
//! through the gap (the turns on which the search runs in that scenario).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::control::tracking::{first_move_round_obstacles, round_lattice_for};
use shared::control::turn::PLANNING_MARGIN_M;
use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};

mod support;

/// The agent's radius, in metres.
const RADIUS_M: f64 = 0.3;
/// The agent's top speed, in metres a step.
const MAX_STEP_M: f64 = 0.5;
/// The look-ahead, in steps.
const HORIZON_STEPS: usize = 10;

/// The wall, grown by the agent's radius and the planning margin.
fn wall() -> DiskGrid {
    let grown_m = 0.7 + RADIUS_M + PLANNING_MARGIN_M;
    DiskGrid::new(
        (0..=20)
            .filter(|y| !(9..=11).contains(y))
            .map(|y| Disk::new(20.0, f64::from(y), grown_m))
            .collect(),
    )
}

/// Where the agent stands and its slot's next positions, on each turn of the approach:
/// the slot from x = 16.5 m to 21 m, the agent on its slot until the wall stops it,
/// then down the wall's near side and into the gap (every place free).
fn turns() -> Vec<(Point, Vec<Point>)> {
    let stands = |x: f64| match x {
        x if x <= 18.99 => Point::new(x, 13.0),
        x if x <= 20.0 => Point::new(18.99, 13.0 - 2.1 * (x - 19.0).max(0.0)),
        x => Point::new(18.99 + (x - 20.0), 10.9),
    };
    (0..19)
        .map(|t| {
            let x = 16.5 + 0.25 * f64::from(t);
            let slots = (1..=HORIZON_STEPS)
                .map(|j| Point::new(x + 0.25 * j as f64, 13.0))
                .collect();
            (stands(x), slots)
        })
        .collect()
}

fn bench_round_obstacles(c: &mut Criterion) {
    let wall = wall();
    let layers = [&wall];
    let space = FreeSpace::new(Field::new(40.0, 20.0), &layers);
    let turns = turns();
    assert!(turns.iter().all(|(me, _)| space.is_free(me, 0.0)));
    let lattice = round_lattice_for(RADIUS_M);
    let search = |(me, slots): &(Point, Vec<Point>)| {
        first_move_round_obstacles(&space, &space, me, slots, &[], MAX_STEP_M, lattice)
    };
    // Every turn finds a move within the top speed (the bench measures real searches).
    for turn in &turns {
        let first = search(turn).expect("a move round the wall");
        assert!((first - turn.0).norm() <= MAX_STEP_M + 1e-9);
    }
    let mut i = 0;
    c.bench_function("round_obstacles/narrow_wall", |b| {
        b.iter(|| {
            i = (i + 1) % turns.len();
            black_box(search(black_box(&turns[i])))
        })
    });
    support::print_best_of_five_percentiles("round_obstacles/narrow_wall", turns.len(), |i| {
        black_box(search(&turns[i]));
    });
}

criterion_group!(benches, bench_round_obstacles);
criterion_main!(benches);
