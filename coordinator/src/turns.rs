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

use anyhow::bail;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use shared::geometry::{Point, Pose};
use shared::record::{Recorder, Run};
use shared::scenario::Scenario;
use shared::vocabulary::{MAX_WAYPOINTS, Move, MoveStatus};
use wire::misbehave::Misbehave;
use wire::{MalformedState, RunPrefix, RunRoot, StateKind, StateMsg, monotonic_ns};

use crate::agents::{self, AgentProcesses, Exit};
use crate::ipc::{CoordinatorIpc, Grant, Incoming, TurnSplit};
use crate::monitor::SafetyMonitor;
use crate::output::Timing;
use crate::procfs::{self, IdleCpu};
use crate::stats::Distribution;

/// How often the coordinator checks an agent's process while it waits for its move.
const LIVENESS_SLICE: Duration = Duration::from_millis(10);

/// How a run is carried out.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The agent executable (default: beside the coordinator).
    pub agent_bin: Option<PathBuf>,
    /// How long an agent has for its turn.
    pub turn_deadline: Duration,
    /// How long every agent together has to start and shake hands.
    pub startup_timeout: Duration,
    /// Consecutive missed turns after which a live but silent agent is declared hung,
    /// killed and frozen.
    pub max_missed_turns: u32,
    /// Start a replacement process for every agent that dies.
    pub respawn: bool,
    /// Fault injection: kill agent `.0` with SIGKILL right after granting its turn at
    /// step `.1`.
    pub kills: Vec<(usize, usize)>,
    /// Test mode: start agent `.0` with `--misbehave .1` (its replacements behave).
    pub misbehave: Vec<(usize, Misbehave)>,
    /// Show a progress bar on stderr (only drawn on a terminal).
    pub progress: bool,
    /// Benchmark hook: after the ready handshake, hold every agent idle this long (no
    /// turn) and measure the CPU time they used meanwhile ([`RunOutcome::idle_cpu`]).
    pub idle_probe: Option<Duration>,
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
            misbehave: Vec::new(),
            progress: true,
            idle_probe: None,
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
    latency_us: Vec<f64>,
    compute_us: Vec<f64>,
    turn_samples: Vec<TurnSample>,
    idle_cpu: Option<IdleCpu>,
    rss_kib: Vec<f64>,
    interrupted: bool,
    completed: bool,
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
    let mut recorder = Recorder::new(scenario, centre_path);
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
    agents::raise_fd_limit();
    crate::ipc::clean_stale_runs();
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
    let mut ipc = match CoordinatorIpc::create(&prefix, scenario) {
        Ok(ipc) => ipc,
        Err(e) => {
            crate::ipc::remove_run_files(&prefix);
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
    let run = if progress.completed && error.is_none() {
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
    RunOutcome {
        run,
        timing: Timing {
            turn_latency_us: Distribution::of(&progress.latency_us),
            compute_us: Distribution::of(&progress.compute_us),
            wall_s: started.elapsed().as_secs_f64(),
            startup_s: progress.startup_s,
            agent_rss_kib: Distribution::of(&progress.rss_kib),
        },
        interrupted: progress.interrupted,
        prefix,
        turn_samples: progress.turn_samples,
        idle_cpu: progress.idle_cpu,
    }
}

/// What the coordinator learned while waiting for a move.
enum Answer {
    /// The move arrived.
    Move(Box<StateMsg>),
    /// The agent answered its turn with a sample that failed the checks.
    Malformed(String),
    /// The agent's process is gone; detected after this long.
    Dead(Duration),
    /// The deadline passed with the process alive.
    Missed,
    /// SIGINT or SIGTERM reached the coordinator.
    Interrupted,
}

struct Driver<'a, 's> {
    scenario: &'a Scenario,
    options: &'a RunOptions,
    ipc: &'a mut CoordinatorIpc,
    procs: &'a mut AgentProcesses,
    recorder: &'a mut Recorder<'s>,
    progress: &'a mut Progress,
    /// Consecutive missed turns per agent.
    missed: Vec<u32>,
    /// Called after every step.
    between_steps: &'a mut dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()>,
}

impl Driver<'_, '_> {
    /// Start `agent`'s process on its open channel; a replacement never misbehaves.
    fn spawn(&mut self, agent: usize, replacement: bool) -> anyhow::Result<()> {
        let generation = self.ipc.generation(agent).unwrap_or(0);
        let mut extra = vec!["--generation".to_string(), generation.to_string()];
        if !replacement
            && let Some((_, mode)) = self.options.misbehave.iter().find(|(a, _)| *a == agent)
        {
            extra.extend(["--misbehave".to_string(), mode.to_string()]);
        }
        self.procs.spawn(agent, &extra)?;
        Ok(())
    }

    fn pids(&self) -> Vec<Option<u32>> {
        (0..self.scenario.agents.len())
            .map(|i| self.procs.pid(i))
            .collect()
    }

    fn drive(mut self, centre_path: &[Pose], started: Instant) -> anyhow::Result<()> {
        let n = self.scenario.agents.len();
        for i in 0..n {
            self.spawn(i, false)?;
        }
        let all: Vec<usize> = (0..n).collect();
        self.start_agents(0, &all, self.options.startup_timeout, false)?;
        self.progress.startup_s = started.elapsed().as_secs_f64();
        self.progress.idle_cpu = self.options.idle_probe.map(|hold| {
            let pids: Vec<u32> = self.pids().into_iter().flatten().collect();
            IdleCpu::measure(&pids, hold)
        });
        self.progress.turn_samples.reserve(n * centre_path.len());

        let monitor = SafetyMonitor::new(self.scenario.field, &self.scenario.obstacles);
        let bar = progress_bar(
            centre_path.len().saturating_sub(1),
            &self.scenario.name,
            self.options.progress,
        );

        'steps: for (step, centre) in centre_path.iter().enumerate().skip(1) {
            // Agents that died while waiting for their turn are noticed now.
            let checked = Instant::now();
            for agent in 0..n {
                if self.recorder.alive()[agent] && self.procs.poll(agent) == Exit::Exited {
                    self.on_death(step, agent, checked.elapsed(), "exited between turns")?;
                }
            }
            for agent in 0..n {
                if !self.recorder.alive()[agent] {
                    continue;
                }
                if self.take_turn(&monitor, step, agent, centre)? {
                    break 'steps;
                }
            }
            self.recorder.end_step(step);
            bar.inc(1);
            let pids = self.pids();
            (self.between_steps)(BetweenSteps {
                step,
                prefix: self.ipc.prefix(),
                ipc: self.ipc,
                alive: self.recorder.alive(),
                pids: &pids,
            })?;
            if self.ipc.termination_requested() {
                self.progress.interrupted = true;
                break;
            }
        }
        bar.finish_and_clear();
        self.progress.rss_kib = self
            .pids()
            .into_iter()
            .flatten()
            .filter_map(procfs::rss_kib)
            .collect();
        self.progress.completed = !self.progress.interrupted;
        Ok(())
    }

    /// Grant `agent` its turn at `step` and judge the answer; true if the run was
    /// interrupted.
    fn take_turn(
        &mut self,
        monitor: &SafetyMonitor,
        step: usize,
        agent: usize,
        centre: &Pose,
    ) -> anyhow::Result<bool> {
        // Nothing that arrived since the agent's last turn answers this one.
        self.drain(step, agent)?;
        if !self.recorder.alive()[agent] {
            return Ok(false);
        }
        let slot = self.scenario.agents[agent].slot.ideal_position(centre);
        // Stamped before the world exists, so no answer to it can predate the stamp.
        let granted = Instant::now();
        let granted_ns = monotonic_ns();
        let grant = self.ipc.publish_world(
            step,
            agent,
            centre,
            self.recorder.bodies(),
            self.recorder.alive(),
        )?;
        self.ipc.notify_turn(agent)?;
        if self.options.kills.contains(&(agent, step))
            && let Some(pid) = self.procs.signal_kill(agent)
        {
            self.recorder.note_fault(
                step,
                agent,
                "killed",
                format!("fault injection: SIGKILL to process {pid} during its turn"),
                None,
            );
        }
        match self.wait_answer(step, agent, grant, granted)? {
            Answer::Move(msg) => {
                let held_ns = monotonic_ns();
                self.missed[agent] = 0;
                let latency_ns = held_ns.saturating_sub(granted_ns);
                if msg.compute_ns > latency_ns {
                    self.recorder.note_fault(
                        step,
                        agent,
                        "malformed",
                        format!(
                            "reports {} ns of compute in a turn of {latency_ns} ns; counted as {latency_ns} ns",
                            msg.compute_ns
                        ),
                        None,
                    );
                }
                let sample = TurnSample {
                    step,
                    agent,
                    latency_us: latency_ns as f64 / 1e3,
                    compute_us: msg.compute_ns.min(latency_ns) as f64 / 1e3,
                    split: TurnSplit::of(granted_ns, &msg, held_ns),
                };
                self.progress.latency_us.push(sample.latency_us);
                self.progress.compute_us.push(sample.compute_us);
                self.progress.turn_samples.push(sample);
                accept_or_reject(monitor, self.recorder, step, agent, slot, *msg);
            }
            Answer::Malformed(why) => {
                self.missed[agent] = 0;
                tracing::debug!("step {step}: agent {agent}'s answer refused: {why}");
                self.recorder
                    .reject_as(step, agent, slot, MoveStatus::Rejected, "malformed", why);
            }
            Answer::Dead(after) => {
                self.on_death(step, agent, after, "died during its turn")?;
            }
            Answer::Missed => self.on_missed(step, agent, slot)?,
            Answer::Interrupted => {
                self.progress.interrupted = true;
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Take in whatever `agent`'s channel holds between turns: none of it answers a
    /// turn. Recorded, never used.
    fn drain(&mut self, step: usize, agent: usize) -> anyhow::Result<()> {
        let pid = self.procs.pid(agent);
        let (mut extra, mut malformed) = (0usize, Vec::new());
        while let Some(incoming) = self.ipc.receive(agent) {
            if let Some(from) = incoming.publisher_pid
                && Some(from) != pid
            {
                self.on_impersonation(step, agent, from)?;
                continue;
            }
            match incoming.msg {
                Ok(msg) if msg.kind == StateKind::Echo => {}
                Ok(_) => extra += 1,
                Err(why) => {
                    let unreadable = matches!(why, MalformedState::Unreadable(_));
                    malformed.push(why.to_string());
                    if unreadable {
                        break;
                    }
                }
            }
        }
        if extra > 0 {
            self.recorder.note_fault(
                step,
                agent,
                "unsolicited",
                format!(
                    "{extra} state(s) arrived between turns (an extra move, or an answer to a turn not yet granted); ignored"
                ),
                None,
            );
        }
        if let Some(first) = malformed.first() {
            self.recorder.note_fault(
                step,
                agent,
                "malformed",
                format!(
                    "{} sample(s) between turns failed the checks, first: {first}",
                    malformed.len()
                ),
                None,
            );
        }
        Ok(())
    }

    /// Wait for `agent`'s answer to `grant`, checking its process every slice.
    fn wait_answer(
        &mut self,
        step: usize,
        agent: usize,
        grant: Grant,
        granted: Instant,
    ) -> anyhow::Result<Answer> {
        let deadline = granted + self.options.turn_deadline;
        let pid = self.procs.pid(agent);
        let mut unsolicited = 0usize;
        let answer = loop {
            let mut found = None;
            while let Some(incoming) = self.ipc.receive(agent) {
                if let Some(from) = incoming.publisher_pid
                    && Some(from) != pid
                {
                    self.on_impersonation(step, agent, from)?;
                    continue;
                }
                match judge_answer(incoming, grant, step, pid) {
                    Judged::Answer(a) => {
                        found = Some(a);
                        break;
                    }
                    Judged::Unsolicited => unsolicited += 1,
                    Judged::Ignore => {}
                }
            }
            if let Some(a) = found {
                break a;
            }
            if self.ipc.termination_requested() {
                break Answer::Interrupted;
            }
            if self.procs.poll(agent) == Exit::Exited {
                break Answer::Dead(granted.elapsed());
            }
            let now = Instant::now();
            if now >= deadline {
                break Answer::Missed;
            }
            self.ipc
                .wait_done(agent, (now + LIVENESS_SLICE).min(deadline));
        };
        if unsolicited > 0 {
            self.recorder.note_fault(
                step,
                agent,
                "unsolicited",
                format!(
                    "{unsolicited} state(s) during the turn carried no valid token for it (replayed or guessed); ignored"
                ),
                None,
            );
        }
        Ok(answer)
    }

    /// A sample on `channel_agent`'s channel was published by process `publisher_pid`,
    /// not by the agent's own: the culprit, if it is one of the run's agents, is killed
    /// and frozen.
    fn on_impersonation(
        &mut self,
        step: usize,
        channel_agent: usize,
        publisher_pid: u32,
    ) -> anyhow::Result<()> {
        self.on_intruder(step, channel_agent, publisher_pid, "published on")
    }

    /// Process `pid` used `channel_agent`'s channel (`how`): recorded against the culprit
    /// agent, which is killed and frozen, or against the channel if it is no agent.
    fn on_intruder(
        &mut self,
        step: usize,
        channel_agent: usize,
        pid: u32,
        how: &str,
    ) -> anyhow::Result<()> {
        let culprit = self.procs.agent_of_pid(pid);
        tracing::warn!(
            "step {step}: process {pid} (agent {culprit:?}) {how} agent {channel_agent}'s channel"
        );
        match culprit {
            Some(c) if self.recorder.alive()[c] && self.procs.pid(c) == Some(pid) => {
                self.recorder.note_fault(
                    step,
                    c,
                    "impersonation",
                    format!("process {pid} {how} agent {channel_agent}'s channel; killed"),
                    None,
                );
                self.on_death(step, c, Duration::ZERO, "was killed for impersonation")?;
            }
            // An earlier process of an agent, already killed and recorded.
            Some(_) => {}
            None => self.recorder.note_fault(
                step,
                channel_agent,
                "impersonation",
                format!("process {pid}, not an agent of this run, {how} this agent's channel"),
                None,
            ),
        }
        Ok(())
    }

    /// Look for processes attached to the channels of `agents` that are not theirs.
    fn scan_for_intruders(&mut self, step: usize, agents: &[usize]) -> anyhow::Result<()> {
        for &agent in agents {
            let Some(pid) = self.procs.pid(agent) else {
                continue;
            };
            for intruder in self.ipc.intruders(agent, pid) {
                self.on_intruder(step, agent, intruder, "opened the services of")?;
            }
        }
        Ok(())
    }

    /// Wait for the ready handshake of every agent in `agents` (their processes are
    /// started). An agent that exits first, sends a bad handshake or none in `timeout`
    /// is recorded `failed-to-start` and frozen (or replaced, with `respawn`). For
    /// `replacements`, success is recorded `respawned` and failure `respawn_failed`,
    /// never retried.
    fn start_agents(
        &mut self,
        step: usize,
        agents: &[usize],
        timeout: Duration,
        replacements: bool,
    ) -> anyhow::Result<()> {
        let deadline = Instant::now() + timeout;
        let mut pending: Vec<usize> = agents.to_vec();
        let mut failed: Vec<(usize, String)> = Vec::new();
        while !pending.is_empty() {
            for agent in pending.clone() {
                let pid = self.procs.pid(agent);
                if pid.is_none() || self.ipc.generation(agent).is_none() {
                    // Quarantined while the others started.
                    pending.retain(|&a| a != agent);
                    continue;
                }
                while let Some(incoming) = self.ipc.receive(agent) {
                    if let Some(from) = incoming.publisher_pid
                        && Some(from) != pid
                    {
                        self.on_impersonation(step, agent, from)?;
                        continue;
                    }
                    match incoming.msg {
                        Ok(msg) if msg.kind == StateKind::Ready && Some(msg.pid) == pid => {
                            pending.retain(|&a| a != agent);
                            if let Err(e) = self.ipc.update_connections(agent) {
                                tracing::warn!("agent {agent}: {e:#}");
                            }
                            if replacements {
                                self.recorder.mark_alive(agent);
                                self.recorder.note_fault(
                                    step,
                                    agent,
                                    "respawned",
                                    format!(
                                        "replacement process {} takes the slot from the last position",
                                        msg.pid
                                    ),
                                    None,
                                );
                            }
                            break;
                        }
                        Ok(msg) if msg.kind == StateKind::Ready => {
                            failed.push((
                                agent,
                                format!("its handshake claims process {}, not {pid:?}", msg.pid),
                            ));
                            pending.retain(|&a| a != agent);
                            break;
                        }
                        Ok(msg) => self.recorder.note_fault(
                            step,
                            agent,
                            "unsolicited",
                            format!("a {:?} message before its handshake; ignored", msg.kind),
                            None,
                        ),
                        Err(why) => {
                            self.recorder.note_fault(
                                step,
                                agent,
                                "malformed",
                                format!("handshake: {why}"),
                                None,
                            );
                            failed.push((agent, format!("a malformed handshake ({why})")));
                            pending.retain(|&a| a != agent);
                            break;
                        }
                    }
                }
            }
            // Quarantined agents (impersonators) are no longer waited for.
            pending.retain(|&a| self.procs.pid(a).is_some());
            for agent in pending.clone() {
                if self.procs.poll(agent) == Exit::Exited {
                    failed.push((agent, "it exited before its handshake".to_string()));
                    pending.retain(|&a| a != agent);
                }
            }
            if pending.is_empty() {
                break;
            }
            if self.ipc.termination_requested() {
                bail!("interrupted while the agents were starting");
            }
            if Instant::now() >= deadline {
                for &agent in &pending {
                    failed.push((
                        agent,
                        format!("no handshake within {:.1} s", timeout.as_secs_f64()),
                    ));
                }
                break;
            }
            self.ipc
                .wait_done(pending[0], (Instant::now() + LIVENESS_SLICE).min(deadline));
        }
        let started: Vec<usize> = agents
            .iter()
            .copied()
            .filter(|a| !failed.iter().any(|(f, _)| f == a))
            .collect();
        self.scan_for_intruders(step, &started)?;
        for (agent, why) in failed {
            if replacements {
                tracing::warn!("agent {agent}: the replacement did not start: {why}");
                self.procs.kill_now(agent);
                self.ipc.close_channel(agent);
                self.ipc.cleanup_dead_nodes();
                self.recorder
                    .note_fault(step, agent, "respawn_failed", why, None);
            } else {
                self.on_failed_start(step, agent, &why)?;
            }
        }
        Ok(())
    }

    /// `agent` did not start: frozen where it stands, replaced if `respawn` asks.
    fn on_failed_start(&mut self, step: usize, agent: usize, why: &str) -> anyhow::Result<()> {
        tracing::warn!("step {step}: agent {agent} failed to start: {why}");
        let pid = self.procs.pid(agent);
        self.procs.kill_now(agent);
        // Whoever sat on its channel is named before the channel goes.
        if let Some(pid) = pid {
            for intruder in self.ipc.intruders(agent, pid) {
                self.on_intruder(step, agent, intruder, "opened the services of")?;
            }
        }
        self.ipc.close_channel(agent);
        self.ipc.cleanup_dead_nodes();
        if self.recorder.alive()[agent] {
            self.recorder.freeze(
                step,
                agent,
                "failed-to-start",
                format!("the agent process did not start: {why}"),
                None,
            );
        }
        if self.options.respawn {
            self.respawn(step, agent)?;
        }
        Ok(())
    }

    /// Freeze a dead agent, clean its shared-memory resources, and respawn it if asked.
    fn on_death(
        &mut self,
        step: usize,
        agent: usize,
        after: Duration,
        how: &str,
    ) -> anyhow::Result<()> {
        let ms = after.as_secs_f64() * 1e3;
        tracing::warn!(
            "step {step}: agent {agent} {how}; frozen as an obstacle ({ms:.1} ms to notice)"
        );
        self.recorder
            .freeze_dead(step, agent, format!("the agent process {how}"), ms);
        self.procs.kill_now(agent);
        self.ipc.close_channel(agent);
        let cleaned = self.ipc.cleanup_dead_nodes();
        tracing::info!("cleaned the resources of {cleaned} dead node(s)");
        self.missed[agent] = 0;
        if self.options.respawn {
            self.respawn(step, agent)?;
        }
        Ok(())
    }

    /// Start a replacement process for `agent` on a channel of its own.
    fn respawn(&mut self, step: usize, agent: usize) -> anyhow::Result<()> {
        let opened = self
            .ipc
            .open_channel(agent, self.scenario)
            .and_then(|_| self.spawn(agent, true));
        if let Err(e) = opened {
            tracing::warn!("agent {agent}: the replacement did not start: {e:#}");
            self.recorder
                .note_fault(step, agent, "respawn_failed", format!("{e:#}"), None);
            return Ok(());
        }
        // The replacement's own failure is recorded, and not retried (no respawn loop).
        self.start_agents(step, &[agent], REPLACEMENT_TIMEOUT, true)
    }

    /// A live agent missed its deadline: it keeps its place; after too many misses in a
    /// row it is declared hung, killed and frozen.
    fn on_missed(&mut self, step: usize, agent: usize, slot: Point) -> anyhow::Result<()> {
        self.missed[agent] += 1;
        self.recorder.reject(
            step,
            agent,
            slot,
            MoveStatus::Missed,
            format!(
                "no move within the {:?} turn deadline",
                self.options.turn_deadline
            ),
        );
        if self.missed[agent] >= self.options.max_missed_turns {
            tracing::warn!(
                "step {step}: agent {agent} missed {} turns in a row: killing it",
                self.missed[agent]
            );
            self.recorder.note_fault(
                step,
                agent,
                "hung",
                format!("missed {} turns in a row; killed", self.missed[agent]),
                None,
            );
            self.on_death(step, agent, Duration::ZERO, "was killed as hung")?;
        }
        Ok(())
    }
}

/// How long a replacement process has to shake hands.
const REPLACEMENT_TIMEOUT: Duration = Duration::from_secs(10);

/// What a sample from the agent's own process means during its turn.
enum Judged {
    /// It ends the turn.
    Answer(Answer),
    /// It answers no turn (a replay, a guess, a handshake): counted, ignored.
    Unsolicited,
    /// A late echo: no fault.
    Ignore,
}

/// Judge `incoming` during the turn of `grant` at `step`, from the agent's process `pid`.
fn judge_answer(incoming: Incoming, grant: Grant, step: usize, pid: Option<u32>) -> Judged {
    let msg = match incoming.msg {
        Ok(msg) => msg,
        Err(why) => return Judged::Answer(Answer::Malformed(why.to_string())),
    };
    match msg.kind {
        StateKind::Echo => Judged::Ignore,
        StateKind::Move if msg.token == grant.token => {
            let bad = if msg.seq != grant.seq {
                Some(format!("answers world {} in turn {}", msg.seq, grant.seq))
            } else if msg.step != step as u64 {
                Some(format!("answers step {} at step {step}", msg.step))
            } else if Some(msg.pid) != pid {
                Some(format!("claims process {}, not {pid:?}", msg.pid))
            } else {
                None
            };
            match bad {
                Some(why) => Judged::Answer(Answer::Malformed(why)),
                None => Judged::Answer(Answer::Move(Box::new(msg))),
            }
        }
        StateKind::Move | StateKind::Ready => Judged::Unsolicited,
    }
}

/// Check a published move with the monitor (parry) and the recorder (plain geometry):
/// both must accept it.
fn accept_or_reject(
    monitor: &SafetyMonitor,
    recorder: &mut Recorder,
    step: usize,
    agent: usize,
    slot: Point,
    msg: StateMsg,
) {
    let from = recorder.bodies()[agent].position;
    let verdict = match msg.move_status() {
        None => Err(format!("unknown move status code {}", msg.status)),
        Some(status) if status as u8 > MoveStatus::PathTooLong as u8 => {
            Err(format!("an agent may not report status {}", status.name()))
        }
        Some(status) => monitor
            .check(
                agent,
                &from,
                &msg.waypoints,
                &msg.best,
                recorder.bodies(),
                MAX_WAYPOINTS,
            )
            .map(|()| status)
            .map_err(|r| r.to_string()),
    };
    match verdict {
        Ok(status) => {
            let mv = Move {
                slot: msg.slot,
                best: msg.best,
                status,
                waypoints: msg.waypoints,
            };
            if let Err(v) = recorder.submit(step, agent, mv) {
                tracing::debug!("step {step}: agent {agent}'s move rejected: {v}");
            }
        }
        Err(why) => {
            tracing::debug!("step {step}: agent {agent}'s move rejected by the monitor: {why}");
            recorder.reject(step, agent, slot, MoveStatus::Rejected, why);
        }
    }
}
