//! The step loop: every live agent takes its turn, one group at a time (one agent a group
//! in sequential mode); the answers are judged and checked before the recorder takes
//! them. [`Driver`] is one run while it goes; its methods are spread over `turns/` by
//! concern: the step loop here, a group's turns in `turn.rs`, waiting for an answer in
//! `answer.rs`, handshakes in `startup.rs`, faults in `faults.rs` and `deaths.rs`.

use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use shared::course::Course;
use shared::geometry::{Point, Pose};
use shared::groups::turn_groups_ordered;
use shared::record::{Recorder, replay_course};
use shared::scenario::Scenario;
use shared::tracking::MAX_HORIZON_STEPS;

use super::hand_over::HandOver;
use super::lateness::TurnHistory;
use super::options::RunOptions;
use super::outcome::Progress;
use crate::agents::{AgentProcesses, Exit, StartGate};
use crate::ipc::CoordinatorIpc;
use crate::monitor::SafetyMonitor;
use crate::network::NetworkOptions;
use crate::procfs::{self, IdleCpu};

/// The `tracing` target of the line logged when a step is done (`step N done`):
/// `RUST_LOG=coordinator::progress=info` shows one such line per step on stderr.
pub const PROGRESS_TARGET: &str = "coordinator::progress";

/// What the hook of [`super::run_scenario_with`] sees between two steps.
pub struct BetweenSteps<'a> {
    /// The step just finished.
    pub step: usize,
    /// The run's prefix (every resource of the run starts with it).
    pub prefix: &'a str,
    /// The run's ports (benchmarks ring the agents' echo through them).
    pub(crate) ipc: &'a CoordinatorIpc,
    /// Which agents are alive.
    pub alive: &'a [bool],
    /// The step's groups of turns (agents granted together), in the order taken.
    pub groups: &'a [Vec<usize>],
    /// Each agent's process id, if it has a process.
    pub pids: &'a [Option<u32>],
}

/// What a caller does after every step ([`super::run_scenario_with`]).
pub type BetweenStepsFn<'a> = dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()> + 'a;

/// One run while it goes: the scenario and options, the ports and processes, the record
/// and what the step loop has measured.
pub(super) struct Driver<'a, 's> {
    pub(super) scenario: &'a Scenario,
    pub(super) options: &'a RunOptions,
    pub(super) ipc: &'a mut CoordinatorIpc,
    pub(super) procs: &'a mut AgentProcesses,
    pub(super) recorder: &'a mut Recorder<'s>,
    pub(super) progress: &'a mut Progress,
    /// How late every agent's last turns were.
    pub(super) history: TurnHistory,
    /// How a turn is handed over to the next agent.
    pub(super) hand_over: HandOver,
    /// Whether any agent has a sensing radius (then each world lists what it senses).
    pub(super) senses: bool,
    /// Whether the run has a control group for its sandboxed agents.
    pub(super) run_cgroup: bool,
    /// How agents reach the router, as it was opened (the run's own TLS folder named).
    pub(super) network: Option<&'a NetworkOptions>,
    /// The run's log, handed every step as it ends (written by a thread of its own,
    /// which also tells each step done once it is in the file).
    pub(super) log: Option<&'a mut crate::run_log::LogThread>,
    /// How many of the turn samples are in the log.
    pub(super) turns_logged: usize,
    /// The mission file's digest, handed to every process started.
    pub(super) mission_digest: wire::MissionDigest,
    /// The agents already started, behind their gate (none over a network).
    pub(super) early: Option<EarlyStart>,
    /// Called after every step.
    /// What the caller does after every step (benchmarks), if anything.
    pub(super) between_steps: Option<&'a mut BetweenStepsFn<'a>>,
}

/// The agents started before the run's channels existed, waiting behind a gate
/// ([`crate::agents::StartGate`]) that [`Driver::drive`] opens.
pub(super) struct EarlyStart {
    /// The gate they wait behind.
    pub(super) gate: StartGate,
    /// The agents whose process could not be started, and why.
    pub(super) failed: Vec<(usize, String)>,
    /// How long starting them took, seconds.
    pub(super) spawn_s: f64,
}

/// The command-line arguments of agent `agent`'s process beyond its prefix and index:
/// its channel's `generation`, the mission's digest, its test mode unless it is a
/// `replacement` (a replacement never misbehaves), and its relay's settings: a sandbox
/// relay for an agent this host starts when the run sandboxes (over Zenoh too), a
/// network relay for the others over Zenoh.
pub(super) fn agent_args(
    options: &RunOptions,
    agent: usize,
    replacement: bool,
    generation: u32,
    mission_digest: &wire::MissionDigest,
    network: Option<&NetworkOptions>,
    run_cgroup: bool,
) -> Vec<String> {
    let mut extra = vec![
        "--generation".to_string(),
        generation.to_string(),
        "--mission-sha256".to_string(),
        mission_digest.to_string(),
    ];
    if !replacement && let Some((_, mode)) = options.misbehave.iter().find(|(a, _)| *a == agent) {
        extra.extend(["--misbehave".to_string(), mode.to_string()]);
    }
    // An agent this host starts is sandboxed when the run sandboxes, over Zenoh too:
    // behind the sandbox's socket relay, with no key and no link of its own. An agent
    // started elsewhere (`--remote`) has a network relay here.
    let here = network.is_none_or(|n| n.starts_here(agent));
    match (&options.sandbox, network) {
        (Some(sandbox), _) if here => extra.extend(sandbox.relay_args(agent, run_cgroup)),
        (_, Some(network)) => extra.extend(network.relay_args(agent)),
        (_, None) => {}
    }
    extra
}

impl Driver<'_, '_> {
    /// Start `agent`'s process on its open channel; a replacement never misbehaves.
    pub(super) fn spawn(&mut self, agent: usize, replacement: bool) -> anyhow::Result<()> {
        let generation = self.ipc.generation(agent).unwrap_or(0);
        let extra = agent_args(
            self.options,
            agent,
            replacement,
            generation,
            &self.mission_digest,
            self.network,
            self.run_cgroup,
        );
        self.procs.spawn(agent, &extra)?;
        Ok(())
    }

    /// Log the step just recorded, with what happened since the last one.
    fn log_step(&mut self, course: Option<&Course<'_>>) -> anyhow::Result<()> {
        let course = course.map(crate::run_log::CourseSoFar::of);
        let Some(log) = self.log.as_deref_mut() else {
            return Ok(());
        };
        let Some(step) = self.recorder.steps().last() else {
            return Ok(());
        };
        let turns = self.progress.turn_samples[self.turns_logged..]
            .iter()
            .map(|t| crate::run_log::TurnMessage {
                step: t.step,
                agent: t.agent,
                latency_us: t.latency_us,
                compute_us: t.compute_us,
            })
            .collect();
        log.log_step(step, self.recorder.faults(), course, turns)?;
        self.turns_logged = self.progress.turn_samples.len();
        Ok(())
    }

    /// Each agent's process id, if it has a process.
    pub(super) fn pids(&self) -> Vec<Option<u32>> {
        (0..self.scenario.agents.len())
            .map(|i| self.procs.pid(i))
            .collect()
    }

    /// Start every agent, then run every step of `centre_path`; a resumed run (its
    /// recorder rebuilt from the log) starts the agents alive at its last step and goes
    /// on from there, its course replayed through the steps logged.
    pub(super) fn drive(mut self, centre_path: &[Pose], started: Instant) -> anyhow::Result<()> {
        let n = self.scenario.agents.len();
        let resumed_at = self
            .options
            .resume
            .as_ref()
            .and_then(|_| self.recorder.steps().last())
            .map(|s| s.step);
        let (mut course, mut step) = match resumed_at {
            Some(last) => {
                let course = replay_course(self.scenario, centre_path, self.recorder.steps())
                    .map_err(|at| {
                        anyhow::anyhow!("the log does not replay: step {at}'s centre differs")
                    })?;
                // The turns of the steps before the kill count in the run's timing.
                if let Some(logged) = self.options.resume.as_deref() {
                    let before = logged.turns.iter().filter(|t| t.step <= last);
                    for t in before {
                        self.progress.latency_us.push(t.latency_us);
                        self.progress.compute_us.push(t.compute_us);
                    }
                }
                self.progress.steps_before = last;
                (course, last)
            }
            None => {
                self.log_step(None)?;
                (Course::new(self.scenario, centre_path), 0)
            }
        };
        let to_start: Vec<usize> = (0..n).filter(|&i| self.recorder.alive()[i]).collect();
        match self.early.take() {
            Some(mut early) => {
                // Started already, waiting for their channels, which exist now.
                early.gate.open();
                for (i, why) in early.failed {
                    self.on_failed_start(step, i, &why)?;
                }
                self.progress.startup_phases.spawn = early.spawn_s;
            }
            None => {
                let spawning = Instant::now();
                for &i in &to_start {
                    // A spawn that fails (the machine out of processes, say) fails that
                    // agent alone: it is frozen where it starts, or replaced with
                    // `--respawn`.
                    if let Err(e) = self.spawn(i, false) {
                        let why = format!("its process could not be started: {e:#}");
                        self.on_failed_start(step, i, &why)?;
                    }
                }
                self.progress.startup_phases.spawn = spawning.elapsed().as_secs_f64();
            }
        }
        self.start_agents(
            step,
            &to_start,
            self.options.startup_timeout_for(to_start.len()),
            false,
        )?;
        self.progress.startup_s = started.elapsed().as_secs_f64();
        self.progress.idle_cpu = self.options.idle_probe.map(|hold| {
            let pids: Vec<u32> = self.pids().into_iter().flatten().collect();
            IdleCpu::measure(&pids, hold)
        });
        self.progress.turn_samples.reserve(n * centre_path.len());

        let mut monitor =
            SafetyMonitor::new(self.scenario.field, &self.scenario.static_obstacles())
                .with_polygons(&self.scenario.polygons);
        let bar = progress_bar(
            centre_path.len().saturating_sub(1),
            &self.scenario.name,
            self.options.progress,
        );
        bar.set_position(step as u64);

        let stepping = Instant::now();
        // What the caller does between the steps (a benchmark's references) is not the
        // step loop's time.
        let mut between_s = 0.0;
        let mut between_ticks = (0, 0);
        let ticks_at_start = procfs::machine_cpu_ticks();
        'steps: while let Some(centre) =
            course.advance(step + 1, self.recorder.bodies(), self.recorder.alive())
        {
            step += 1;
            let centre = &centre;
            let ahead = course.ahead(MAX_HORIZON_STEPS).to_vec();
            self.begin_step(&mut monitor, step, centre);
            if bar.position() + 1 >= bar.length().unwrap_or(0) {
                // The course waited or was replanned: the path ahead is longer.
                bar.inc_length(1);
            }
            // Agents that died while waiting for their turn are noticed now.
            let checked = Instant::now();
            // One wait call tells whether any child has exited (or an agent has no
            // process any more); only then is each agent looked at (one call each).
            let any_exited = self.procs.any_child_exited()
                || (0..n).any(|a| self.recorder.alive()[a] && self.procs.pid(a).is_none());
            for agent in (0..n).filter(|_| any_exited) {
                if self.recorder.alive()[agent] && self.procs.poll(agent) == Exit::Exited {
                    // How it ended tells a crash (a signal) from an error (a code).
                    let how = match self.procs.exit_status(agent) {
                        Some(status) => format!("exited between turns ({status})"),
                        None => "exited between turns".to_string(),
                    };
                    self.on_death(step, agent, checked.elapsed(), &how)?;
                }
            }
            let groups = turn_groups_ordered(
                self.scenario.turns,
                self.scenario.turn_order,
                centre.heading_rad,
                &self.scenario.agents,
                self.recorder.bodies(),
                self.recorder.alive(),
            );
            self.recorder.note_groups(groups.len());
            for (k, group) in groups.iter().enumerate() {
                let next = self.hand_over.next_after(
                    &groups,
                    k,
                    self.scenario.turns,
                    self.recorder.alive(),
                );
                if self.take_group(&monitor, step, group, &next, centre, &ahead)? {
                    break 'steps;
                }
            }
            self.recorder.end_step(step);
            self.log_step(Some(&course))?;
            self.hand_over.end_step(self.ipc);
            bar.inc(1);
            // For whoever follows the run from outside (tests time their kills by it);
            // with a log, its thread tells each step once it is in the file.
            if self.log.is_none() {
                tell_step_done(step);
            }
            let pids = self.between_steps.is_some().then(|| self.pids());
            if let (Some(between_steps), Some(pids)) = (self.between_steps.as_mut(), pids) {
                let ticks_before = procfs::machine_cpu_ticks();
                let between = Instant::now();
                between_steps(BetweenSteps {
                    step,
                    prefix: self.ipc.prefix(),
                    ipc: self.ipc,
                    alive: self.recorder.alive(),
                    groups: &groups,
                    pids: &pids,
                })?;
                let ticks_after = procfs::machine_cpu_ticks();
                between_s += between.elapsed().as_secs_f64();
                if let Some((from, to)) = ticks_before.zip(ticks_after) {
                    between_ticks.0 += to.0.saturating_sub(from.0);
                    between_ticks.1 += to.1.saturating_sub(from.1);
                }
            }
            if self.ipc.termination_requested() {
                self.progress.interrupted = true;
                break;
            }
        }
        bar.finish_and_clear();
        self.recorder.note_course(&course);
        self.progress.gave_up = course.gave_up();
        self.progress.steps_s = stepping.elapsed().as_secs_f64() - between_s;
        self.progress.loop_idle_share = ticks_at_start
            .map(|(idle, total)| (idle + between_ticks.0, total + between_ticks.1))
            .zip(procfs::machine_cpu_ticks())
            .and_then(|(from, to)| procfs::idle_share(from, to));
        let pids: Vec<u32> = self.pids().into_iter().flatten().collect();
        let memory: Vec<procfs::Memory> = pids.iter().filter_map(|&p| procfs::memory(p)).collect();
        self.progress.rss_kib = memory.iter().map(|m| m.rss_kib).collect();
        self.progress.pss_kib = memory.iter().map(|m| m.pss_kib).collect();
        self.progress.cpu_s = pids.iter().filter_map(|&p| procfs::cpu_s(p)).collect();
        self.progress.completed = !self.progress.interrupted;
        Ok(())
    }

    /// Open `step`: the recorder and the monitor each move the moving obstacles and check
    /// their motion against the agents standing still; a strike the monitor sees is
    /// recorded as a fault of the agent struck (the recorder counts its own).
    fn begin_step(&mut self, monitor: &mut SafetyMonitor, step: usize, centre: &Pose) {
        self.recorder.begin_step(step, *centre);
        if self.scenario.moving.is_empty() {
            return;
        }
        let sweeps: Vec<(Vec<Point>, f64)> = self
            .scenario
            .moving
            .iter()
            .map(|m| (m.sweep(step), m.radius_m))
            .collect();
        // The recorder records each strike (as the reference does); the monitor's own
        // check, independent of it, must agree.
        let mut seen =
            monitor.move_obstacles(&sweeps, self.recorder.bodies(), self.recorder.alive());
        let mut recorded: Vec<(usize, usize)> = self
            .recorder
            .struck_now()
            .iter()
            .map(|&(m, a, _)| (m, a))
            .collect();
        seen.sort_unstable();
        recorded.sort_unstable();
        if seen != recorded {
            tracing::warn!(
                "step {step}: the monitor sees moving obstacles strike {seen:?}, the recorder {recorded:?}"
            );
        }
    }
}

/// Tell that `step` is done: the `step N done` line of [`PROGRESS_TARGET`] (not for step
/// 0, the start).
pub(super) fn tell_step_done(step: usize) {
    if step > 0 {
        tracing::info!(target: PROGRESS_TARGET, "step {step} done");
    }
}

/// The progress bar of a run of `steps` steps of scenario `name` (hidden unless
/// `enabled`; drawn only on a terminal).
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
