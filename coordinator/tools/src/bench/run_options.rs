//! The run options and limits every bench measurement starts from.

use std::path::Path;
use std::time::Duration;

use runner::turns::{RunOptions, WakeMode};

/// How long a benched agent has to answer a turn: generous, so that a noisy machine
/// never turns a slow turn into a fault and changes what is measured.
pub const BENCH_TURN_DEADLINE: Duration = Duration::from_secs(2);

/// How long an agent has to answer an echo.
pub const ECHO_DEADLINE: Duration = Duration::from_secs(2);

/// Most steps: the generated field must stay within the largest field accepted.
pub const MAX_BENCH_STEPS: usize = 20_000;

/// The options of a measured run: the agents from `agent_bin`, rung as `wake` has it, the
/// generous [`BENCH_TURN_DEADLINE`], no progress line; the rest as [`RunOptions::default`].
pub fn bench_run_options(agent_bin: &Path, wake: WakeMode) -> RunOptions {
    RunOptions {
        agent_bin: Some(agent_bin.to_path_buf()),
        wake,
        turn_deadline: BENCH_TURN_DEADLINE,
        progress: false,
        ..RunOptions::default()
    }
}
