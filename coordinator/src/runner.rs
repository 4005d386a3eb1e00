//! `coordinator run`: one agent process per agent, turns granted over iceoryx2, every
//! move checked by the safety monitor, faults survived, the run recorded.
//!
//! Liveness: while it waits for a move, the coordinator wakes every
//! [`LIVENESS_SLICE`] to ask the kernel whether the agent's process still exists, so a
//! killed agent is noticed within a slice, not at the end of the turn deadline. A dead
//! agent is frozen as an obstacle where it last stood and leaves the formation; with
//! `respawn`, a replacement process takes its place from there.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::bail;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use shared::geometry::{Point, Pose};
use shared::run::{Recorder, Run};
use shared::scenario::Scenario;
use shared::turn::{MAX_WAYPOINTS, Move, MoveStatus};
use shared::wire::{AgentState, StateKind, monotonic_ns};

use crate::agents::{self, AgentProcesses, Exit};
use crate::ipc::{CoordinatorIpc, TurnSplit};
use crate::monitor::SafetyMonitor;
use crate::output::Timing;
use crate::stats::Distribution;

/// How often the coordinator checks an agent's process while it waits for its move.
pub const LIVENESS_SLICE: Duration = Duration::from_millis(10);

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
    /// Test mode: start agent `.0` with `--misbehave .1`.
    pub misbehave: Vec<(usize, String)>,
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
    pub turn_samples: Vec<TurnSample>,
    /// The agents' CPU time while held idle ([`RunOptions::idle_probe`]).
    pub idle_cpu: Option<crate::bench::IdleCpu>,
}

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
}

/// What the hook of [`run_scenario_with`] sees between two steps.
pub struct BetweenSteps<'a> {
    /// The step just finished.
    pub step: usize,
    /// The run's ports (benchmarks ring the agents' echo through them).
    pub ipc: &'a CoordinatorIpc,
    /// Which agents are alive.
    pub alive: &'a [bool],
}

/// A new run's prefix: no other run on this machine uses it, and no one can predict it
/// (see [`shared::wire::RunPrefix`]).
pub fn unique_prefix() -> anyhow::Result<String> {
    Ok(shared::wire::RunPrefix::new_random()?.as_str().to_string())
}

fn rss_kib(pid: u32) -> Option<f64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
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
) -> anyhow::Result<RunOutcome> {
    run_scenario_with(scenario, centre_path, options, &mut |_| Ok(()))
}

/// [`run_scenario`] calling `between_steps` after every step (benchmarks measure their
/// references there, in the same run; an error ends the run).
pub fn run_scenario_with(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
    between_steps: &mut dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<RunOutcome> {
    let started = Instant::now();
    let n = scenario.agents.len();
    let bin = agents::locate_agent_binary(options.agent_bin.as_deref())?;
    agents::raise_fd_limit();
    crate::ipc::clean_stale_runs();
    let prefix = unique_prefix()?;
    // The run's private folder, made before anything else of the run (a folder already
    // there is refused); dropped last: after the agents and the node.
    let _root = shared::wire::RunRoot::create(&prefix)?;
    let mut ipc = CoordinatorIpc::create(&prefix, n)?;
    ipc.publish_mission(scenario)?;
    let mut procs = AgentProcesses::new(bin, &prefix, n);

    let result = Driver {
        scenario,
        options,
        ipc: &mut ipc,
        procs: &mut procs,
        missed: vec![0; n],
        between_steps,
    }
    .drive(centre_path, started);

    // Whatever happened, stop the agents and clean up before reporting.
    for i in procs.running() {
        let _ = ipc.notify_quit(i);
    }
    procs.stop_all(Duration::from_secs(2));
    drop(procs);
    ipc.shut_down()?;
    let mut outcome = result?;
    outcome.timing.wall_s = started.elapsed().as_secs_f64();
    outcome.prefix = prefix;
    Ok(outcome)
}

/// What the coordinator learned while waiting for a move.
enum Answer {
    /// The move arrived.
    Move(Box<AgentState>),
    /// The agent's process is gone; detected after this long.
    Dead(Duration),
    /// The deadline passed with the process alive.
    Missed,
    /// SIGINT or SIGTERM reached the coordinator.
    Interrupted,
}

struct Driver<'a> {
    scenario: &'a Scenario,
    options: &'a RunOptions,
    ipc: &'a mut CoordinatorIpc,
    procs: &'a mut AgentProcesses,
    /// Consecutive missed turns per agent.
    missed: Vec<u32>,
    /// Called after every step.
    between_steps: &'a mut dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()>,
}

impl Driver<'_> {
    fn spawn(&mut self, agent: usize, replacement: bool) -> anyhow::Result<()> {
        let mut extra = Vec::new();
        if !replacement
            && let Some((_, mode)) = self.options.misbehave.iter().find(|(a, _)| *a == agent)
        {
            extra = vec!["--misbehave".to_string(), mode.clone()];
        }
        self.procs.spawn(agent, &extra)?;
        Ok(())
    }

    fn drive(mut self, centre_path: &[Pose], started: Instant) -> anyhow::Result<RunOutcome> {
        let n = self.scenario.agents.len();
        for i in 0..n {
            self.spawn(i, false)?;
        }
        let all: Vec<usize> = (0..n).collect();
        wait_ready(self.ipc, self.procs, &all, self.options.startup_timeout)?;
        let startup_s = started.elapsed().as_secs_f64();
        self.ipc.update_connections()?;
        let idle_cpu = self.options.idle_probe.map(|hold| {
            let pids: Vec<u32> = (0..n).filter_map(|i| self.procs.pid(i)).collect();
            crate::bench::IdleCpu::measure(&pids, hold)
        });
        let mut turn_samples = Vec::with_capacity(n * centre_path.len());

        let monitor = SafetyMonitor::new(self.scenario.field, &self.scenario.obstacles);
        let mut recorder = Recorder::new(self.scenario, centre_path);
        let mut latency_us = Vec::with_capacity(n * centre_path.len());
        let mut compute_us = Vec::with_capacity(n * centre_path.len());
        let bar = progress_bar(
            centre_path.len().saturating_sub(1),
            &self.scenario.name,
            self.options.progress,
        );
        let mut interrupted = false;

        'steps: for (step, centre) in centre_path.iter().enumerate().skip(1) {
            // Agents that died while waiting for their turn are noticed now.
            let checked = Instant::now();
            for agent in 0..n {
                if recorder.alive()[agent] && self.procs.poll(agent) == Exit::Exited {
                    self.on_death(
                        &mut recorder,
                        step,
                        agent,
                        checked.elapsed(),
                        "exited between turns",
                    )?;
                }
            }
            for agent in 0..n {
                if !recorder.alive()[agent] {
                    continue;
                }
                let slot = self.scenario.agents[agent].slot.ideal_position(centre);
                let seq = self.ipc.publish_world(
                    step,
                    agent,
                    centre,
                    recorder.bodies(),
                    recorder.alive(),
                )?;
                let granted = Instant::now();
                let granted_ns = monotonic_ns();
                self.ipc.notify_turn(agent)?;
                if self.options.kills.contains(&(agent, step))
                    && let Some(pid) = self.procs.signal_kill(agent)
                {
                    recorder.note_fault(
                        step,
                        agent,
                        "killed",
                        format!("fault injection: SIGKILL to process {pid} during its turn"),
                        None,
                    );
                }
                match self.wait_answer(agent, seq, granted) {
                    Answer::Move(state) => {
                        let held_ns = monotonic_ns();
                        self.missed[agent] = 0;
                        let sample = TurnSample {
                            step,
                            agent,
                            latency_us: held_ns.saturating_sub(granted_ns) as f64 / 1e3,
                            compute_us: state.compute_ns as f64 / 1e3,
                            split: TurnSplit::of(granted_ns, &state, held_ns),
                        };
                        latency_us.push(sample.latency_us);
                        compute_us.push(sample.compute_us);
                        turn_samples.push(sample);
                        accept_or_reject(&monitor, &mut recorder, step, agent, slot, &state);
                    }
                    Answer::Dead(after) => {
                        self.on_death(&mut recorder, step, agent, after, "died during its turn")?;
                    }
                    Answer::Missed => self.on_missed(&mut recorder, step, agent, slot)?,
                    Answer::Interrupted => {
                        interrupted = true;
                        break 'steps;
                    }
                }
            }
            recorder.end_step(step);
            bar.inc(1);
            (self.between_steps)(BetweenSteps {
                step,
                ipc: self.ipc,
                alive: recorder.alive(),
            })?;
            if self.ipc.termination_requested() {
                interrupted = true;
                break;
            }
        }
        bar.finish_and_clear();

        let rss: Vec<f64> = (0..n)
            .filter_map(|i| self.procs.pid(i).and_then(rss_kib))
            .collect();
        let timing = Timing {
            turn_latency_us: Distribution::of(&latency_us),
            compute_us: Distribution::of(&compute_us),
            wall_s: 0.0,
            startup_s,
            agent_rss_kib: Distribution::of(&rss),
        };
        let run = if interrupted {
            recorder.snapshot()
        } else {
            recorder.finish(true)
        };
        Ok(RunOutcome {
            run,
            timing,
            interrupted,
            prefix: String::new(),
            turn_samples,
            idle_cpu,
        })
    }

    /// Wait for `agent`'s move to world `seq`, checking its process every slice.
    fn wait_answer(&mut self, agent: usize, seq: u64, granted: Instant) -> Answer {
        let deadline = granted + self.options.turn_deadline;
        loop {
            let until = (Instant::now() + LIVENESS_SLICE).min(deadline);
            let got = self.ipc.wait_state(&[agent], until, |s| {
                s.state_kind() == Some(StateKind::Move) && s.agent as usize == agent && s.seq == seq
            });
            match got {
                Ok(Some(state)) => return Answer::Move(Box::new(state)),
                Ok(None) => {}
                Err(e) => {
                    tracing::warn!("agent {agent}: {e:#}");
                }
            }
            if self.ipc.termination_requested() {
                return Answer::Interrupted;
            }
            if self.procs.poll(agent) == Exit::Exited {
                return Answer::Dead(granted.elapsed());
            }
            if Instant::now() >= deadline {
                return Answer::Missed;
            }
        }
    }

    /// Freeze a dead agent, clean its shared-memory resources, and respawn it if asked.
    fn on_death(
        &mut self,
        recorder: &mut Recorder,
        step: usize,
        agent: usize,
        after: Duration,
        how: &str,
    ) -> anyhow::Result<()> {
        let ms = after.as_secs_f64() * 1e3;
        tracing::warn!(
            "step {step}: agent {agent} {how}; frozen as an obstacle ({ms:.1} ms to notice)"
        );
        recorder.freeze_dead(step, agent, format!("the agent process {how}"), ms);
        self.procs.kill_now(agent);
        let cleaned = self.ipc.cleanup_dead_nodes();
        tracing::info!("cleaned the resources of {cleaned} dead node(s)");
        self.missed[agent] = 0;
        if self.options.respawn {
            self.respawn(recorder, step, agent)?;
        }
        Ok(())
    }

    fn respawn(
        &mut self,
        recorder: &mut Recorder,
        step: usize,
        agent: usize,
    ) -> anyhow::Result<()> {
        self.spawn(agent, true)?;
        match wait_ready(self.ipc, self.procs, &[agent], Duration::from_secs(10)) {
            Ok(()) => {
                self.ipc.update_connections()?;
                recorder.mark_alive(agent);
                let pid = self.procs.pid(agent).unwrap_or(0);
                recorder.note_fault(
                    step,
                    agent,
                    "respawned",
                    format!("replacement process {pid} takes the slot from the last position"),
                    None,
                );
            }
            Err(e) => {
                tracing::warn!("agent {agent}: the replacement did not start: {e:#}");
                self.procs.kill_now(agent);
                recorder.note_fault(step, agent, "respawn_failed", format!("{e:#}"), None);
            }
        }
        Ok(())
    }

    /// A live agent missed its deadline: it keeps its place; after too many misses in a
    /// row it is declared hung, killed and frozen.
    fn on_missed(
        &mut self,
        recorder: &mut Recorder,
        step: usize,
        agent: usize,
        slot: Point,
    ) -> anyhow::Result<()> {
        self.missed[agent] += 1;
        recorder.reject(
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
            recorder.note_fault(
                step,
                agent,
                "hung",
                format!("missed {} turns in a row; killed", self.missed[agent]),
                None,
            );
            self.on_death(recorder, step, agent, Duration::ZERO, "was killed as hung")?;
        }
        Ok(())
    }
}

/// Wait for the ready handshake of every agent in `agents`.
fn wait_ready(
    ipc: &CoordinatorIpc,
    procs: &mut AgentProcesses,
    agents: &[usize],
    timeout: Duration,
) -> anyhow::Result<()> {
    let deadline = Instant::now() + timeout;
    let mut pending: Vec<usize> = agents.to_vec();
    while !pending.is_empty() {
        let got = ipc.wait_state(
            &pending,
            (Instant::now() + Duration::from_millis(50)).min(deadline),
            |s| s.state_kind() == Some(StateKind::Ready) && pending.contains(&(s.agent as usize)),
        )?;
        if let Some(s) = got {
            pending.retain(|&i| i != s.agent as usize);
            continue;
        }
        if ipc.termination_requested() {
            bail!("interrupted while the agents were starting");
        }
        if let Some(&i) = pending.iter().find(|&&i| procs.poll(i) == Exit::Exited) {
            bail!("agent {i} exited before it was ready (see its error above)");
        }
        if Instant::now() >= deadline {
            bail!(
                "agents {pending:?} were not ready after {:.1} s",
                timeout.as_secs_f64()
            );
        }
    }
    Ok(())
}

/// Check a published move with the monitor (parry) and the recorder (plain geometry):
/// both must accept it.
fn accept_or_reject(
    monitor: &SafetyMonitor,
    recorder: &mut Recorder,
    step: usize,
    agent: usize,
    slot: Point,
    state: &AgentState,
) {
    let waypoints = state.waypoint_points();
    let best = Point::from(state.best);
    let from = recorder.bodies()[agent].position;
    let verdict = match state.move_status() {
        None => Err(format!("unknown move status code {}", state.status)),
        Some(status) if status as u8 > MoveStatus::PathTooLong as u8 => {
            Err(format!("an agent may not report status {}", status.name()))
        }
        Some(status) => monitor
            .check(
                agent,
                &from,
                &waypoints,
                &best,
                recorder.bodies(),
                MAX_WAYPOINTS,
            )
            .map(|()| status)
            .map_err(|r| r.to_string()),
    };
    match verdict {
        Ok(status) => {
            let mv = Move {
                slot: Point::from(state.slot),
                best,
                status,
                waypoints,
            };
            if let Err(v) = recorder.submit(step, agent, mv) {
                tracing::warn!("step {step}: agent {agent}'s move rejected: {v}");
            }
        }
        Err(why) => {
            tracing::warn!("step {step}: agent {agent}'s move rejected by the monitor: {why}");
            recorder.reject(step, agent, slot, MoveStatus::Rejected, why);
        }
    }
}
