//! Cost of planning among polygon obstacles, on `scenarios/polygon-corridor.toml` (two
//! L-shaped walls with a doorway, a wedge and two disks) and on
//! `scenarios/depot-shelves.toml` (a real map: the depot's blocked cells as 500 polygon
//! pieces): one best point (every agent's slot at every step, against the obstacles
//! grown by the agent's radius), and one agent's whole move (best point, reachability
//! and shortest path) on the turns of the reference simulation, beside the same turns
//! with the polygons left out. Each is also timed item by item (p50, p90, largest).

mod support;

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::control::best_point::nearest_free_point;
use shared::control::turn::{TurnController, TurnRequest};
use shared::control::vocabulary::Body;
use shared::geometry::{Disk, DiskGrid, FreeSpace, InflatedPolygon, Point, PolygonLayer, Pose};
use shared::run::simulate::{agent_controllers, simulate};
use shared::world::scenario::Scenario;

/// One recorded turn: the centre, the agent, where it stood, the others.
struct Turn {
    step: usize,
    centre: Pose,
    agent: usize,
    me: Point,
    others: Vec<Body>,
}

fn shipped(name: &str) -> Scenario {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    Scenario::load(&file).expect("a shipped scenario")
}

/// Every agent's turn at every step, from where the step before left every agent.
fn turns(scenario: &Scenario) -> Vec<Turn> {
    let run = simulate(scenario).expect("simulate");
    let mut out = Vec::new();
    for pair in run.steps.windows(2) {
        let (before, now) = (&pair[0], &pair[1]);
        let bodies = before.bodies(scenario);
        for agent in 0..bodies.len() {
            out.push(Turn {
                step: now.step,
                centre: now.centre,
                agent,
                me: bodies[agent].position,
                others: bodies
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != agent)
                    .map(|(_, b)| *b)
                    .collect(),
            });
        }
    }
    out
}

/// Each turn of `turns` planned by `controllers`, timed alone.
fn print_turn_percentiles(what: &str, controllers: &[TurnController], turns: &[Turn]) {
    support::print_best_of_five_percentiles(what, turns.len(), |i| {
        let t = &turns[i];
        black_box(
            controllers[t.agent].plan(&TurnRequest::new(t.centre, t.me, &t.others).at_step(t.step)),
        );
    });
}

fn bench_polygons(c: &mut Criterion) {
    bench_scenario(c, "corridor", &shipped("polygon-corridor.toml"));
    bench_scenario(c, "depot", &shipped("depot-shelves.toml"));
}

fn bench_scenario(c: &mut Criterion, name: &str, scenario: &Scenario) {
    let turns = turns(scenario);
    let with = agent_controllers(scenario).expect("controllers");
    let mut bare = scenario.clone();
    bare.polygons.clear();
    bare.map = None;
    let without = agent_controllers(&bare).expect("controllers");
    print_turn_percentiles(&format!("{name}: moves among polygons"), &with, &turns);
    print_turn_percentiles(
        &format!("{name}: the same turns without the polygons"),
        &without,
        &turns,
    );

    let radius_m = scenario.agents[0].radius_m;
    let grid = DiskGrid::new(
        scenario
            .obstacles
            .iter()
            .map(|d| Disk::new(d.centre.x, d.centre.y, d.radius_m + radius_m))
            .collect(),
    );
    let layers = [&grid];
    let grown: Vec<InflatedPolygon> = scenario
        .polygons
        .iter()
        .map(|p| InflatedPolygon::from_polygon(p.clone(), radius_m))
        .collect();
    let grown = PolygonLayer::new(grown);
    let space = FreeSpace::new(scenario.field, &layers).with_polygons(&grown);
    let slots: Vec<Point> = turns
        .iter()
        .map(|t| scenario.agents[t.agent].slot.ideal_position(&t.centre))
        .collect();

    support::print_best_of_five_percentiles(
        &format!("{name}: best points among polygons"),
        slots.len(),
        |i| {
            black_box(nearest_free_point(&space, &slots[i]).ok());
        },
    );

    let mut group = c.benchmark_group(format!("polygons/{name}"));
    let mut i = 0;
    group.bench_function("best_point", |b| {
        b.iter(|| {
            let q = &slots[i % slots.len()];
            i += 1;
            black_box(nearest_free_point(&space, q))
        })
    });
    for (name, controllers) in [
        ("plan_turn", &with),
        ("plan_turn/without_polygons", &without),
    ] {
        let mut i = 0;
        group.bench_function(name, |b| {
            b.iter(|| {
                let t = &turns[i % turns.len()];
                i += 1;
                black_box(
                    controllers[t.agent]
                        .plan(&TurnRequest::new(t.centre, t.me, &t.others).at_step(t.step)),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_polygons);
criterion_main!(benches);
