//! The seeded kill campaigns: the fast tier's fault tests (`faults`) over more seeds and
//! on 64 agents (the fast tier's run on the paper example's 6).

use crate::faults::{
    LongRun, a_second_ctrl_c_ends_a_stuck_coordinator, agents_killed_from_outside,
    agents_leave_when_the_coordinator_is_killed, kill_campaign, sigterm_and_ctrl_c_stop_cleanly,
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

/// The coordinator of a run of 64 agents killed mid-run: all 64 go with it.
#[test]
fn the_agents_of_a_large_run_leave_when_the_coordinator_is_killed() {
    agents_leave_when_the_coordinator_is_killed(LongRun::Large);
}

/// A stuck coordinator of 64 agents ends at the second SIGINT and leaves nothing.
#[test]
fn a_second_ctrl_c_ends_a_stuck_coordinator_of_a_large_run_at_once() {
    a_second_ctrl_c_ends_a_stuck_coordinator(LongRun::Large);
}
