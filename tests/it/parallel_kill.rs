//! Parallel turns over real processes: a small parallel swarm (16 agent processes) equals
//! the reference simulation to the bit, also when an agent is killed in the middle of a
//! step, in a group with others (`FaultInjection::deaths`: killed before its group's turns
//! are granted, so the death is always detected during its turn, as
//! `simulate_along_with_deaths` has it), and in a changing world (moving obstacles, the
//! centre replanned). Nothing is left behind: no process, no shared-memory file.

use crate::support;

use runner::turns::{FaultInjection, RunOptions, run_scenario};
use shared::control::vocabulary::{Body, MoveStatus, TurnMode};
use shared::run::record::{FaultKind, Run};
use shared::run::simulate::{plan_centre_path, simulate_along, simulate_along_with_deaths};
use shared::world::groups::turn_groups_ordered;
use shared::world::scenario::Scenario;

/// About determinism, not liveness: a generous turn deadline keeps a healthy agent that
/// the loaded test machine schedules late from counting as missed (dead agents are still
/// noticed at once through their process).
fn options(deaths: &[(usize, usize)]) -> RunOptions {
    RunOptions {
        agent_bin: Some(support::agent_bin()),
        turn_deadline: std::time::Duration::from_secs(10),
        progress: false,
        faults: FaultInjection {
            deaths: deaths.to_vec(),
            ..FaultInjection::default()
        },
        ..RunOptions::default()
    }
}

fn swarm16() -> Scenario {
    let file = support::repo_root().join("tests/data/swarm16-parallel.toml");
    let scenario = Scenario::load(&file).expect("swarm16-parallel.toml");
    assert_eq!(scenario.agents.len(), 16);
    assert_eq!(scenario.turns, TurnMode::Parallel);
    scenario
}

/// The faults as the two sides must agree on them: agent, step and kind (the detail and
/// the detection time are the coordinator's own).
fn fault_keys(run: &Run) -> Vec<(usize, usize, FaultKind)> {
    run.faults
        .iter()
        .map(|f| (f.agent, f.step, f.kind))
        .collect()
}

/// Run `scenario` with real processes, `deaths` injected, and compare it with the
/// reference with the same deaths, step by step and field by field (f64 equality is bit
/// equality here: no NaN in a record).
fn run_and_compare(scenario: &Scenario, deaths: &[(usize, usize)]) -> Run {
    let path = plan_centre_path(scenario).expect("centre path");
    let reference = simulate_along_with_deaths(scenario, &path, deaths).expect("reference");
    let outcome = run_scenario(scenario, &path, &options(deaths)).expect("multi-process run");
    assert!(!outcome.interrupted);
    assert!(
        support::leftovers(&outcome.prefix).is_empty(),
        "iceoryx2 files left: {:?}",
        support::leftovers(&outcome.prefix)
    );
    assert!(
        support::processes_mentioning(&outcome.prefix).is_empty(),
        "agent processes left running"
    );
    let run = outcome.run;
    assert_eq!(run.steps.len(), reference.steps.len());
    for (got, want) in run.steps.iter().zip(&reference.steps) {
        assert_eq!(got, want, "step {} differs from the reference", want.step);
    }
    assert_eq!(fault_keys(&run), fault_keys(&reference));
    // Every death was detected during the agent's turn, by the coordinator's liveness
    // check (its detection time is recorded).
    for f in run.faults.iter().filter(|f| f.kind == FaultKind::Dead) {
        assert!(f.detection_ms.is_some(), "{f:?}");
        assert!(f.detail.contains("during its turn"), "{f:?}");
    }
    assert!(run.completed);
    let s = run.summary();
    assert_eq!(s.collisions, 0);
    assert!(s.min_clearance_m >= -shared::control::safety::SAFETY_TOLERANCE_M);
    run
}

/// The groups of `step` in `reference`, in the order they take their turns (formed from
/// where the agents stood at the end of the step before, in the scenario's turn order).
fn groups_at(scenario: &Scenario, reference: &Run, step: usize) -> Vec<Vec<usize>> {
    let before = &reference.steps[step - 1];
    let bodies: Vec<Body> = before
        .agents
        .iter()
        .zip(&scenario.agents)
        .map(|(a, spec)| Body {
            position: a.position,
            radius_m: spec.radius_m,
        })
        .collect();
    let alive: Vec<bool> = before.agents.iter().map(|a| a.alive).collect();
    turn_groups_ordered(
        scenario.turns,
        scenario.turn_order,
        reference.steps[step].centre.heading_rad,
        &scenario.agents,
        &bodies,
        &alive,
    )
}

#[test]
fn a_small_parallel_swarm_over_sixteen_processes_matches_the_reference_to_the_bit() {
    let scenario = swarm16();
    let run = run_and_compare(&scenario, &[]);
    assert!(run.faults.is_empty(), "{:?}", run.faults);
    let s = run.summary();
    assert!(
        s.mean_groups_per_step > 1.0 && s.mean_groups_per_step < 8.0,
        "parallel, not one by one: {s:?}"
    );
}

#[test]
fn an_agent_killed_mid_step_in_a_parallel_group_matches_the_reference_to_the_bit() {
    let scenario = swarm16();
    let path = plan_centre_path(&scenario).expect("centre path");
    let undisturbed = simulate_along(&scenario, &path).expect("reference");
    // Mid-step: a group after the first (the agents of the groups before it have already
    // moved), holding others besides the victim.
    let step = 40;
    let groups = groups_at(&scenario, &undisturbed, step);
    let (index, group) = groups
        .iter()
        .enumerate()
        .skip(1)
        .find(|(_, g)| g.len() >= 3)
        .expect("a later group of three or more at the kill step");
    let victim = group[group.len() / 2];
    let mates: Vec<usize> = group.iter().copied().filter(|&a| a != victim).collect();

    let run = run_and_compare(&scenario, &[(victim, step)]);
    assert_eq!(
        fault_keys(&run),
        [
            (victim, step, FaultKind::Killed),
            (victim, step, FaultKind::Dead)
        ]
    );
    // The victim took no turn from the kill on: frozen where it stood, out of the
    // formation; alive before.
    let stood = run.steps[step - 1].agents[victim].position;
    for s in &run.steps[step..] {
        let a = &s.agents[victim];
        assert!(!a.alive && a.status == MoveStatus::Dead && a.position == stood);
    }
    assert!(run.steps[..step].iter().all(|s| s.agents[victim].alive));
    // Its group mates still took their turns at the kill step, the same moves as in the
    // run without the kill (planned against the same snapshot; only their clearances at
    // the end of the step may differ, the victim standing elsewhere).
    for &m in &mates {
        let (got, want) = (
            &run.steps[step].agents[m],
            &undisturbed.steps[step].agents[m],
        );
        assert_eq!(
            (got.status, &got.waypoints),
            (want.status, &want.waypoints),
            "group {index} mate {m} of {victim}"
        );
    }
    assert!(
        mates
            .iter()
            .any(|&m| run.steps[step].agents[m].waypoints.len() > 1),
        "some mate of {victim} moved at step {step}"
    );
    // Without it the formation goes on: after the kill step the groups are formed without
    // the victim.
    assert!(
        groups_at(&scenario, &run, step + 1)
            .iter()
            .all(|g| !g.contains(&victim))
    );
}

#[test]
fn two_agents_killed_at_one_step_in_sequential_mode_match_the_reference_to_the_bit() {
    let mut scenario = swarm16();
    scenario.turns = TurnMode::Sequential;
    let run = run_and_compare(&scenario, &[(9, 25), (3, 25), (12, 60)]);
    let dead: Vec<(usize, usize)> = run
        .faults
        .iter()
        .filter(|f| f.kind == FaultKind::Dead)
        .map(|f| (f.agent, f.step))
        .collect();
    // Detected in turn order (the scenario's, found again from the positions).
    let order = groups_at(&scenario, &run, 25).concat();
    let mut at_25: Vec<(usize, usize)> = order
        .iter()
        .filter(|a| [3, 9].contains(*a))
        .map(|&a| (a, 25))
        .collect();
    assert_eq!(at_25.len(), 2, "both victims take a turn at step 25");
    at_25.push((12, 60));
    assert_eq!(dead, at_25);
}

/// ORCA's own model (every agent moves at once) with agents killed mid-step: the large
/// formation under a top speed, 64 processes, three deaths. Each dead agent stands frozen
/// where it was, and every move is judged against it as the reference judges it: the
/// run equals the reference with those deaths, to the bit.
#[test]
fn agents_killed_in_orcas_own_model_match_the_reference() {
    let scenario = support::orca_crowd();
    let run = run_and_compare(&scenario, &[(20, 30), (41, 31), (9, 150)]);
    let dead = run
        .faults
        .iter()
        .filter(|f| f.kind == FaultKind::Dead)
        .count();
    assert_eq!(dead, 3, "{:?}", run.faults);
}

/// The same in a changing world: the patrol scenario (moving obstacles crossing the
/// formation's path, the centre replanning) with agent 2 killed at step 60 equals the
/// reference with that death, to the bit, with no collision.
#[test]
fn a_killed_agent_in_a_changing_world_matches_the_reference() {
    let file = support::repo_root().join("scenarios/patrol.toml");
    let scenario = Scenario::load(&file).expect("patrol.toml");
    assert!(!scenario.moving.is_empty());
    let run = run_and_compare(&scenario, &[(2, 60)]);
    assert!(run.steps[60..].iter().all(|s| !s.agents[2].alive));
    assert!(run.steps[..60].iter().all(|s| s.agents[2].alive));
    assert_eq!(
        run.steps[80].moving[0],
        scenario.moving[0].position_at(80),
        "the obstacles moved on"
    );
}
