//! Cost of the exact best point (Theorem 1) as the field fills up.
//!
//! Fields hold disks of radius 1.3 m (already inflated) at uniformly random seeded
//! positions, at a realistic density of one disk per 100 m^2 (8 disks in 28.3 m x 28.3 m,
//! 100 in 100 m x 100 m, 10 000 in 1000 m x 1000 m), plus a crowded field of 10 000 disks
//! in 300 m x 300 m (one per 9 m^2, about 45 % of the field covered, heavy overlaps).
//! Queries either land inside a disk (the non-trivial case) or are free.
//!
//! `packed_formation`: one agent's turn in a tightly packed formation (200 agents of radius
//! 0.3 m in a 20 x 10 block at 1 m spacing, through a sparse field), on the turns of six
//! steps of the reference simulation: neighbours' inflated disks overlap into a closed
//! pocket around each agent, and its slot often lies outside. The reachable best point
//! with one `shortest_path` per candidate against `PathsFrom` (one barrier graph per turn),
//! and the whole `plan_move`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shared::control::best_point::{nearest_free_point, nearest_reachable_free_point};
use shared::control::turn::{BestPointController, PLANNING_MARGIN_M};
use shared::control::vocabulary::Body;
use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point, Pose, Vector};
use shared::paths::disk_path::{PathsFrom, shortest_path};
use shared::run::record::Recorder;
use shared::run::simulate::plan_centre_path;
use shared::world::scenario::Scenario;

/// Radius of every (inflated) disk, in metres.
const DISK_RADIUS_M: f64 = 1.3;
/// Queries per kind, cycled through by the benchmark loop.
const QUERY_COUNT: usize = 1024;

/// A field of `count` disks, queries inside disks, and free queries.
struct Workload {
    field: Field,
    grid: DiskGrid,
    inside_queries: Vec<Point>,
    free_queries: Vec<Point>,
}

fn workload(count: usize, side_m: f64, seed: u64) -> Workload {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let field = Field::new(side_m, side_m);
    let disks: Vec<Disk> = (0..count)
        .map(|_| {
            Disk::new(
                rng.random::<f64>() * side_m,
                rng.random::<f64>() * side_m,
                DISK_RADIUS_M,
            )
        })
        .collect();
    let inside_queries = (0..QUERY_COUNT)
        .map(|_| {
            let disk = disks[rng.random_range(0..count)];
            // Uniform over the disk area.
            let r = DISK_RADIUS_M * rng.random::<f64>().sqrt();
            let a = std::f64::consts::TAU * rng.random::<f64>();
            disk.centre + r * Vector::new(a.cos(), a.sin())
        })
        .collect();
    let grid = DiskGrid::new(disks);
    let mut free_queries = Vec::with_capacity(QUERY_COUNT);
    {
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        while free_queries.len() < QUERY_COUNT {
            let p = Point::new(rng.random::<f64>() * side_m, rng.random::<f64>() * side_m);
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

/// The packed scale test: 200 agents of radius 0.3 m in a 20 x 10 block at 1 m spacing
/// (inflated disks of neighbours overlap), through a sparse field of 20 obstacles.
fn packed_scenario() -> Scenario {
    let mut text = String::from(
        "name = \"packed-200\"\nseed = 13\n\
         [field]\nwidth_m = 100.0\nheight_m = 60.0\n\
         [obstacles]\nradius_m = 1.5\n\
         [obstacles.random]\ncount = 20\nkeep_clear_m = 12.0\n\
         [formation]\nagent_radius_m = 0.3\nslots = [\n",
    );
    for j in 0..10 {
        for i in 0..20 {
            let (x, y) = (i as f64 - 9.5, j as f64 - 4.5);
            let theta_deg = y.atan2(x).to_degrees();
            text += &format!("  {{ r_m = {}, theta_deg = {theta_deg} }},\n", x.hypot(y));
        }
    }
    text += "]\n[path]\n\
             start = { x_m = 15.0, y_m = 15.0, heading_deg = 0.0 }\n\
             goal = { x_m = 85.0, y_m = 45.0, heading_deg = 23.0 }\n\
             turning_radius_m = 8.0\nstep_m = 0.3\ncentre_clearance_m = 1.0\n\
             allow_reverse = false\n";
    Scenario::parse(&text, "packed-200").expect("a valid scenario")
}

/// One agent's turn: its controller's index, the centre, its position, the other bodies.
type Turn = (usize, Pose, Point, Vec<Body>);

/// Every turn of the steps `sampled` of the reference simulation of `scenario` (the same
/// turns as `simulate`), run up to the last of them.
fn recorded_turns(scenario: &Scenario, sampled: &[usize]) -> (Vec<BestPointController>, Vec<Turn>) {
    let path = plan_centre_path(scenario).expect("a centre path");
    let controllers: Vec<BestPointController> = scenario
        .agents
        .iter()
        .map(|spec| BestPointController::new(scenario.field, &scenario.obstacles, spec))
        .collect();
    let mut recorder = Recorder::new(scenario, path[0]);
    let mut turns = Vec::new();
    let last = sampled
        .iter()
        .copied()
        .max()
        .unwrap_or(0)
        .min(path.len() - 1);
    for (step, centre) in path.iter().enumerate().take(last + 1).skip(1) {
        for (agent, controller) in controllers.iter().enumerate() {
            let me = recorder.world().bodies()[agent].position;
            let others = recorder.world().others(agent);
            if sampled.contains(&step) {
                turns.push((agent, *centre, me, others.clone()));
            }
            let _ = recorder.submit(step, agent, controller.plan_move(centre, &me, &others));
        }
        recorder.end_step(step);
    }
    (controllers, turns)
}

fn bench_packed_formation(c: &mut Criterion) {
    let scenario = packed_scenario();
    let (controllers, turns) = recorded_turns(&scenario, &[10, 40, 80, 120, 160, 200]);
    // Each turn's free space as `plan_move` sees it (the field inset by the inflation
    // aside), its slot and its start.
    let radius_m = scenario.agents[0].radius_m;
    let grow_m = radius_m + PLANNING_MARGIN_M;
    let spaces: Vec<(DiskGrid, DiskGrid, Point, Point)> = turns
        .iter()
        .map(|(agent, centre, me, others)| {
            let inflate = |d: &Disk| Disk {
                centre: d.centre,
                radius_m: d.radius_m + grow_m,
            };
            let obstacles = DiskGrid::new(scenario.obstacles.iter().map(inflate).collect());
            let agents = DiskGrid::new(
                others
                    .iter()
                    .map(|b| {
                        inflate(&Disk {
                            centre: b.position,
                            radius_m: b.radius_m,
                        })
                    })
                    .collect(),
            );
            (
                obstacles,
                agents,
                controllers[*agent].slot_position(centre),
                *me,
            )
        })
        .collect();
    let mut group = c.benchmark_group("packed_formation");
    group.sample_size(10);
    let mut next = 0;
    group.bench_function("reachable_best_point/shortest_path_each", |b| {
        b.iter(|| {
            next = (next + 1) % spaces.len();
            let (obstacles, agents, slot, me) = &spaces[next];
            let layers = [obstacles, agents];
            let space = FreeSpace::new(scenario.field, &layers);
            black_box(nearest_reachable_free_point(&space, slot, me, |p| {
                shortest_path(&space, me, p).is_ok()
            }))
        })
    });
    let mut next = 0;
    group.bench_function("reachable_best_point/paths_from", |b| {
        b.iter(|| {
            next = (next + 1) % spaces.len();
            let (obstacles, agents, slot, me) = &spaces[next];
            let layers = [obstacles, agents];
            let space = FreeSpace::new(scenario.field, &layers);
            let mut paths = PathsFrom::new(&space, me);
            black_box(nearest_reachable_free_point(&space, slot, me, |p| {
                paths.shortest_path(p).is_ok()
            }))
        })
    });
    let mut next = 0;
    group.bench_function("plan_move", |b| {
        b.iter(|| {
            next = (next + 1) % turns.len();
            let (agent, centre, me, others) = &turns[next];
            black_box(controllers[*agent].plan_move(centre, me, others))
        })
    });
    group.finish();
}

criterion_group!(benches, bench_best_point, bench_packed_formation);
criterion_main!(benches);
