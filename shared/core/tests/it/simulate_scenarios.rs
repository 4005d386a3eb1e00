//! The reference simulation on every shipped scenario: no collision, clearance never
//! negative, every move checked independently, and the deviation shape of the paper's
//! Fig. 9 (it returns to near zero once the obstacles are behind).

use std::path::PathBuf;

use shared::control::safety::{self, SAFETY_TOLERANCE_M};
use shared::control::vocabulary::{Body, ControllerKind, MAX_WAYPOINTS, MoveStatus};
use shared::geometry::{DiskGrid, distance_polyline_polyline, polyline_length_m};
use shared::run::record::Run;
use shared::run::simulate::simulate;
use shared::world::groups::turn_groups_ordered;
use shared::world::scenario::Scenario;

fn scenario_files() -> Vec<PathBuf> {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios"));
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 4,
        "the paper scenario and at least three more"
    );
    files
}

/// Re-check every accepted move of the run from the record alone, with the turn
/// semantics of the scenario: the groups of each step are found again from the positions
/// at its start, in the scenario's turn order ([`turn_groups_ordered`]); each move is
/// checked against the true obstacles and every other agent as they stood when its group
/// moved, against the agent's top speed, and against the whole moves of its group mates.
fn recheck_every_move(scenario: &Scenario, run: &Run) {
    let obstacles = DiskGrid::new(scenario.obstacles.clone());
    for w in run.steps.windows(2) {
        let (before, after) = (&w[0], &w[1]);
        let mut bodies: Vec<Body> = before
            .agents
            .iter()
            .zip(&scenario.agents)
            .map(|(a, s)| Body {
                position: a.position,
                radius_m: s.radius_m,
            })
            .collect();
        let alive: Vec<bool> = before.agents.iter().map(|a| a.alive).collect();
        let groups = turn_groups_ordered(
            scenario.turns,
            scenario.turn_order,
            after.centre.heading_rad,
            &scenario.agents,
            &bodies,
            &alive,
        );
        assert_eq!(
            groups.len(),
            after.groups,
            "{}: step {}",
            scenario.name,
            after.step
        );
        for group in &groups {
            for &i in group {
                let a = &after.agents[i];
                let others: Vec<Body> = bodies
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, b)| *b)
                    .collect();
                safety::check_move(
                    &scenario.field,
                    &obstacles,
                    &others,
                    bodies[i].radius_m,
                    &bodies[i].position,
                    &a.waypoints,
                    MAX_WAYPOINTS,
                )
                .unwrap_or_else(|v| {
                    panic!("{}: step {} agent {i}: {v}", scenario.name, after.step)
                });
                assert_clear_of_polygons(scenario, bodies[i].radius_m, &a.waypoints, i, after.step);
                assert_eq!(*a.waypoints.last().unwrap(), a.position);
                if let Some(max_m) = scenario.agents[i].max_step_m {
                    let length_m = polyline_length_m(&a.waypoints);
                    assert!(
                        length_m <= max_m + 1e-9,
                        "{}: step {} agent {i}: a move of {length_m} m, top speed {max_m} m",
                        scenario.name,
                        after.step
                    );
                }
                for &j in group.iter().filter(|&&j| j < i) {
                    let d = distance_polyline_polyline(&a.waypoints, &after.agents[j].waypoints);
                    let need = bodies[i].radius_m + bodies[j].radius_m;
                    assert!(
                        d >= need - SAFETY_TOLERANCE_M,
                        "{}: step {}: agents {i} and {j} of one group come within {d} m",
                        scenario.name,
                        after.step
                    );
                }
            }
            for &i in group {
                bodies[i].position = after.agents[i].position;
            }
        }
    }
}

/// Every point of `waypoints`, sampled every millimetre, keeps `radius_m` from every
/// polygon (its plain distance, not the grown shape the planner uses).
fn assert_clear_of_polygons(
    scenario: &Scenario,
    radius_m: f64,
    waypoints: &[shared::geometry::Point],
    agent: usize,
    step: usize,
) {
    for w in waypoints.windows(2) {
        let n = ((w[1] - w[0]).norm() / 1e-3).ceil().max(1.0) as usize;
        for k in 0..=n {
            let p = w[0] + (w[1] - w[0]) * (k as f64 / n as f64);
            for (j, polygon) in scenario.polygons.iter().enumerate() {
                let d = polygon.distance_m(&p);
                assert!(
                    d >= radius_m - SAFETY_TOLERANCE_M,
                    "{}: step {step} agent {agent}: {d} m from polygon {j} at {p:?}",
                    scenario.name
                );
            }
        }
    }
}

/// The run completed with no collision, no negative clearance, no fault (not one move
/// refused), and every move holds up when re-checked from the record.
fn assert_safe_without_faults(scenario: &Scenario, run: &Run) {
    let summary = run.summary();
    assert!(run.completed, "{}", scenario.name);
    assert_eq!(summary.collisions, 0, "{}", scenario.name);
    assert!(
        summary.min_clearance_m >= -SAFETY_TOLERANCE_M,
        "{}",
        scenario.name
    );
    assert!(
        summary.faults.is_empty(),
        "{}: {:?}",
        scenario.name,
        summary.faults
    );
    recheck_every_move(scenario, run);
}

#[test]
fn every_shipped_scenario_runs_safely_and_the_formation_recovers() {
    for file in scenario_files() {
        let scenario = Scenario::load(&file).unwrap();
        let run = simulate(&scenario).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let summary = run.summary();
        eprintln!(
            "{}: {} agents, {} steps, min clearance {:.4} m, mean deviation {:.4} m, max {:.4} m, final {:.6} m",
            scenario.name,
            summary.agents,
            summary.steps,
            summary.min_clearance_m,
            summary.mean_deviation_m,
            summary.max_deviation_m,
            summary.final_mean_deviation_m
        );
        assert_safe_without_faults(&scenario, &run);
        // Fig. 9: the formation deviates among the obstacles and recovers afterwards.
        assert!(
            summary.max_deviation_m > 0.0,
            "{}: the field must disturb the formation",
            scenario.name
        );
        assert!(
            summary.final_mean_deviation_m < 0.05,
            "{}: final mean deviation {}",
            scenario.name,
            summary.final_mean_deviation_m
        );
        let last = run.steps.last().unwrap();
        assert!(
            last.agents
                .iter()
                .all(|a| a.status == MoveStatus::AtSlot || a.deviation_m < 0.05)
        );
    }
}

#[test]
fn the_barrier_function_controller_never_breaks_clearance_on_any_shipped_static_scenario() {
    for file in scenario_files() {
        let scenario = Scenario::load(&file)
            .unwrap()
            .with_controller(ControllerKind::Cbf);
        if !scenario.polygons.is_empty() {
            continue; // refused beside polygons: it does not plan round them yet
        }
        let run = simulate(&scenario).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        if scenario.changes() {
            // A reactive baseline is not claimed safe against moving obstacles: it gets
            // the same reach disks and escapes, but no more. Reported, not asserted.
            eprintln!(
                "cbf on {} (a changing world): {} collisions",
                scenario.name,
                run.summary().collisions
            );
            continue;
        }
        // Safe by construction: not one move needed refusing.
        assert_safe_without_faults(&scenario, &run);
    }
}

#[test]
fn orca_never_breaks_clearance_or_its_top_speed_on_any_shipped_static_scenario() {
    for file in scenario_files() {
        let scenario = Scenario::load(&file)
            .unwrap()
            .with_controller(ControllerKind::Orca);
        if !scenario.polygons.is_empty() {
            continue; // refused beside polygons: it does not plan round them yet
        }
        let run = simulate(&scenario).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        if scenario.changes() {
            // A reactive baseline is not claimed safe against moving obstacles: it gets
            // the same reach disks and escapes, but no more. Reported, not asserted.
            eprintln!(
                "orca on {} (a changing world): {} collisions",
                scenario.name,
                run.summary().collisions
            );
            continue;
        }
        // Its moves are cut before any contact: not one needed refusing.
        assert_safe_without_faults(&scenario, &run);
        if let Some(max_m) = scenario.agents[0].max_step_m {
            assert!(
                run.summary().max_move_m <= max_m + 1e-9,
                "{}",
                scenario.name
            );
        }
        eprintln!(
            "orca on {}: mean deviation {:.4} m, final {:.4} m, longest move {:.3} m",
            scenario.name,
            run.summary().mean_deviation_m,
            run.summary().final_mean_deviation_m,
            run.summary().max_move_m
        );
    }
}
