//! Unicycle agents in the reference simulation, checked from the record alone with the
//! geometry written out here: every move is a polyline driven facing along each segment
//! (or, where the agent may reverse, away from it), and its turning and driving fit in
//! one step; the
//! run is safe and complete; the holonomic agents of the same scenario keep no heading.

use std::f64::consts::PI;

use shared::control::vocabulary::Kinematics;
use shared::geometry::{Point, polyline_length_m};
use shared::run::simulate::simulate;
use shared::world::scenario::Scenario;

fn repository(path: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join(path)
}

/// `a - b` wrapped into (-pi, pi].
fn angle_between(a: f64, b: f64) -> f64 {
    let mut d = (a - b) % (2.0 * PI);
    if d > PI {
        d -= 2.0 * PI;
    } else if d <= -PI {
        d += 2.0 * PI;
    }
    d
}

/// The least turning a unicycle needs to drive `waypoints` from `from_rad` and end
/// facing `to_rad`: at each vertex, the short way to the next segment's direction; with
/// `reverse`, each segment may also be driven facing away from it, whichever choice over
/// the whole move turns least (tried exhaustively, the moves being short).
fn least_turning_rad(from_rad: f64, waypoints: &[Point], to_rad: f64, reverse: bool) -> f64 {
    let directions: Vec<f64> = waypoints
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| d.norm() > 1e-12)
        .map(|d| d.y.atan2(d.x))
        .collect();
    let choices: u32 = if reverse {
        assert!(
            directions.len() <= 16,
            "a short move: {} segments",
            directions.len()
        );
        1 << directions.len()
    } else {
        1
    };
    (0..choices)
        .map(|mask| {
            let mut facing = from_rad;
            let mut total = 0.0;
            for (i, along) in directions.iter().enumerate() {
                let along = if mask & (1 << i) != 0 {
                    along + PI
                } else {
                    *along
                };
                total += angle_between(along, facing).abs();
                facing = along;
            }
            total + angle_between(to_rad, facing).abs()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn every_unicycle_move_turns_and_drives_within_one_step() {
    // The paper's example (forward only) and the Robotarium's robots (reversing).
    for file in [
        "scenarios/paper-unicycle.toml",
        "scenarios/robotarium-unicycle.toml",
    ] {
        check_every_move(file);
    }
}

fn check_every_move(file: &str) {
    let scenario = Scenario::load(&repository(file)).expect("load");
    let run = simulate(&scenario).expect("simulate");
    let summary = run.summary();
    assert!(run.completed);
    assert_eq!(summary.collisions, 0);
    assert!(run.faults.is_empty(), "{:?}", run.faults);
    let mut turned_rad: f64 = 0.0;
    let mut limit_rad: f64 = 0.0;
    for (spec_i, spec) in scenario.agents.iter().enumerate() {
        let Kinematics::Unicycle {
            max_turn_rad,
            reverse,
        } = spec.kinematics
        else {
            panic!("agent {spec_i} is a unicycle in this scenario");
        };
        limit_rad = limit_rad.max(max_turn_rad);
        let max_step_m = spec.max_step_m.expect("a top speed");
        // It starts facing the centre's heading plus its offset.
        let first = run.steps[0].agents[spec_i].heading_rad.expect("a heading");
        let want = scenario.path.start.heading_rad + spec.heading_offset_rad;
        assert!(angle_between(first, want).abs() < 1e-12);
        for pair in run.steps.windows(2) {
            let (before, after) = (&pair[0].agents[spec_i], &pair[1].agents[spec_i]);
            let (from, to) = (
                before.heading_rad.expect("a heading"),
                after.heading_rad.expect("a heading"),
            );
            let turn_rad = least_turning_rad(from, &after.waypoints, to, reverse);
            let length_m = polyline_length_m(&after.waypoints);
            let share = turn_rad / max_turn_rad + length_m / max_step_m;
            assert!(
                share <= 1.0 + 1e-9,
                "{file}: step {}, agent {spec_i}: the move takes {share} of a step",
                pair[1].step
            );
            turned_rad = turned_rad.max(turn_rad);
        }
    }
    // The check means something only if the agents turned.
    assert!(
        turned_rad > limit_rad / 6.0,
        "{file}: the largest turn in one step was {turned_rad} rad"
    );
}

#[test]
fn holonomic_agents_keep_no_heading() {
    let scenario = Scenario::load(&repository("scenarios/paper-top-speed.toml")).expect("load");
    let run = simulate(&scenario).expect("simulate");
    assert!(
        run.steps
            .iter()
            .all(|s| s.agents.iter().all(|a| a.heading_rad.is_none()))
    );
}
