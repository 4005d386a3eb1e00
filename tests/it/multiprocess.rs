//! Every agent its own process over real iceoryx2 shared memory: the multi-process run
//! reproduces the reference simulation to the bit, on every shipped scenario, and leaves
//! no process and no shared-memory file behind. Runs in parallel tests do not meet.

use crate::support;

use runner::turns::{FaultInjection, RunOptions, WaitMode, WakeMode, run_scenario};
use shared::run::record::{FaultKind, Run};
use shared::run::simulate::{plan_centre_path, simulate_along};
use shared::world::scenario::Scenario;
use wire::misbehave::Misbehave;

/// These tests are about determinism, not liveness: a generous turn deadline keeps a
/// healthy agent that the loaded test machine schedules late from counting as missed
/// (dead agents are still noticed at once through their process).
pub(crate) fn options() -> RunOptions {
    options_waiting(WaitMode::default())
}

fn options_waiting(wait: WaitMode) -> RunOptions {
    RunOptions {
        wait,
        agent_bin: Some(support::agent_bin()),
        turn_deadline: std::time::Duration::from_secs(10),
        progress: false,
        ..RunOptions::default()
    }
}

/// Run `scenario` with real processes and compare with the reference, field by field
/// (f64 equality is bit equality here: no NaN in a record).
pub(crate) fn run_and_compare(scenario: &Scenario) -> Run {
    let path = plan_centre_path(scenario).expect("centre path");
    let reference = simulate_along(scenario, &path).expect("reference simulation");
    let outcome = run_scenario(scenario, &path, &options()).expect("multi-process run");
    assert!(!outcome.interrupted);
    assert!(
        support::leftovers(&outcome.prefix).is_empty(),
        "{}: iceoryx2 files left: {:?}",
        scenario.name,
        support::leftovers(&outcome.prefix)
    );
    assert!(
        support::processes_mentioning(&outcome.prefix).is_empty(),
        "{}: agent processes left running",
        scenario.name
    );
    let run = outcome.run;
    assert_eq!(run.steps.len(), reference.steps.len(), "{}", scenario.name);
    for (got, want) in run.steps.iter().zip(&reference.steps) {
        assert_eq!(
            got, want,
            "{}: step {} differs from the reference",
            scenario.name, want.step
        );
    }
    assert_eq!(run.faults, reference.faults);
    assert!(run.completed);
    let s = run.summary();
    assert_eq!(s.collisions, 0, "{}", scenario.name);
    assert!(s.min_clearance_m >= -shared::control::safety::SAFETY_TOLERANCE_M);
    assert!(outcome.timing.turn_latency_us.count > 0);
    run
}

/// Sleeping and spinning hand the turns over differently, rung by doorbells or by
/// iceoryx2 events, and never decide differently: in sequential and parallel turns, all
/// four equal the reference to the bit.
#[test]
fn every_wait_and_wake_mode_matches_the_reference_to_the_bit() {
    let parallel = Scenario::load(&support::repo_root().join("tests/data/swarm16-parallel.toml"))
        .expect("swarm16-parallel.toml");
    for scenario in [Scenario::paper(), parallel] {
        let path = plan_centre_path(&scenario).expect("centre path");
        let reference = simulate_along(&scenario, &path).expect("reference simulation");
        for wait in [WaitMode::Block, WaitMode::Spin] {
            for wake in [WakeMode::Doorbell, WakeMode::Event] {
                let options = RunOptions {
                    wake,
                    ..options_waiting(wait)
                };
                let outcome = run_scenario(&scenario, &path, &options).expect("multi-process run");
                assert_eq!(
                    outcome.run.steps, reference.steps,
                    "{} {wait:?} {wake:?}",
                    scenario.name
                );
                assert!(outcome.run.faults.is_empty(), "{:?}", outcome.run.faults);
                assert!(support::leftovers(&outcome.prefix).is_empty());
            }
        }
    }
}

/// With `--wait spin` an agent told its turn comes next is granted it without a ring;
/// one that does not listen for the notice (sleeping instead) is rung once the spin
/// budget is spent, and never misses a turn: the run equals the reference to the bit.
#[test]
fn an_agent_deaf_to_the_prepare_notice_is_rung_after_the_spin_budget() {
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let reference = simulate_along(&scenario, &path).expect("reference simulation");
    let options = RunOptions {
        faults: FaultInjection {
            misbehave: vec![(2, Misbehave::DeafToPrepare), (5, Misbehave::DeafToPrepare)],
            ..FaultInjection::default()
        },
        // Every turn of a deaf agent waits out the spin budget: a missed turn would show.
        turn_deadline: std::time::Duration::from_millis(500),
        ..options_waiting(WaitMode::Spin)
    };
    let outcome = run_scenario(&scenario, &path, &options).expect("multi-process run");
    assert!(outcome.run.faults.is_empty(), "{:?}", outcome.run.faults);
    assert_eq!(outcome.run.steps, reference.steps);
    // Granted without a ring, a deaf agent wakes only when the budget is spent: most of
    // its turns (all but those whose notice came too long before) take that long.
    let budget_us = runner::turns::SPIN_BUDGET.as_secs_f64() * 1e6;
    for agent in [2, 5] {
        let mut turns: Vec<f64> = outcome.turn_latencies_us(agent).collect();
        turns.sort_by(f64::total_cmp);
        let median = turns[turns.len() / 2];
        assert!(
            median >= budget_us,
            "agent {agent}: median turn {median} us"
        );
    }
    assert!(support::leftovers(&outcome.prefix).is_empty());
}

/// On one core a spinning coordinator yields to the agent it waits for, and a spinning
/// agent to the one computing: `--wait spin` pinned to a single CPU still completes, safe,
/// with no missed turn.
#[test]
fn spinning_on_one_core_starves_nobody() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let mut c = support::coordinator(&["--wait", "spin"], &out);
    // SAFETY: only an async-signal-safe system call between fork and exec.
    unsafe {
        c.pre_exec(|| {
            let mut one = nix::sched::CpuSet::new();
            one.set(0).map_err(std::io::Error::from)?;
            nix::sched::sched_setaffinity(nix::unistd::Pid::from_raw(0), &one)
                .map_err(std::io::Error::from)
        });
    }
    let output = c.output().expect("coordinator");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let s = support::summary(&out);
    assert_eq!(s["completed"], true);
    assert_eq!(s["collisions"], 0);
    assert_eq!(s["faults"].as_array().map(Vec::len), Some(0), "{s:#}");
}

#[test]
fn the_paper_example_over_six_processes_matches_the_reference_to_the_bit() {
    let run = run_and_compare(&Scenario::paper());
    assert_eq!(run.steps[0].agents.len(), 6);
}

#[test]
fn two_hundred_agent_processes_complete_safely_and_match_the_reference() {
    let file = support::repo_root().join("scenarios/swarm200.toml");
    let scenario = Scenario::load(&file).expect("swarm200.toml");
    assert_eq!(scenario.agents.len(), 200);
    run_and_compare(&scenario);
}

/// The shipped scenarios whose multi-process runs only the system tier compares with the
/// reference: the depot's two (a turn on that map costs milliseconds; the fast tier runs
/// a map in `tb3-pillars.toml` and parallel turns on the depot in
/// `parallel_turns_on_a_map_match_the_reference`) and 200 agents in parallel turns (the
/// fast tier runs 200 in sequence, and 16 in parallel in `parallel_kill`).
pub(crate) const HEAVY_SCENARIOS: [&str; 3] = [
    "depot-shelves.toml",
    "depot-forklifts.toml",
    "swarm200-parallel.toml",
];

#[test]
fn every_other_shipped_scenario_matches_the_reference() {
    for file in support::shipped_scenarios() {
        if [
            "swarm200.toml",
            "swarm1000.toml",
            "paper.toml",
            "paper-unicycle.toml",
        ]
        .iter()
        .chain(&HEAVY_SCENARIOS)
        .any(|own| file.ends_with(own))
        {
            continue; // their own tests (the thousand and the heavy in the system tier)
        }
        let scenario = Scenario::load(&file).expect("shipped scenario");
        run_and_compare(&scenario);
    }
}

/// Unicycle agents over real processes: each is sent its heading with its world and
/// publishes the heading it ends at; the coordinator checks the turning and the run
/// equals the reference to the bit, headings and all.
#[test]
fn unicycle_agent_processes_match_the_reference_headings_and_all() {
    let file = support::repo_root().join("scenarios/paper-unicycle.toml");
    let scenario = Scenario::load(&file).expect("paper-unicycle.toml");
    assert!(scenario.agents.iter().all(|a| a.kinematics.has_heading()));
    let run = run_and_compare(&scenario);
    let first: Vec<Option<f64>> = run.steps[0].agents.iter().map(|a| a.heading_rad).collect();
    assert!(
        first.iter().all(Option::is_some),
        "every agent has a heading"
    );
    let last = run.steps.last().expect("steps");
    assert!(
        last.agents
            .iter()
            .zip(&first)
            .any(|(a, h)| a.heading_rad != *h),
        "some agent turned on the way"
    );
}

/// The barrier baseline on the Robotarium's robots over real processes: each agent
/// steers the point ahead of it and drives and turns at once (its move is an arc, drawn
/// as chords); the run equals the reference to the bit, with no move refused.
#[test]
fn the_barrier_baseline_on_unicycle_processes_matches_the_reference() {
    let file = support::repo_root().join("scenarios/robotarium-unicycle.toml");
    let scenario = Scenario::load(&file)
        .expect("robotarium-unicycle.toml")
        .with_controller(shared::control::vocabulary::ControllerKind::Cbf);
    let run = run_and_compare(&scenario);
    assert!(run.faults.is_empty(), "{:?}", run.faults);
    let arcs = run
        .steps
        .windows(2)
        .flat_map(|w| w[0].agents.iter().zip(&w[1].agents))
        .filter(|(before, after)| {
            after.waypoints.len() >= 2
                && after.heading_rad != before.heading_rad
                && after.position != before.position
        })
        .count();
    assert!(arcs > 0, "some moves drive and turn at once");
}

/// A changing world with limited sensing: each agent process is sent only the agents
/// it senses and plans around only the moving obstacles it senses, its escapes too; the
/// run still equals the reference to the bit.
#[test]
fn a_changing_world_with_limited_sensing_matches_the_reference() {
    let file = support::repo_root().join("tests/data/patrol-sensing.toml");
    let scenario = Scenario::load(&file).expect("patrol-sensing.toml");
    assert!(!scenario.moving.is_empty());
    assert!(scenario.agents.iter().all(|a| a.sensing_radius_m.is_some()));
    let run = run_and_compare(&scenario);
    assert!(run.steps.iter().any(|s| s.moving != run.steps[0].moving));
}

/// Parallel turns on a map: the agents of a group plan round the map's pieces at once, in
/// their own processes; the run equals the reference to the bit, with groups of more
/// than one agent.
#[test]
fn parallel_turns_on_a_map_match_the_reference() {
    let file = support::repo_root().join("tests/data/depot-parallel.toml");
    let scenario = Scenario::load(&file).expect("depot-parallel.toml");
    assert!(
        scenario.map.is_some() && scenario.turns == shared::control::vocabulary::TurnMode::Parallel
    );
    let run = run_and_compare(&scenario);
    let agents = scenario.agents.len() as f64;
    assert!(
        run.summary().mean_groups_per_step < agents,
        "no step had a group of two"
    );
}

/// ORCA's own model over real processes: every agent moves at once with the velocities
/// of the last step (sent with each turn), and the safety checks refuse moves that
/// would meet a mate's. The run, refusals and all, equals the reference to the bit.
#[test]
fn orca_in_its_own_model_matches_the_reference() {
    let file = support::repo_root().join("tests/data/dense-orca.toml");
    let scenario = Scenario::load(&file).expect("dense-orca.toml");
    assert_eq!(
        scenario.turns,
        shared::control::vocabulary::TurnMode::Simultaneous
    );
    let run = run_and_compare(&scenario);
    let agents = scenario.agents.len() as f64;
    assert_eq!(
        run.summary().mean_groups_per_step,
        1.0,
        "one group of {agents}"
    );
    // Agents do move reciprocally: somebody's velocity was not zero when it planned.
    assert!(
        run.steps[2..]
            .iter()
            .any(|s| s.agents.iter().any(|a| a.waypoints.len() > 1))
    );
}

/// ORCA's own model in a crowd: the large formation under a top speed, 64 agent
/// processes moving at once. Agents queue behind one another there (a follower may move
/// into where its leader stood, as the leader leaves), moves meet in time and are
/// refused, and a move into a refused mate's place is refused after it. The run, every
/// refusal included, equals the reference to the bit.
#[test]
fn orca_in_its_own_model_in_a_crowd_matches_the_reference() {
    let scenario = support::orca_crowd();
    let run = run_and_compare(&scenario);
    assert_eq!(run.summary().collisions, 0);
    let refused = run
        .faults
        .iter()
        .filter(|f| f.kind == FaultKind::Rejected)
        .count();
    assert!(refused > 0, "no move of the crowd was refused");
}

/// Strikes over real processes: a moving obstacle that catches agents now and then. The
/// monitor (parry) and the recorder both let a struck agent move away, and only away; the
/// run equals the reference to the bit, strikes and all.
#[test]
fn strikes_by_a_moving_obstacle_match_the_reference() {
    let file = support::repo_root().join("tests/data/strike.toml");
    let scenario = Scenario::load(&file).expect("strike.toml");
    let path = plan_centre_path(&scenario).expect("centre path");
    let reference = simulate_along(&scenario, &path).expect("reference simulation");
    let outcome = run_scenario(&scenario, &path, &options()).expect("multi-process run");
    assert!(support::leftovers(&outcome.prefix).is_empty());
    assert_eq!(outcome.run.steps, reference.steps);
    assert_eq!(outcome.run.faults, reference.faults);
    let struck = reference
        .faults
        .iter()
        .filter(|f| f.kind == FaultKind::Struck)
        .count();
    assert!(struck > 0, "no strike");
    assert_eq!(struck, reference.faults.len(), "{:?}", reference.faults);
}

#[test]
fn concurrent_runs_of_the_same_scenario_do_not_see_each_other() {
    let scenario = Scenario::paper();
    let runs: Vec<Run> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..3)
            .map(|_| s.spawn(|| run_and_compare(&scenario)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("run thread"))
            .collect()
    });
    assert!(runs.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn a_failing_coordinator_stops_its_agents_cleans_up_and_keeps_the_steps_done() {
    use runner::turns::run_scenario_with;
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let reference = simulate_along(&scenario, &path).expect("reference simulation");
    for panics in [false, true] {
        let failure = run_scenario_with(&scenario, &path, &options(), &mut |ctx| {
            if ctx.step == 20 {
                if panics {
                    panic!("injected panic at step 20");
                }
                anyhow::bail!("injected error at step 20");
            }
            Ok(())
        })
        .expect_err("the hook fails the run");
        assert!(
            format!("{:#}", failure.error).contains("injected"),
            "{:#}",
            failure.error
        );
        let partial = failure.partial;
        // Nothing of the run is left: processes and shared memory.
        assert!(!partial.prefix.is_empty());
        assert!(
            support::leftovers(&partial.prefix).is_empty(),
            "{:?}",
            support::leftovers(&partial.prefix)
        );
        assert!(support::processes_mentioning(&partial.prefix).is_empty());
        // The steps completed before the failure are kept, exactly as the reference.
        assert!(!partial.run.completed);
        assert_eq!(partial.run.steps.len(), 21);
        assert_eq!(partial.run.steps[..], reference.steps[..21]);
    }
}
