//! Cost of one unicycle agent's move against the holonomic move, on the same turns: the
//! turns of every agent at every tenth step of the reference simulation of
//! `scenarios/paper-unicycle.toml` (the paper's example with unicycles), planned once by
//! the unicycle's controller and once by the same agent's holonomic controller; and one
//! car agent's move, on the turns of `scenarios/paper-car.toml`.

mod support;

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::control::turn::{TurnController, TurnRequest};
use shared::control::vocabulary::{Body, Kinematics};
use shared::geometry::{Point, Pose};
use shared::run::simulate::{agent_controllers, simulate};
use shared::world::scenario::Scenario;

/// One recorded turn: the centre, the agent, where it stood and faced, the others.
struct Turn {
    step: usize,
    centre: Pose,
    agent: usize,
    me: Point,
    heading_rad: f64,
    others: Vec<Body>,
}

/// The controllers of `scenarios/{name}`, the same agents made holonomic, and the turns.
fn recorded(name: &str) -> (Vec<TurnController>, Vec<TurnController>, Vec<Turn>) {
    let file = format!("{}/../../scenarios/{name}", env!("CARGO_MANIFEST_DIR"));
    let scenario = Scenario::load(std::path::Path::new(&file)).expect("a shipped scenario");
    let run = simulate(&scenario).expect("simulate");
    let unicycles = agent_controllers(&scenario).expect("controllers");
    let mut holonomic_scenario = scenario.clone();
    for a in &mut holonomic_scenario.agents {
        a.kinematics = Kinematics::Holonomic;
    }
    let holonomic = agent_controllers(&holonomic_scenario).expect("controllers");
    let mut turns = Vec::new();
    // A turn at step s plans from where step s - 1 left every agent (sequential turns:
    // the agents before it have moved; close enough for timing).
    for pair in run.steps.windows(2).step_by(10) {
        let (before, now) = (&pair[0], &pair[1]);
        let bodies = before.bodies(&scenario);
        for agent in 0..bodies.len() {
            turns.push(Turn {
                step: now.step,
                centre: now.centre,
                agent,
                me: bodies[agent].position,
                heading_rad: before.agents[agent].heading_rad.expect("a heading"),
                others: bodies
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != agent)
                    .map(|(_, b)| *b)
                    .collect(),
            });
        }
    }
    (unicycles, holonomic, turns)
}

/// The car's move on `turn`.
fn plan_car_turn(cars: &[TurnController], t: &Turn) {
    black_box(
        cars[t.agent].plan(
            &TurnRequest::new(t.centre, t.me, &t.others)
                .at_step(t.step)
                .facing(t.heading_rad),
        ),
    );
}

/// Each car turn timed alone (see [`support::print_best_of_five_percentiles`]).
fn print_car_turn_percentiles(cars: &[TurnController], turns: &[Turn]) {
    support::print_best_of_five_percentiles("car turns on paper-car.toml", turns.len(), |i| {
        plan_car_turn(cars, &turns[i]);
    });
}

fn bench_kinematics(c: &mut Criterion) {
    let (unicycles, holonomic, turns) = recorded("paper-unicycle.toml");
    let (cars, _, car_turns) = recorded("paper-car.toml");
    print_car_turn_percentiles(&cars, &car_turns);
    let mut group = c.benchmark_group("kinematics/paper");
    let mut i = 0;
    group.bench_function("plan_turn/holonomic", |b| {
        b.iter(|| {
            let t = &turns[i % turns.len()];
            i += 1;
            black_box(
                holonomic[t.agent]
                    .plan(&TurnRequest::new(t.centre, t.me, &t.others).at_step(t.step)),
            )
        })
    });
    let mut i = 0;
    group.bench_function("plan_turn_with_heading/unicycle", |b| {
        b.iter(|| {
            let t = &turns[i % turns.len()];
            i += 1;
            black_box(
                unicycles[t.agent].plan(
                    &TurnRequest::new(t.centre, t.me, &t.others)
                        .at_step(t.step)
                        .facing(t.heading_rad),
                ),
            )
        })
    });
    let mut i = 0;
    group.bench_function("plan_turn_with_heading/car", |b| {
        b.iter(|| {
            let t = &car_turns[i % car_turns.len()];
            i += 1;
            plan_car_turn(&cars, t)
        })
    });
    group.finish();
}

criterion_group!(benches, bench_kinematics);
criterion_main!(benches);
