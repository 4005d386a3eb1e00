//! Online replanning on the CL-CBS obstacle fields (100 m and 300 m maps, 0.8 m
//! obstacles), turning radius 2.5 m, clearance 0.5 m, reverse allowed, the agents of
//! `benches/hybrid_astar.rs`.
//!
//! For each case a [`Replanner`] plans from the agent's start; then three new obstacles
//! (0.8 m, like the maps') are put on the remaining path and the centre, a third of the
//! way along, replans. Timed, side by side:
//!
//! - `replan`: `Replanner::plan_from` from that pose with the obstacles added, on a copy of
//!   the replanner as it was after the first plan (so each iteration pays for the
//!   incremental update of the heuristic, and reuses what the first plan built);
//! - `plan`: `plan()` from scratch, same pose, same obstacles;
//! - `first_blocked_pose`: the check of the whole first path against all the obstacles.
//!
//! Target: `replan` under 20 ms median. The data is read from `FORMATION_CLCBS_DIR` or,
//! by default, the copy in `shared/core/tests/data/clcbs`.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use shared::geometry::{Disk, Pose};
use shared::paths::hybrid_astar::{HybridAStarSettings, Replanner, first_blocked_pose, plan};
use testkit::clcbs::{CLCBS_OBSTACLE_RADIUS_M, ClcbsInstance, default_clcbs_dir};

const TURNING_RADIUS_M: f64 = 2.5;
const CLEARANCE_M: f64 = 0.5;

/// (benchmark id, instance file, agent index)
const CASES: [(&str, &str, usize); 4] = [
    (
        "100m/ex0-agent5",
        "map_100by100_obst50_agents10_ex0.yaml",
        5,
    ),
    (
        "100m/ex7-agent1",
        "map_100by100_obst50_agents50_ex7.yaml",
        1,
    ),
    (
        "300m/ex0-agent4",
        "map_300by300_obst100_agents10_ex0.yaml",
        4,
    ),
    (
        "300m/ex2-agent50",
        "map_300by300_obst100_agents100_ex2.yaml",
        50,
    ),
];

/// Three obstacles centred on `path` at a quarter, half and three quarters of the way from
/// pose `from` to the end, kept off the start pose and the goal.
fn obstacles_on_path(path: &[Pose], from: usize) -> Vec<Disk> {
    let keep_off_m = CLCBS_OBSTACLE_RADIUS_M + CLEARANCE_M + 0.5;
    let (start, goal) = (path[from].position(), path[path.len() - 1].position());
    let remaining = path.len() - from;
    (1..=3)
        .map(|k| {
            let mut i = from + remaining * k / 4;
            while (path[i].position() - start).norm() < keep_off_m {
                i += 1;
            }
            while (path[i].position() - goal).norm() < keep_off_m {
                i -= 1;
            }
            let p = path[i].position();
            Disk::new(p.x, p.y, CLCBS_OBSTACLE_RADIUS_M)
        })
        .collect()
}

fn bench_replan(c: &mut Criterion) {
    let mut group = c.benchmark_group("replan");
    for (id, file, agent) in CASES {
        let path = default_clcbs_dir().join(file);
        let instance = ClcbsInstance::load(&path).unwrap_or_else(|e| {
            panic!("{e} (set FORMATION_CLCBS_DIR to the folder of the CL-CBS files)")
        });
        let agent = &instance.agents[agent];
        let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, true);
        let mut replanner = Replanner::new(instance.field, agent.goal, settings.clone())
            .unwrap_or_else(|e| panic!("{id}: {e}"));
        let first = replanner
            .plan_from(&agent.start, &instance.obstacles)
            .unwrap_or_else(|e| panic!("{id}: {e}"));
        let here_index = first.len() / 3;
        let here = first[here_index];
        let mut obstacles = instance.obstacles.clone();
        obstacles.extend(obstacles_on_path(&first, here_index));
        assert!(
            first_blocked_pose(&instance.field, &first, &obstacles, CLEARANCE_M).is_some(),
            "{id}: the new obstacles block the path"
        );
        // Make sure the case replans, and that it is the same path as from scratch.
        let replanned = replanner
            .clone()
            .plan_from(&here, &obstacles)
            .unwrap_or_else(|e| panic!("{id}: {e}"));
        let scratch = plan(&instance.field, &obstacles, &here, &agent.goal, &settings)
            .unwrap_or_else(|e| panic!("{id}: {e}"));
        assert_eq!(replanned, scratch, "{id}");

        group.bench_function(format!("{id}/replan"), |b| {
            b.iter_batched(
                || replanner.clone(),
                |mut r| r.plan_from(black_box(&here), black_box(&obstacles)),
                BatchSize::SmallInput,
            )
        });
        group.bench_function(format!("{id}/plan"), |b| {
            b.iter(|| {
                plan(
                    black_box(&instance.field),
                    black_box(&obstacles),
                    black_box(&here),
                    black_box(&agent.goal),
                    &settings,
                )
            })
        });
        group.bench_function(format!("{id}/first_blocked_pose"), |b| {
            b.iter(|| {
                first_blocked_pose(
                    black_box(&instance.field),
                    black_box(&first),
                    black_box(&obstacles),
                    CLEARANCE_M,
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_replan);
criterion_main!(benches);
