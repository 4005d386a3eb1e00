//! The run log's kill campaigns: the fast tier's `run_log` tests over more seeded kills
//! and more of what a run can hold.

use crate::resume::resumed_twice;
use crate::run_log::coordinator_killed_at_seeded_moments;
use crate::support;

/// Eight more seeded kills of the paper example's coordinator, and ten (one during
/// start-up, one while drawing the plots) of a run that finds its obstacles on the way.
#[test]
fn a_coordinator_killed_at_eighteen_more_seeded_moments_leaves_every_step_before_the_kill() {
    coordinator_killed_at_seeded_moments("paper", 2..10, false);
    coordinator_killed_at_seeded_moments("discovered-wall", 0..10, true);
}

/// Resumed runs with limited sensing and a top speed, killed twice each.
#[test]
fn resumed_runs_with_sensing_and_a_top_speed_equal_the_uninterrupted_ones() {
    let root = support::repo_root();
    resumed_twice(&[
        (
            "sensing-wall",
            root.join("scenarios/sensing-wall.toml"),
            &["--die-agent", "2@100"],
        ),
        (
            "paper-top-speed",
            root.join("scenarios/paper-top-speed.toml"),
            &["--die-agent", "1@30", "--die-agent", "4@200", "--respawn"],
        ),
    ]);
}
