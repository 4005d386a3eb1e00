//! Hybrid A* on the CL-CBS obstacle fields (50 m, 100 m and 300 m maps, 0.8 m obstacles),
//! turning radius 2.5 m, clearance 0.5 m, reverse allowed. For each map the benchmark
//! takes the agents whose plans took longest in a survey of every agent (the hardest
//! searches, not straight shots), plus one forward-only (Dubins) case on a 100 m map.
//!
//! Also the cost of one Reeds-Shepp length (`reeds_shepp/shortest_length_m`), which the
//! search computes for every pose it reaches (its heuristic), on poses spread over a
//! 20 m square round the goal with every heading.
//!
//! Target: under 50 ms median on the 100 m maps. The data is read from
//! `FORMATION_CLCBS_DIR` or, by default, the copy in `shared/tests/data/clcbs`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::geometry::Pose;
use shared::hybrid_astar::{HybridAStarSettings, plan};
use shared::reeds_shepp;
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

criterion_group!(benches, bench_hybrid_astar, bench_reeds_shepp_length);
criterion_main!(benches);
