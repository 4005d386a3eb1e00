//! The turns of a run over agent processes ([`run_scenario`], used by `coordinator run`,
//! `compare` and `bench`): one agent process per agent, turns granted over iceoryx2,
//! every move checked by the safety monitor, faults survived, the run recorded.
//!
//! Liveness: while it waits for a move, the coordinator wakes every
//! [`LIVENESS_SLICE`] to ask the kernel whether the agent's process still exists, so a
//! killed agent is noticed within a slice, not at the end of the turn deadline. A dead
//! agent is frozen as an obstacle where it last stood and leaves the formation; with
//! `respawn`, a replacement process takes its place from there.
//!
//! Trust: every agent is another process, so what arrives on its channel is checked
//! before use ([`wire::AgentState::read_checked`]) and judged here:
//! - a sample published by any process but the agent's own is `impersonation`: the
//!   process that sent it, if it is one of the run's agents, is killed and frozen;
//! - a sample that fails the checks is `malformed`; during a turn it ends the turn (the
//!   agent stays where it was);
//! - a move must carry the turn's token (drawn from a generator seeded by the OS random
//!   source when the world is published); anything else, and anything that arrives
//!   between turns, is `unsolicited` and changes nothing;
//! - an agent that exits, fails its handshake or never sends one is `failed-to-start`
//!   and frozen where it starts (or replaced, with `respawn`); the run goes on.
//!
//! If the coordinator itself fails (an error or a panic), its agents are still stopped,
//! the run's shared memory is still removed, and the steps completed so far are returned
//! in [`RunFailure::partial`].

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use shared::geometry::Pose;
use shared::record::{Recorder, Run};
use shared::scenario::Scenario;
use wire::misbehave::Misbehave;
use wire::{RunPrefix, RunRoot};

mod deaths;
mod driver;
mod faults;
mod judge;
mod startup;

use driver::Driver;
pub use driver::PROGRESS_TARGET;

use crate::agents::{self, AgentProcesses};
use crate::ipc::{CoordinatorIpc, TurnSplit};
pub use crate::network::NetworkOptions;
use crate::network::Router;
use crate::output::Timing;
use crate::procfs::IdleCpu;
use crate::stats::Distribution;

/// How often the coordinator checks an agent's process while it waits for its move.
const LIVENESS_SLICE: Duration = Duration::from_millis(10);

/// How the coordinator waits for a move, and how an agent waits for its turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum WaitMode {
    /// Sleep in a blocking event wait on both sides: no CPU spent waiting, two wake-ups
    /// per turn (the agent's and the coordinator's).
    Block,
    /// The coordinator spins (yielding) on the agent's state for up to [`SPIN_BUDGET`]
    /// before sleeping, and the agent whose turn comes next is told so and polls its
    /// world meanwhile; its turn is then granted by publishing the world alone, without a
    /// ring: no wake-up and no event on the turn's path, at the price of up to two busy
    /// cores while turns go on. Agents not next in line still sleep.
    Spin,
    /// `Spin` on a machine with two cores or more, `Block` on one core (where a spinning
    /// process would take the core from the one it waits for).
    #[default]
    Auto,
}

impl WaitMode {
    /// Whether to spin on this machine.
    pub fn spins(&self) -> bool {
        match self {
            Self::Block => false,
            Self::Spin => true,
            Self::Auto => std::thread::available_parallelism().is_ok_and(|n| n.get() >= 2),
        }
    }
}

/// How long the coordinator spins on an agent's state before it sleeps (`--wait spin`):
/// a turn computes in tens of microseconds; a longer one pays a wake-up as before.
pub const SPIN_BUDGET: Duration = Duration::from_millis(1);

/// How a run is carried out.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The agent executable (default: beside the coordinator).
    pub agent_bin: Option<PathBuf>,
    /// How long an agent has for its turn.
    pub turn_deadline: Duration,
    /// How long every agent together has to start and shake hands, plus
    /// [`STARTUP_PER_AGENT`] for each agent ([`RunOptions::startup_timeout_for`]).
    pub startup_timeout: Duration,
    /// Consecutive missed turns after which a live but silent agent is declared hung,
    /// killed and frozen.
    pub max_missed_turns: u32,
    /// Start a replacement process for every agent that dies.
    pub respawn: bool,
    /// Fault injection: kill agent `.0` with SIGKILL right after granting its turn at
    /// step `.1`.
    pub kills: Vec<(usize, usize)>,
    /// Deterministic fault injection: agent `.0` dies at step `.1` before its turn. Its
    /// process is killed with SIGKILL (and waited for) once the step's groups are formed,
    /// just before its group's turns are granted, so the death is always detected during
    /// its turn and its group mates still move: the run equals
    /// [`shared::simulate::simulate_along_with_deaths`] to the bit.
    pub deaths: Vec<(usize, usize)>,
    /// Test mode: start agent `.0` with `--misbehave .1` (its replacements behave).
    pub misbehave: Vec<(usize, Misbehave)>,
    /// Show a progress bar on stderr (only drawn on a terminal).
    pub progress: bool,
    /// How turns are handed over: sleeping, spinning, or chosen by the core count.
    pub wait: WaitMode,
    /// Benchmark hook: after the ready handshake, hold every agent idle this long (no
    /// turn) and measure the CPU time they used meanwhile ([`RunOutcome::idle_cpu`]).
    pub idle_probe: Option<Duration>,
    /// Agents over Zenoh: each agent's process is a relay to the agent itself, which runs
    /// here or on another machine ([`NetworkOptions`]); `None`: every agent on iceoryx2.
    pub network: Option<NetworkOptions>,
}

/// Start-up time allowed per agent on top of [`RunOptions::startup_timeout`]: the agents
/// start on the machine's few cores at once, so their handshakes take time in proportion
/// to their number (measured on 2 vCPUs: 780 agents ready 6.6 s after the run began, 8.5
/// ms per agent; this leaves room for a machine that is busy with other work).
pub const STARTUP_PER_AGENT: Duration = Duration::from_millis(25);

impl RunOptions {
    /// How long `agents` agents together have to start and shake hands.
    pub fn startup_timeout_for(&self, agents: usize) -> Duration {
        self.startup_timeout + STARTUP_PER_AGENT * u32::try_from(agents).unwrap_or(u32::MAX)
    }
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            agent_bin: None,
            turn_deadline: Duration::from_millis(250),
            startup_timeout: Duration::from_secs(30),
            max_missed_turns: 3,
            respawn: false,
            kills: Vec::new(),
            deaths: Vec::new(),
            misbehave: Vec::new(),
            progress: true,
            wait: WaitMode::default(),
            idle_probe: None,
            network: None,
        }
    }
}

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
    pub(crate) turn_samples: Vec<TurnSample>,
    /// The agents' CPU time while held idle ([`RunOptions::idle_probe`]).
    pub(crate) idle_cpu: Option<IdleCpu>,
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
pub(crate) struct TurnSample {
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

/// What the hook of [`run_scenario_with`] sees between two steps.
pub struct BetweenSteps<'a> {
    /// The step just finished.
    pub step: usize,
    /// The run's prefix (every resource of the run starts with it).
    pub prefix: &'a str,
    /// The run's ports (benchmarks ring the agents' echo through them).
    pub(crate) ipc: &'a CoordinatorIpc,
    /// Which agents are alive.
    pub alive: &'a [bool],
    /// Each agent's process id, if it has a process.
    pub pids: &'a [Option<u32>],
}

fn progress_bar(steps: usize, name: &str, enabled: bool) -> ProgressBar {
    if !enabled {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(steps as u64), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} steps, {elapsed} (eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(name.to_string());
    bar
}

/// Run `scenario` along `centre_path` with one agent process per agent.
pub fn run_scenario(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
) -> Result<RunOutcome, RunFailure> {
    run_scenario_with(scenario, centre_path, options, &mut |_| Ok(()))
}

/// What the step loop has gathered so far; kept outside it so a failed run still
/// reports its complete steps.
#[derive(Default)]
struct Progress {
    startup_s: f64,
    /// Time spent in the step loop, seconds.
    steps_s: f64,
    latency_us: Vec<f64>,
    compute_us: Vec<f64>,
    turn_samples: Vec<TurnSample>,
    idle_cpu: Option<IdleCpu>,
    rss_kib: Vec<f64>,
    interrupted: bool,
    completed: bool,
    /// The centre waited too long for a way through: the run ended short of the goal.
    gave_up: bool,
}

/// [`run_scenario`] calling `between_steps` after every step (benchmarks measure their
/// references there, in the same run; an error ends the run).
pub fn run_scenario_with(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
    between_steps: &mut dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()>,
) -> Result<RunOutcome, RunFailure> {
    let started = Instant::now();
    let n = scenario.agents.len();
    let mut recorder = Recorder::new(
        scenario,
        centre_path.first().copied().unwrap_or(scenario.path.start),
    );
    let mut progress = Progress::default();
    let fail = |error: anyhow::Error, recorder: &Recorder, progress: Progress| RunFailure {
        error,
        partial: Box::new(outcome(
            recorder.snapshot(),
            progress,
            String::new(),
            started,
        )),
    };
    let bin = match agents::locate_agent_binary(options.agent_bin.as_deref()) {
        Ok(bin) => bin,
        Err(e) => return Err(fail(e, &recorder, progress)),
    };
    if let Err(e) = agents::raise_fd_limit(n) {
        return Err(fail(e, &recorder, progress));
    }
    crate::stale_runs::clean_stale_runs();
    // No other run on this machine uses it, and no one can predict it.
    let prefix = match RunPrefix::new_random() {
        Ok(prefix) => prefix.to_string(),
        Err(e) => return Err(fail(e.into(), &recorder, progress)),
    };
    // The run's private folder, made before anything else of the run (a folder already
    // there is refused); dropped last: after the agents and the node.
    let _root = match RunRoot::create(&prefix) {
        Ok(root) => root,
        Err(e) => return Err(fail(e.into(), &recorder, progress)),
    };
    // The scenario as run, for the agents to read at start-up.
    if let Err(e) = wire::write_mission(&prefix, scenario) {
        return Err(fail(e.into(), &recorder, progress));
    }
    let mut ipc = match CoordinatorIpc::create(&prefix, scenario) {
        Ok(ipc) => ipc,
        Err(e) => {
            crate::stale_runs::remove_run_files(&prefix);
            return Err(fail(e, &recorder, progress));
        }
    };
    let router = match options
        .network
        .as_ref()
        .map(|network| Router::open(network, n))
        .transpose()
    {
        Ok(router) => router,
        Err(e) => {
            drop(ipc);
            crate::stale_runs::remove_run_files(&prefix);
            return Err(fail(e, &recorder, progress));
        }
    };
    let mut procs = AgentProcesses::new(bin, &prefix, n);

    let driven = catch_unwind(AssertUnwindSafe(|| {
        Driver {
            scenario,
            options,
            ipc: &mut ipc,
            procs: &mut procs,
            recorder: &mut recorder,
            progress: &mut progress,
            missed: vec![0; n],
            prepared: vec![None; n],
            spin: options.wait.spins(),
            senses: scenario.agents.iter().any(|a| a.sensing_radius_m.is_some()),
            between_steps,
        }
        .drive(centre_path, started)
    }));

    // Whatever happened, stop the agents and clean up before reporting.
    for i in procs.running() {
        let _ = ipc.notify_quit(i);
    }
    procs.stop_all(Duration::from_secs(2));
    drop(procs);
    if let Some(router) = router {
        router.close();
    }
    let cleaned = ipc.shut_down();
    let error = match driven {
        Ok(Ok(())) => cleaned.err(),
        Ok(Err(e)) => Some(e),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Some(anyhow::anyhow!("the coordinator panicked: {what}"))
        }
    };
    let run = if progress.completed && !progress.gave_up && error.is_none() {
        recorder.finish(true)
    } else {
        recorder.snapshot()
    };
    let result = outcome(run, progress, prefix, started);
    match error {
        None => Ok(result),
        Some(error) => Err(RunFailure {
            error,
            partial: Box::new(result),
        }),
    }
}

fn outcome(run: Run, progress: Progress, prefix: String, started: Instant) -> RunOutcome {
    let steps = run.steps.len().saturating_sub(1);
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
            agent_rss_kib: Distribution::of(&progress.rss_kib),
        },
        run,
        interrupted: progress.interrupted,
        prefix,
        turn_samples: progress.turn_samples,
        idle_cpu: progress.idle_cpu,
    }
}
