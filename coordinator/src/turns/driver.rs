//! The step loop: every live agent takes its turn, one group at a time (one agent a group
//! in sequential mode); the answers are judged and checked before the recorder takes
//! them.

use std::time::{Duration, Instant};

use shared::course::Course;
use shared::geometry::{Point, Pose};
use shared::groups::turn_groups;
use shared::record::{FaultKind, Recorder};
use shared::scenario::Scenario;
use shared::sensing::SensedAgents;
use shared::vocabulary::TurnMode;
use wire::{MalformedState, PREPARED_GRANT_WINDOW, StateKind, StateMsg, monotonic_ns};

use super::judge::{Judged, judge_answer, judge_move, settle_group};
use super::{
    BetweenSteps, LIVENESS_SLICE, Progress, RunOptions, SPIN_BUDGET, TurnSample, progress_bar,
};
use crate::agents::{AgentProcesses, Exit};
use crate::ipc::{CoordinatorIpc, Grant, Incoming, TurnSplit};
use crate::monitor::SafetyMonitor;
use crate::procfs::{self, IdleCpu};

/// How many agents of the next group are told their turn comes next (`--wait spin`).
/// Each polls its world on a core of its own while the group before computes, so more
/// pollers take cores from the group: measured on 2 vCPUs with `coordinator bench
/// --loop-scenario scenarios/swarm200-parallel.toml` (parallel turns), the step loop
/// took 2.48-2.66 s telling the whole next group, 1.66-1.74 s telling one agent, and
/// 1.71-2.14 s sleeping (`--wait block`). With sequential turns a group is one agent.
const PREPARED_AT_MOST: usize = 1;

/// The `tracing` target of the line logged when a step is done (`step N done`):
/// `RUST_LOG=coordinator::progress=info` shows one such line per step on stderr.
pub const PROGRESS_TARGET: &str = "coordinator::progress";

/// What the coordinator learned while waiting for a move.
pub(super) enum Answer {
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

/// One run while it goes: the scenario and options, the ports and processes, the record
/// and what the step loop has measured. Its methods are spread over `turns/` by concern:
/// the step loop here, handshakes in `startup.rs`, faults in `faults.rs`.
pub(super) struct Driver<'a, 's> {
    pub(super) scenario: &'a Scenario,
    pub(super) options: &'a RunOptions,
    pub(super) ipc: &'a mut CoordinatorIpc,
    pub(super) procs: &'a mut AgentProcesses,
    pub(super) recorder: &'a mut Recorder<'s>,
    pub(super) progress: &'a mut Progress,
    /// Consecutive missed turns per agent.
    pub(super) missed: Vec<u32>,
    /// When each agent was last told its turn comes next, and its process then
    /// (`--wait spin`): its turn is granted without a ring if it comes soon enough.
    pub(super) prepared: Vec<Option<(Instant, Option<u32>)>>,
    /// Spin rather than sleep while a turn is short ([`super::WaitMode`]).
    pub(super) spin: bool,
    /// Whether any agent has a sensing radius (then each world lists what it senses).
    pub(super) senses: bool,
    /// Called after every step.
    pub(super) between_steps: &'a mut dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()>,
}

impl Driver<'_, '_> {
    /// Start `agent`'s process on its open channel; a replacement never misbehaves.
    pub(super) fn spawn(&mut self, agent: usize, replacement: bool) -> anyhow::Result<()> {
        let generation = self.ipc.generation(agent).unwrap_or(0);
        let mut extra = vec!["--generation".to_string(), generation.to_string()];
        if !replacement
            && let Some((_, mode)) = self.options.misbehave.iter().find(|(a, _)| *a == agent)
        {
            extra.extend(["--misbehave".to_string(), mode.to_string()]);
        }
        if let Some(network) = &self.options.network {
            extra.extend(network.relay_args(agent));
        }
        self.procs.spawn(agent, &extra)?;
        Ok(())
    }

    /// Each agent's process id, if it has a process.
    pub(super) fn pids(&self) -> Vec<Option<u32>> {
        (0..self.scenario.agents.len())
            .map(|i| self.procs.pid(i))
            .collect()
    }

    /// Start every agent, then run every step of `centre_path`.
    pub(super) fn drive(mut self, centre_path: &[Pose], started: Instant) -> anyhow::Result<()> {
        let n = self.scenario.agents.len();
        for i in 0..n {
            self.spawn(i, false)?;
        }
        let all: Vec<usize> = (0..n).collect();
        self.start_agents(0, &all, self.options.startup_timeout_for(n), false)?;
        self.progress.startup_s = started.elapsed().as_secs_f64();
        self.progress.idle_cpu = self.options.idle_probe.map(|hold| {
            let pids: Vec<u32> = self.pids().into_iter().flatten().collect();
            IdleCpu::measure(&pids, hold)
        });
        self.progress.turn_samples.reserve(n * centre_path.len());

        let mut monitor =
            SafetyMonitor::new(self.scenario.field, &self.scenario.static_obstacles());
        let bar = progress_bar(
            centre_path.len().saturating_sub(1),
            &self.scenario.name,
            self.options.progress,
        );

        let stepping = Instant::now();
        let mut course = Course::new(self.scenario, centre_path);
        let mut step = 0;
        'steps: while let Some(centre) =
            course.advance(step + 1, self.recorder.bodies(), self.recorder.alive())
        {
            step += 1;
            let centre = &centre;
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
                    self.on_death(step, agent, checked.elapsed(), "exited between turns")?;
                }
            }
            let groups = turn_groups(
                self.scenario.turns,
                &self.scenario.agents,
                self.recorder.bodies(),
                self.recorder.alive(),
            );
            self.recorder.note_groups(groups.len());
            for (k, group) in groups.iter().enumerate() {
                // Who comes next, told ahead when spinning: the next group of the step,
                // or after the last one, the first live agent (next step's first turn
                // in sequential mode).
                let first;
                let next: &[usize] = match groups.get(k + 1) {
                    Some(g) => g,
                    None if self.spin && self.scenario.turns == TurnMode::Sequential => {
                        first = self.recorder.alive().iter().position(|a| *a);
                        first.as_slice()
                    }
                    None => &[],
                };
                if self.take_group(&monitor, step, group, next, centre)? {
                    break 'steps;
                }
            }
            self.recorder.end_step(step);
            if self.spin {
                // Once a step, not once a group: iceoryx2 sends one datagram per ring
                // only while the listener has been drained since, so rings left pending
                // cost neither the agents a send nor this process a receive per turn.
                self.ipc.drain_done();
            }
            bar.inc(1);
            // For whoever follows the run from outside (tests time their kills by it).
            tracing::info!(target: PROGRESS_TARGET, "step {step} done");
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
        self.recorder.note_course(&course);
        self.progress.gave_up = course.gave_up();
        self.progress.steps_s = stepping.elapsed().as_secs_f64();
        self.progress.rss_kib = self
            .pids()
            .into_iter()
            .flatten()
            .filter_map(procfs::rss_kib)
            .collect();
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

    /// Grant every agent of `group` its turn at `step` at once (each sees the same
    /// snapshot, filtered to what it senses), then take their answers in order and judge
    /// them; true if the run was interrupted.
    pub(super) fn take_group(
        &mut self,
        monitor: &SafetyMonitor,
        step: usize,
        group: &[usize],
        next: &[usize],
        centre: &Pose,
    ) -> anyhow::Result<bool> {
        let sensing = self
            .senses
            .then(|| SensedAgents::new(self.recorder.bodies()));
        self.kill_before_turns(step, group);
        let mut granted = Vec::with_capacity(group.len());
        for &agent in group {
            // Nothing that arrived since the agent's last turn answers this one.
            self.drain(step, agent)?;
            if !self.recorder.alive()[agent] {
                continue;
            }
            let spec = &self.scenario.agents[agent];
            // Without sensing, every agent (no list built).
            let visible = sensing.as_ref().map(|s| s.sensed_by(agent, spec));
            // Stamped before the world exists, so no answer to it can predate the stamp.
            let at = Instant::now();
            let at_ns = monotonic_ns();
            let grant = self.ipc.publish_world(
                step,
                agent,
                centre,
                self.recorder.bodies(),
                self.recorder.alive(),
                visible.as_deref(),
            )?;
            // An agent told it is next polls its world: publishing it is the grant.
            let rung = !self.polls_world(agent);
            if rung {
                self.ipc.notify_turn(agent)?;
            }
            if self.options.kills.contains(&(agent, step))
                && let Some(pid) = self.procs.signal_kill(agent)
            {
                self.recorder.note_fault(
                    step,
                    agent,
                    FaultKind::Killed,
                    format!("fault injection: SIGKILL to process {pid} during its turn"),
                    None,
                );
            }
            granted.push((agent, self.procs.pid(agent), grant, at, at_ns, rung));
        }
        if self.spin {
            // The next group's first live agent polls its world while this group
            // computes; one only: every poller takes a core from the group
            // ([`PREPARED_AT_MOST`]).
            let ahead = next
                .iter()
                .copied()
                .filter(|&a| self.recorder.alive()[a] && !group.contains(&a))
                .take(PREPARED_AT_MOST);
            for agent in ahead {
                if self.ipc.notify_prepare(agent).is_ok() {
                    self.prepared[agent] = Some((Instant::now(), self.procs.pid(agent)));
                }
            }
        }
        let mut moves = Vec::with_capacity(granted.len());
        for (agent, pid, grant, at, at_ns, rung) in granted {
            // Handled already while a group mate's answer was awaited (killed for
            // intruding, say, and maybe replaced): not this turn's agent any more.
            if !self.recorder.alive()[agent] || self.procs.pid(agent) != pid {
                continue;
            }
            let slot = self.scenario.agents[agent].slot.ideal_position(centre);
            match self.wait_answer(step, agent, grant, at, rung)? {
                Answer::Move(msg) => {
                    let held_ns = monotonic_ns();
                    self.missed[agent] = 0;
                    let latency_ns = held_ns.saturating_sub(at_ns);
                    if msg.compute_ns > latency_ns {
                        self.recorder.note_fault(
                            step,
                            agent,
                            FaultKind::Malformed,
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
                        split: TurnSplit::of(at_ns, &msg, held_ns),
                        polled: !rung,
                    };
                    self.progress.latency_us.push(sample.latency_us);
                    self.progress.compute_us.push(sample.compute_us);
                    self.progress.turn_samples.push(sample);
                    if let Some(mv) = judge_move(monitor, self.recorder, step, agent, slot, *msg) {
                        moves.push((agent, mv));
                    }
                }
                Answer::Malformed(why) => {
                    self.missed[agent] = 0;
                    tracing::debug!("step {step}: agent {agent}'s answer refused: {why}");
                    self.recorder
                        .refuse(step, agent, slot, FaultKind::Malformed, why);
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
        }
        // A mate frozen after its move was judged does not move.
        moves.retain(|(agent, _)| self.recorder.alive()[*agent]);
        settle_group(self.recorder, step, moves);
        Ok(false)
    }

    /// The next sample on `agent`'s channel published by the agent's own process (or one
    /// that could not be received at all); samples of any other process are recorded
    /// as `impersonation` on the way and dropped.
    pub(super) fn receive_own(
        &mut self,
        step: usize,
        agent: usize,
    ) -> anyhow::Result<Option<Incoming>> {
        let pid = self.procs.pid(agent);
        while let Some(incoming) = self.ipc.receive(agent) {
            match incoming.publisher_pid {
                Some(from) if Some(from) != pid => self.on_impersonation(step, agent, from)?,
                _ => return Ok(Some(incoming)),
            }
        }
        Ok(None)
    }

    /// Take in whatever `agent`'s channel holds between turns: none of it answers a
    /// turn. Recorded, never used.
    pub(super) fn drain(&mut self, step: usize, agent: usize) -> anyhow::Result<()> {
        let (mut extra, mut malformed) = (0usize, Vec::new());
        while let Some(incoming) = self.receive_own(step, agent)? {
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
                FaultKind::Unsolicited,
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
                FaultKind::Malformed,
                format!(
                    "{} sample(s) between turns failed the checks, first: {first}",
                    malformed.len()
                ),
                None,
            );
        }
        Ok(())
    }

    /// Whether `agent`'s process was told its turn comes next so lately that it is still
    /// polling its world ([`PREPARED_GRANT_WINDOW`]); the mark is used up.
    fn polls_world(&mut self, agent: usize) -> bool {
        let pid = self.procs.pid(agent);
        self.prepared
            .get_mut(agent)
            .and_then(Option::take)
            .is_some_and(|(at, told)| told == pid && at.elapsed() < PREPARED_GRANT_WINDOW)
    }

    /// Wait for `agent`'s answer to `grant`, checking its process every slice. `rung`:
    /// whether its turn was rung; if not (it was polling its world), it is rung once the
    /// spin budget is spent, in case the agent stopped polling before the world came.
    pub(super) fn wait_answer(
        &mut self,
        step: usize,
        agent: usize,
        grant: Grant,
        granted: Instant,
        mut rung: bool,
    ) -> anyhow::Result<Answer> {
        let deadline = granted + self.options.turn_deadline;
        let pid = self.procs.pid(agent);
        let mut unsolicited = 0usize;
        let answer = loop {
            let mut found = None;
            while let Some(incoming) = self.receive_own(step, agent)? {
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
            // Spinning: look again at once (yielding the core to whoever needs it) until
            // the budget is spent, then wait as usual; liveness is looked at then.
            if self.spin && granted.elapsed() < SPIN_BUDGET {
                std::thread::yield_now();
                continue;
            }
            if !rung {
                rung = true;
                // A ring that fails changes nothing: the agent's process is looked at next.
                if let Err(e) = self.ipc.notify_turn(agent) {
                    tracing::debug!("step {step}: ringing agent {agent}'s turn late: {e:#}");
                }
                continue;
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
                FaultKind::Unsolicited,
                format!(
                    "{unsolicited} state(s) during the turn carried no valid token for it (replayed or guessed); ignored"
                ),
                None,
            );
        }
        Ok(answer)
    }
}
