//! Hybrid A* on the CL-CBS obstacle fields (50 m, 100 m and 300 m maps, 0.8 m obstacles),
//! turning radius 2.5 m, clearance 0.5 m, reverse allowed. For each map the benchmark
//! takes the agents whose plans took longest in a survey of every agent (the hardest
//! searches, not straight shots), plus one forward-only (Dubins) case on a 100 m map.
//!
//! `hybrid_astar_no_path`: the searches that find no path, which end only once every
//! reachable cell has been expanded (the cases of `tests/it/hybrid_astar.rs`): on a
//! 100 m field, the goal and then the start walled in by a ring of 0.8 m obstacles, with
//! and without reverse; on a 20 m field, a forward-only turn inside a ring too tight to
//! make it in.
//!
//! Also the cost of one Reeds-Shepp length (`reeds_shepp/shortest_length_m`), which the
//! search computes for every pose it reaches (its heuristic), on poses spread over a
//! 20 m square round the goal with every heading.
//!
//! Target: under 50 ms median on the 100 m maps. The data is read from
//! `FORMATION_CLCBS_DIR` or, by default, the copy in `shared/core/tests/data/clcbs`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::geometry::{Disk, Field, Pose};
use shared::paths::hybrid_astar::{HybridAStarSettings, PlanError, plan};
use shared::paths::reeds_shepp;
use testkit::clcbs::{ClcbsInstance, default_clcbs_dir};

const TURNING_RADIUS_M: f64 = 2.5;
const CLEARANCE_M: f64 = 0.5;

/// (benchmark id, instance file, agent index, reverse allowed)
const CASES: [(&str, &str, usize, bool); 7] = [
    (
        "50m/ex0-agent9",
        "map_50by50_obst25_agents10_ex0.yaml",
        9,
        true,
    ),
    (
        "50m/ex3-agent19",
        "map_50by50_obst25_agents20_ex3.yaml",
        19,
        true,
    ),
    (
        "100m/ex0-agent5",
        "map_100by100_obst50_agents10_ex0.yaml",
        5,
        true,
    ),
    (
        "100m/ex7-agent1",
        "map_100by100_obst50_agents50_ex7.yaml",
        1,
        true,
    ),
    (
        "100m/ex0-agent8-forward",
        "map_100by100_obst50_agents10_ex0.yaml",
        8,
        false,
    ),
    (
        "300m/ex0-agent4",
        "map_300by300_obst100_agents10_ex0.yaml",
        4,
        true,
    ),
    (
        "300m/ex2-agent50",
        "map_300by300_obst100_agents100_ex2.yaml",
        50,
        true,
    ),
];

fn bench_hybrid_astar(c: &mut Criterion) {
    let mut group = c.benchmark_group("hybrid_astar");
    for (id, file, agent, allow_reverse) in CASES {
        let path = default_clcbs_dir().join(file);
        let instance = ClcbsInstance::load(&path).unwrap_or_else(|e| {
            panic!("{e} (set FORMATION_CLCBS_DIR to the folder of the CL-CBS files)")
        });
        let agent = &instance.agents[agent];
        let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, allow_reverse);
        // Make sure the case plans before timing it.
        if let Err(e) = plan(
            &instance.field,
            &instance.obstacles,
            &agent.start,
            &agent.goal,
            &settings,
        ) {
            panic!("{id}: {e}");
        }
        group.bench_function(id, |b| {
            b.iter(|| {
                plan(
                    black_box(&instance.field),
                    black_box(&instance.obstacles),
                    black_box(&agent.start),
                    black_box(&agent.goal),
                    &settings,
                )
            })
        });
    }
    group.finish();
}

/// A ring of overlapping 0.8 m obstacles of radius `ring_radius_m` round a point: what is
/// inside is walled in.
fn ring_around(center_x: f64, center_y: f64, ring_radius_m: f64) -> Vec<Disk> {
    let count = (std::f64::consts::TAU * ring_radius_m).ceil() as usize;
    (0..count)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / count as f64;
            Disk::new(
                center_x + ring_radius_m * a.cos(),
                center_y + ring_radius_m * a.sin(),
                0.8,
            )
        })
        .collect()
}

/// (benchmark id, field, obstacles, start, goal, reverse allowed): searches that end with
/// no path.
fn no_path_cases() -> Vec<(String, Field, Vec<Disk>, Pose, Pose, bool)> {
    let (field, ring) = (Field::new(100.0, 100.0), ring_around(70.0, 70.0, 6.0));
    let (outside, inside) = (Pose::new(10.0, 10.0, 0.0), Pose::new(70.0, 70.0, 1.0));
    let mut cases = Vec::new();
    for (suffix, allow_reverse) in [("", true), ("-forward", false)] {
        for (what, start, goal) in [("goal", outside, inside), ("start", inside, outside)] {
            let id = format!("enclosed-{what}{suffix}");
            cases.push((id, field, ring.clone(), start, goal, allow_reverse));
        }
    }
    cases.push((
        "tight-pocket-forward".to_string(),
        Field::new(20.0, 20.0),
        ring_around(10.0, 10.0, 3.0),
        Pose::new(10.0, 10.0, 0.0),
        Pose::new(10.0, 10.5, 1.0),
        false,
    ));
    cases
}

fn bench_no_path(c: &mut Criterion) {
    let mut group = c.benchmark_group("hybrid_astar_no_path");
    for (id, field, obstacles, start, goal, allow_reverse) in no_path_cases() {
        let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, allow_reverse);
        // Make sure the case finds no path before timing it.
        let result = plan(&field, &obstacles, &start, &goal, &settings);
        assert_eq!(result, Err(PlanError::NoPath), "{id}");
        group.bench_function(&id, |b| {
            b.iter(|| {
                plan(
                    black_box(&field),
                    black_box(&obstacles),
                    black_box(&start),
                    black_box(&goal),
                    &settings,
                )
            })
        });
    }
    group.finish();
}

/// Poses on a 21 x 21 grid of 1 m over a square round the origin, headings in 16ths of a
/// turn (a quasi-random mix, so no branch is learnt).
fn spread_poses() -> Vec<Pose> {
    let mut poses = Vec::new();
    for k in 0..21 * 21 * 16 {
        let (x, y, h) = (k % 21, (k / 21) % 21, (k * 7) % 16);
        poses.push(Pose::new(
            x as f64 - 10.0,
            y as f64 - 10.0,
            h as f64 * std::f64::consts::TAU / 16.0,
        ));
    }
    poses
}

fn bench_reeds_shepp_length(c: &mut Criterion) {
    let poses = spread_poses();
    let goal = Pose::new(0.0, 0.0, 0.3);
    let mut group = c.benchmark_group("reeds_shepp");
    let mut i = 0;
    group.bench_function("shortest_length_m", |b| {
        b.iter(|| {
            let from = &poses[i % poses.len()];
            i += 1;
            reeds_shepp::shortest_length_m(black_box(from), black_box(&goal), 0.5)
        })
    });
    group.finish();
}

criterion_group!(
    benches,
    bench_hybrid_astar,
    bench_no_path,
    bench_reeds_shepp_length
);
criterion_main!(benches);
