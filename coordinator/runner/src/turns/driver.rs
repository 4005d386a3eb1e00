//! A run over agent processes while it goes ([`Driver`]): it starts the agents, then
//! hands the steps to the step loop (`shared::run::step_loop::run_steps`, the reference
//! simulation's too) as its source of moves, the monitor as an extra judge. Its methods
//! are spread over `turns/` by concern: the run and its steps' edges here, a group's
//! turns in `turn.rs`, waiting for an answer in `answer.rs`, handshakes in `startup.rs`,
//! faults in `faults.rs` and `deaths.rs`, the monitor's judgement in `judge.rs`, what
//! follows each step in `step_report.rs`.

use std::ops::ControlFlow;
use std::time::Instant;

use shared::geometry::Pose;
use shared::run::record::{Recorder, replay_course};
use shared::run::step_loop::{GroupMoves, GroupTurn, MoveSource, run_steps};
use shared::world::course::Course;
use shared::world::scenario::Scenario;

use super::hand_over::HandOver;
use super::judge::MonitorJudge;
use super::lateness::TurnHistory;
use super::launch::AgentLaunch;
use super::options::RunOptions;
use super::outcome::Progress;
use super::run_handle::{EarlyStart, RunHandle};
use super::step_report::{BetweenStepsFn, StepReport, StepSeen};
use crate::agents::{AgentProcesses, Exit};
use crate::ipc::CoordinatorIpc;
use crate::monitor::SafetyMonitor;
use crate::procfs::{self, IdleCpu};
use crate::run_log::LogThread;

/// One run while it goes: the scenario and options, the ports and processes, the record
/// and what the step loop has measured.
pub(super) struct Driver<'a> {
    pub(super) scenario: &'a Scenario,
    pub(super) options: &'a RunOptions,
    pub(super) ipc: &'a mut CoordinatorIpc,
    pub(super) procs: &'a mut AgentProcesses,
    pub(super) progress: &'a mut Progress,
    /// How late every agent's last turns were.
    pub(super) history: TurnHistory,
    /// How a turn is handed over to the next agent.
    pub(super) hand_over: HandOver,
    /// Whether any agent has a sensing radius (then each world lists what it senses).
    pub(super) senses: bool,
    /// How an agent's process is started.
    pub(super) launch: &'a AgentLaunch,
    /// The agents already started, behind their gate (none over a network).
    pub(super) early: Option<EarlyStart>,
    /// What follows each step: the log, the progress bar, the caller's hook.
    pub(super) report: StepReport<'a>,
}

impl<'a> Driver<'a> {
    /// The run of `scenario` as `options` has it, over the resources of `handle`, its
    /// progress measured into `progress`, each step handed to `log` and then to
    /// `between_steps`, if given.
    pub(super) fn new(
        scenario: &'a Scenario,
        options: &'a RunOptions,
        handle: &'a mut RunHandle,
        progress: &'a mut Progress,
        log: Option<&'a mut LogThread>,
        between_steps: Option<&'a mut BetweenStepsFn<'_>>,
    ) -> Self {
        let n = scenario.agents.len();
        Self {
            scenario,
            options,
            ipc: &mut handle.ipc,
            procs: &mut handle.agents.procs,
            progress,
            history: TurnHistory::new(
                n,
                options.max_missed_turns as usize,
                options.late_window_turns as usize,
            ),
            hand_over: HandOver::new(options.wait.spins(), n),
            senses: scenario.agents.iter().any(|a| a.sensing_radius_m.is_some()),
            launch: &handle.launch,
            early: handle.early.take(),
            report: StepReport::new(log, between_steps),
        }
    }

    /// Start `agent`'s process on its open channel; a replacement never misbehaves.
    pub(super) fn spawn(&mut self, agent: usize, replacement: bool) -> anyhow::Result<()> {
        let generation = self.ipc.generation(agent).unwrap_or(0);
        let extra = self.launch.args(agent, replacement, generation);
        self.procs.spawn(agent, &extra)?;
        Ok(())
    }

    /// Each agent's process id, if it has a process.
    pub(super) fn pids(&self) -> Vec<Option<u32>> {
        (0..self.scenario.agents.len())
            .map(|i| self.procs.pid(i))
            .collect()
    }

    /// Start every agent, then run every step of `centre_path` in `recorder`; a resumed run
    /// (its world rebuilt from the log) starts the agents alive at its last step and goes
    /// on from there, its course replayed through the steps logged.
    pub(super) fn drive(
        mut self,
        recorder: &mut Recorder<'_>,
        centre_path: &[Pose],
        started: Instant,
    ) -> anyhow::Result<()> {
        let (mut course, step) = self.course_so_far(recorder, centre_path)?;
        self.start_all(recorder, step, started)?;
        self.progress
            .turn_samples
            .reserve(self.scenario.agents.len() * centre_path.len());
        let monitor = SafetyMonitor::new(self.scenario.field, &self.scenario.static_obstacles())
            .with_polygons(&self.scenario.polygons);
        self.report.show_progress(
            centre_path.len().saturating_sub(1),
            &self.scenario.name,
            self.options.progress,
            step,
        );

        let stepping = Instant::now();
        let ticks_at_start = procfs::machine_cpu_ticks();
        run_steps(
            &mut course,
            recorder,
            step,
            &mut self,
            &mut MonitorJudge { monitor },
        )?;
        // What the caller does between the steps (a benchmark's references) is not the
        // step loop's time.
        let (between_s, between_ticks) = self.report.finish();
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

    /// The centre's course and the last step taken: a new course at step 0 (logged), or
    /// a resumed run's course replayed through the steps of its log.
    fn course_so_far(
        &mut self,
        recorder: &Recorder<'_>,
        centre_path: &[Pose],
    ) -> anyhow::Result<(Course<'a>, usize)> {
        let resumed_at = self
            .options
            .resume
            .as_ref()
            .and_then(|_| recorder.steps().last())
            .map(|s| s.step);
        let Some(last) = resumed_at else {
            self.report
                .log_step(recorder, None, &self.progress.turn_samples)?;
            return Ok((Course::new(self.scenario, centre_path), 0));
        };
        let course = replay_course(self.scenario, centre_path, recorder.steps())
            .map_err(|at| anyhow::anyhow!("the log does not replay: step {at}'s centre differs"))?;
        // The turns of the steps before the kill count in the run's timing.
        if let Some(logged) = self.options.resume.as_deref() {
            for t in logged.turns.iter().filter(|t| t.step <= last) {
                self.progress.latency_us.push(t.latency_us);
                self.progress.compute_us.push(t.compute_us);
            }
        }
        self.progress.steps_before = last;
        Ok((course, last))
    }

    /// Start the process of every agent alive in `recorder` at `step` (or open the gate of
    /// those started early) and wait for their handshakes; `started` is when the run began.
    fn start_all(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        started: Instant,
    ) -> anyhow::Result<()> {
        let n = self.scenario.agents.len();
        let to_start: Vec<usize> = (0..n).filter(|&i| recorder.world().alive()[i]).collect();
        match self.early.take() {
            Some(mut early) => {
                // Started already, waiting for their channels, which exist now.
                early.gate.open();
                for (i, why) in early.failed {
                    self.on_failed_start(recorder, step, i, &why)?;
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
                        self.on_failed_start(recorder, step, i, &why)?;
                    }
                }
                self.progress.startup_phases.spawn = spawning.elapsed().as_secs_f64();
            }
        }
        let timeout = self.options.startup_timeout_for(to_start.len());
        self.start_agents(recorder, step, &to_start, timeout, false)?;
        self.progress.startup_s = started.elapsed().as_secs_f64();
        self.progress.idle_cpu = self.options.idle_probe.map(|hold| {
            let pids: Vec<u32> = self.pids().into_iter().flatten().collect();
            IdleCpu::measure(&pids, hold)
        });
        Ok(())
    }

    /// Notice the agents that died while waiting for their turn (at `step`, before its
    /// groups are formed).
    fn notice_deaths(&mut self, recorder: &mut Recorder<'_>, step: usize) -> anyhow::Result<()> {
        let n = self.scenario.agents.len();
        let checked = Instant::now();
        // One wait call tells whether any child has exited (or an agent has no process
        // any more); only then is each agent looked at (one call each).
        let any_exited = self.procs.any_child_exited()
            || (0..n).any(|a| recorder.world().alive()[a] && self.procs.pid(a).is_none());
        for agent in (0..n).filter(|_| any_exited) {
            if recorder.world().alive()[agent] && self.procs.poll(agent) == Exit::Exited {
                // How it ended tells a crash (a signal) from an error (a code).
                let how = match self.procs.exit_status(agent) {
                    Some(status) => format!("exited between turns ({status})"),
                    None => "exited between turns".to_string(),
                };
                self.on_death(recorder, step, agent, checked.elapsed(), &how)?;
            }
        }
        Ok(())
    }

    /// After `step` (recorded in `recorder`, its turns taken in `groups`): log it, hand
    /// the turns over to the next step, report it done; `Break` if the run was asked to
    /// stop.
    fn after_step(
        &mut self,
        recorder: &Recorder<'_>,
        step: usize,
        groups: &[Vec<usize>],
        course: &Course<'_>,
    ) -> anyhow::Result<ControlFlow<()>> {
        self.report
            .log_step(recorder, Some(course), &self.progress.turn_samples)?;
        self.hand_over.end_step(self.ipc);
        let pids = self.report.has_hook().then(|| self.pids());
        let seen = StepSeen {
            step,
            alive: recorder.world().alive(),
            groups,
            pids: pids.as_deref(),
        };
        self.report.step_done(&seen, self.ipc)?;
        if self.ipc.termination_requested() {
            self.progress.interrupted = true;
            return Ok(ControlFlow::Break(()));
        }
        Ok(ControlFlow::Continue(()))
    }
}

/// The agent processes as the step loop's source of moves.
impl MoveSource for Driver<'_> {
    type Error = anyhow::Error;

    fn open_step(&mut self, step: usize, recorder: &mut Recorder<'_>) -> anyhow::Result<()> {
        self.report.step_opened();
        self.notice_deaths(recorder, step)
    }

    fn take_group(
        &mut self,
        turn: &GroupTurn<'_>,
        recorder: &mut Recorder<'_>,
    ) -> anyhow::Result<GroupMoves> {
        Driver::take_group(self, recorder, turn)
    }

    fn close_step(
        &mut self,
        step: usize,
        groups: &[Vec<usize>],
        course: &Course<'_>,
        recorder: &Recorder<'_>,
    ) -> anyhow::Result<ControlFlow<()>> {
        self.after_step(recorder, step, groups, course)
    }
}
