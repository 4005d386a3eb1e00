//! The fast tier's `multiprocess` at the largest scale and on the heaviest scenarios.

use shared::run::simulate::plan_centre_path;
use shared::world::scenario::Scenario;

use crate::multiprocess::{HEAVY_SCENARIOS, options, run_and_compare};
use crate::support;
use runner::turns::run_scenario;

/// A thousand agent processes. The coordinator holds 15 open files per agent (iceoryx2;
/// see `raise_fd_limit` in `coordinator/runner/src/agents.rs`): where its hard limit allows the
/// 15 064 files (20 000 on the machines this was written on), the run completes safely
/// and matches the reference; where it does not, the run is refused up front, naming
/// the figure, with no agent started and nothing left in shared memory.
#[test]
fn a_thousand_agent_processes_match_the_reference_or_are_refused_up_front() {
    use nix::sys::resource::{Resource, getrlimit};
    let file = support::repo_root().join("scenarios/swarm1000.toml");
    let scenario = Scenario::load(&file).expect("swarm1000.toml");
    assert_eq!(scenario.agents.len(), 1000);
    let (_, hard) = getrlimit(Resource::RLIMIT_NOFILE).expect("RLIMIT_NOFILE");
    if hard >= 64 + 15 * 1000 {
        run_and_compare(&scenario);
        return;
    }
    let path = plan_centre_path(&scenario).expect("centre path");
    let failure = run_scenario(&scenario, &path, &options()).expect_err("beyond the limit");
    let why = failure.error.to_string();
    assert!(
        why.contains("1000 agents need about 15064 open files"),
        "{why}"
    );
    assert_eq!(failure.partial.run.steps.len(), 1, "nothing but step 0");
    // Refused before a run prefix was drawn: no agent, no shared memory, no folder.
    assert!(
        failure.partial.prefix.is_empty(),
        "no run prefix was even drawn"
    );
}

/// The shipped scenarios the fast tier leaves to this tier
/// ([`HEAVY_SCENARIOS`]): each multi-process run equals the reference to the bit.
#[test]
fn the_heavy_shipped_scenarios_match_the_reference() {
    for name in HEAVY_SCENARIOS {
        let file = support::repo_root().join("scenarios").join(name);
        let scenario = Scenario::load(&file).expect("a shipped scenario");
        run_and_compare(&scenario);
    }
}
