//! The seeded kill campaigns: the fast tier's fault tests (`faults`) over more seeds and
//! on 64 agents.

use crate::faults::{
    LongRun, agents_killed_from_outside, kill_campaign, sigterm_and_ctrl_c_stop_cleanly,
};

/// The other 18 runs of the seeded kill campaign (the fast tier runs seeds 0 and 1).
#[test]
fn random_agents_killed_at_random_steps_over_eighteen_more_seeds() {
    kill_campaign(2..20);
}

/// Three agents of 64, one a run, killed with SIGKILL from outside at random steps.
#[test]
fn agents_killed_from_outside_at_random_moments_of_a_large_run_are_survived() {
    agents_killed_from_outside(LongRun::Large, 100..103);
}

/// SIGTERM and SIGINT to a run of 64 agents.
#[test]
fn sigterm_and_ctrl_c_stop_a_large_run_cleanly_with_complete_outputs() {
    sigterm_and_ctrl_c_stop_cleanly(LongRun::Large);
}
