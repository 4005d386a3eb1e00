//! `coordinator run`: one agent process per agent, turns granted over iceoryx2, every
//! move checked by the safety monitor, the run recorded and written out.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

use anyhow::bail;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use shared::geometry::{Point, Pose};
use shared::run::{Recorder, Run};
use shared::scenario::Scenario;
use shared::turn::{MAX_WAYPOINTS, Move, MoveStatus};
use shared::wire::{AgentState, StateKind};

use crate::agents::{self, AgentProcesses, Exit};
use crate::ipc::CoordinatorIpc;
use crate::monitor::SafetyMonitor;
use crate::output::Timing;
use crate::stats::Distribution;

/// How a run is carried out.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The agent executable (default: beside the coordinator).
    pub agent_bin: Option<PathBuf>,
    /// How long an agent has for its turn before the coordinator checks on it.
    pub turn_deadline: Duration,
    /// How long every agent together has to start and shake hands.
    pub startup_timeout: Duration,
    /// Show a progress bar on stderr (only drawn on a terminal).
    pub progress: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            agent_bin: None,
            turn_deadline: Duration::from_millis(250),
            startup_timeout: Duration::from_secs(30),
            progress: true,
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
}

/// A prefix no other run on this machine uses: process id and a counter.
pub fn unique_prefix() -> String {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    format!(
        "fc{}x{}_",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    )
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
    let started = Instant::now();
    let n = scenario.agents.len();
    let bin = agents::locate_agent_binary(options.agent_bin.as_deref())?;
    agents::raise_fd_limit();
    let prefix = unique_prefix();
    let mut ipc = CoordinatorIpc::create(&prefix, n)?;
    ipc.publish_mission(scenario)?;
    let mut procs = AgentProcesses::new(bin, &prefix, n);

    let result = drive(
        scenario,
        centre_path,
        options,
        &mut ipc,
        &mut procs,
        started,
    );

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

fn drive(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
    ipc: &mut CoordinatorIpc,
    procs: &mut AgentProcesses,
    started: Instant,
) -> anyhow::Result<RunOutcome> {
    let n = scenario.agents.len();
    for i in 0..n {
        procs.spawn(i, &[])?;
    }
    wait_ready(ipc, procs, n, options.startup_timeout)?;
    let startup_s = started.elapsed().as_secs_f64();
    ipc.update_connections()?;

    let monitor = SafetyMonitor::new(scenario.field, &scenario.obstacles);
    let mut recorder = Recorder::new(scenario, centre_path);
    let mut latency_us = Vec::with_capacity(n * centre_path.len());
    let mut compute_us = Vec::with_capacity(n * centre_path.len());
    let bar = progress_bar(
        centre_path.len().saturating_sub(1),
        &scenario.name,
        options.progress,
    );
    let mut interrupted = false;

    'steps: for (step, centre) in centre_path.iter().enumerate().skip(1) {
        for agent in 0..n {
            if !recorder.alive()[agent] {
                continue;
            }
            let slot = scenario.agents[agent].slot.ideal_position(centre);
            let seq =
                ipc.publish_world(step, agent, centre, recorder.bodies(), recorder.alive())?;
            let sent = Instant::now();
            ipc.notify_turn(agent)?;
            let answer = ipc.wait_state(sent + options.turn_deadline, |s| {
                s.state_kind() == Some(StateKind::Move) && s.agent as usize == agent && s.seq == seq
            })?;
            if ipc.termination_requested() {
                interrupted = true;
                break 'steps;
            }
            match answer {
                Some(state) => {
                    latency_us.push(sent.elapsed().as_secs_f64() * 1e6);
                    compute_us.push(state.compute_ns as f64 / 1e3);
                    accept_or_reject(&monitor, &mut recorder, step, agent, slot, &state);
                }
                None => on_missed_turn(ipc, procs, &mut recorder, step, agent, slot),
            }
        }
        recorder.end_step(step);
        bar.inc(1);
    }
    bar.finish_and_clear();

    let rss: Vec<f64> = (0..n)
        .filter_map(|i| procs.pid(i).and_then(rss_kib))
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
    })
}

/// Wait for every agent's ready handshake.
fn wait_ready(
    ipc: &CoordinatorIpc,
    procs: &mut AgentProcesses,
    n: usize,
    timeout: Duration,
) -> anyhow::Result<()> {
    let deadline = Instant::now() + timeout;
    let mut ready = vec![false; n];
    let mut count = 0;
    while count < n {
        let got = ipc.wait_state(
            (Instant::now() + Duration::from_millis(100)).min(deadline),
            |s| s.state_kind() == Some(StateKind::Ready),
        )?;
        if let Some(s) = got {
            let i = s.agent as usize;
            if i < n && !ready[i] {
                ready[i] = true;
                count += 1;
            }
            continue;
        }
        if ipc.termination_requested() {
            bail!("interrupted while the agents were starting");
        }
        if let Some(i) = (0..n).find(|&i| !ready[i] && procs.poll(i) == Exit::Exited) {
            bail!("agent {i} exited before it was ready (see its error above)");
        }
        if Instant::now() >= deadline {
            let missing: Vec<usize> = (0..n).filter(|&i| !ready[i]).collect();
            bail!(
                "agents {missing:?} were not ready after {:.1} s",
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
            recorder.reject(step, agent, slot, "rejected", why);
        }
    }
}

/// An agent did not answer in time: dead agents are frozen as obstacles and leave the
/// formation; live ones keep their place and the miss is recorded.
fn on_missed_turn(
    ipc: &CoordinatorIpc,
    procs: &mut AgentProcesses,
    recorder: &mut Recorder,
    step: usize,
    agent: usize,
    slot: Point,
) {
    let exited = procs.poll(agent) == Exit::Exited;
    if exited || !ipc.agent_node_alive(agent) {
        tracing::warn!("step {step}: agent {agent} is dead; frozen as an obstacle");
        recorder.reject(step, agent, slot, "dead", "the agent process died".into());
        recorder.mark_dead(agent);
        if !exited {
            procs.kill_now(agent);
        }
        let cleaned = ipc.cleanup_dead_nodes();
        tracing::info!("cleaned the resources of {cleaned} dead node(s)");
    } else {
        tracing::warn!("step {step}: agent {agent} missed its turn deadline");
        recorder.reject(
            step,
            agent,
            slot,
            "missed",
            "no move before the turn deadline".into(),
        );
    }
}
