//! What a run produced: the record, its timing, every answered turn; and what a run that
//! failed had recorded up to then.

use std::time::Instant;

use shared::run::record::Run;

use crate::ipc::TurnSplit;
use crate::output::{GroupTiming, StartupPhases, Timing};
use crate::procfs::IdleCpu;
use crate::stats::Distribution;

/// What a run produced.
#[derive(Debug)]
pub struct RunOutcome {
    /// The record (the same shape as the reference simulation's).
    pub run: Run,
    /// Latencies and times.
    pub timing: Timing,
    /// Whether SIGINT/SIGTERM stopped the run early.
    pub interrupted: bool,
    /// The run's iceoryx2 prefix (every resource of the run starts with it).
    pub prefix: String,
    /// Every answered turn, in order (for benchmarks: per-turn latency and compute).
    pub turn_samples: Vec<TurnSample>,
    /// The agents' CPU time while held idle ([`RunOptions::idle_probe`](crate::turns::RunOptions::idle_probe)).
    pub idle_cpu: Option<IdleCpu>,
}

impl RunOutcome {
    /// The latency of each answered turn of `agent`, in order, microseconds.
    pub fn turn_latencies_us(&self, agent: usize) -> impl Iterator<Item = f64> + '_ {
        self.turn_samples
            .iter()
            .filter(move |t| t.agent == agent)
            .map(|t| t.latency_us)
    }
}

/// A run the coordinator could not finish: what went wrong, and what it recorded up to
/// then (the agents are stopped and the shared memory removed all the same).
#[derive(Debug)]
pub struct RunFailure {
    /// What went wrong.
    pub error: anyhow::Error,
    /// The run up to the last complete step, marked not completed.
    pub partial: Box<RunOutcome>,
}

impl std::fmt::Display for RunFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:#}", self.error)
    }
}

impl std::error::Error for RunFailure {}

/// One answered turn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurnSample {
    /// The step.
    pub step: usize,
    /// The agent.
    pub agent: usize,
    /// Turn latency: from ringing the turn to holding the move, microseconds.
    pub latency_us: f64,
    /// The agent's own compute time for the move, microseconds.
    pub compute_us: f64,
    /// Where the latency went, if the agent stamped its state.
    pub split: Option<TurnSplit>,
    /// Granted without a ring: the agent had been told it came next and was to be
    /// polling its world (`--wait spin`).
    pub polled: bool,
}

/// One group's turns, from its first grant to its last answer judged.
#[derive(Clone, Copy, Debug)]
pub(super) struct GroupSample {
    /// Agents granted a turn.
    pub(super) size: usize,
    /// Wall time, microseconds.
    pub(super) wall_us: f64,
}

/// What the step loop has gathered so far; kept outside it so a failed run still
/// reports its complete steps.
#[derive(Default)]
pub(super) struct Progress {
    pub(super) startup_s: f64,
    /// Where the start-up went.
    pub(super) startup_phases: StartupPhases,
    /// The steps already logged when the run was resumed (none otherwise): the step
    /// loop's speed is of the steps run here.
    pub(super) steps_before: usize,
    /// Time spent in the step loop, seconds.
    pub(super) steps_s: f64,
    pub(super) latency_us: Vec<f64>,
    pub(super) compute_us: Vec<f64>,
    /// Each group's turns: how many agents were granted, and its wall time.
    pub(super) groups: Vec<GroupSample>,
    /// The share of the machine's CPU time that was idle during the step loop.
    pub(super) loop_idle_share: Option<f64>,
    pub(super) turn_samples: Vec<TurnSample>,
    pub(super) idle_cpu: Option<IdleCpu>,
    pub(super) rss_kib: Vec<f64>,
    pub(super) pss_kib: Vec<f64>,
    pub(super) cpu_s: Vec<f64>,
    pub(super) interrupted: bool,
    pub(super) completed: bool,
    /// The centre waited too long for a way through: the run ended short of the goal.
    pub(super) gave_up: bool,
}

impl GroupTiming {
    /// The figures of `groups`, the machine idle for `loop_idle_share` of the loop.
    fn of(groups: &[GroupSample], loop_idle_share: Option<f64>) -> Self {
        let sizes: Vec<f64> = groups.iter().map(|g| g.size as f64).collect();
        let walls: Vec<f64> = groups.iter().map(|g| g.wall_us).collect();
        Self {
            size: Distribution::of(&sizes),
            wall_us: Distribution::of(&walls),
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            loop_idle_share,
        }
    }
}

/// The outcome of a run that recorded `run` and gathered `progress`.
pub(super) fn outcome(
    run: Run,
    progress: Progress,
    prefix: String,
    started: Instant,
) -> RunOutcome {
    let steps = run
        .steps
        .len()
        .saturating_sub(1)
        .saturating_sub(progress.steps_before);
    RunOutcome {
        timing: Timing {
            steps_per_s: if progress.steps_s > 0.0 {
                steps as f64 / progress.steps_s
            } else {
                0.0
            },
            turn_latency_us: Distribution::of(&progress.latency_us),
            compute_us: Distribution::of(&progress.compute_us),
            wall_s: started.elapsed().as_secs_f64(),
            startup_s: progress.startup_s,
            startup_phases_s: progress.startup_phases,
            agent_rss_kib: Distribution::of(&progress.rss_kib),
            agent_pss_kib: Distribution::of(&progress.pss_kib),
            agent_cpu_s: Distribution::of(&progress.cpu_s),
            groups: GroupTiming::of(&progress.groups, progress.loop_idle_share),
        },
        run,
        interrupted: progress.interrupted,
        prefix,
        turn_samples: progress.turn_samples,
        idle_cpu: progress.idle_cpu,
    }
}
