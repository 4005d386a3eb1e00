//! Where a turn's time goes between the processes, cut at the agent's timestamps.

use serde::Serialize;

use runner::stats::Distribution;
use runner::turns::TurnSample;

/// The IPC overhead of a turn in three parts, from the agent's timestamps on the
/// machine's monotonic clock (turns whose stamps were missing are left out).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct OverheadSplit {
    /// Turn rung to agent awake: waking the agent's process, microseconds.
    pub to_agent_us: Distribution,
    /// Agent awake to move sent, minus compute: reading the world and writing the
    /// move in shared memory, microseconds.
    pub agent_io_us: Distribution,
    /// Move sent to the coordinator holding it: waking the coordinator, microseconds.
    pub to_coordinator_us: Distribution,
}

impl OverheadSplit {
    /// The split of the turns in `samples` that carry the agent's stamps.
    pub(crate) fn of(samples: &[TurnSample]) -> Self {
        let splits: Vec<_> = samples
            .iter()
            .filter_map(|t| t.split.map(|s| (s, t.compute_us)))
            .collect();
        Self {
            to_agent_us: Distribution::of_iter(splits.iter().map(|(s, _)| s.to_agent_us)),
            agent_io_us: Distribution::of_iter(
                splits
                    .iter()
                    .map(|(s, compute)| (s.in_agent_us - compute).max(0.0)),
            ),
            to_coordinator_us: Distribution::of_iter(
                splits.iter().map(|(s, _)| s.to_coordinator_us),
            ),
        }
    }
}

/// The echo's round trip in its two wake-ups (what is left is the agent sending its
/// empty answer).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct EchoSplit {
    /// Echo rung to agent awake, microseconds.
    pub to_agent_us: Distribution,
    /// Answer sent to the coordinator holding it, microseconds.
    pub to_coordinator_us: Distribution,
}
