//! One group's turns: every agent of the group granted its turn at once (each sees the
//! same snapshot, filtered to what it senses), the agent of the next group told it comes
//! next, then each answer collected in order and judged, and the group's moves settled
//! together.

use std::time::{Duration, Instant};

use shared::geometry::{Point, Pose};
use shared::record::FaultKind;
use shared::sensing::SensedAgents;
use shared::vocabulary::Move;
use shared::vocabulary::TurnMode;
use wire::{StateMsg, monotonic_ns};

use super::answer::{Answer, Turn};
use super::driver::Driver;
use super::judge::{Judging, judge_move, settle_group};
use super::lateness::Lateness;
use super::outcome::{GroupSample, TurnSample};
use crate::ipc::{TurnSplit, TurnWorld};
use crate::monitor::SafetyMonitor;

impl Driver<'_, '_> {
    /// Take the turns of `group` at `step`, the centre at `centre` with `ahead` its next
    /// poses along its plan, and tell the first live agent of `next` that its turn comes
    /// next; true if the run was interrupted.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn take_group(
        &mut self,
        monitor: &SafetyMonitor,
        step: usize,
        group: &[usize],
        next: &[usize],
        centre: &Pose,
        ahead: &[Pose],
    ) -> anyhow::Result<bool> {
        // The bodies where they stand, in a grid: for sensing, and for the monitor's
        // checks (no body moves before the group is settled). A lone agent without
        // sensing is checked against each body in turn: the grid would cost as much.
        let standing =
            (self.senses || group.len() > 1).then(|| SensedAgents::new(self.recorder.bodies()));
        let sensing = standing.as_ref().filter(|_| self.senses);
        self.kill_before_turns(step, group);
        let began = Instant::now();
        let turns = self.grant_group(step, group, centre, ahead, sensing)?;
        let size = turns.len();
        self.hand_over
            .tell_next(self.ipc, self.procs, self.recorder.alive(), group, next);
        // Agents moving at once are checked against each other in time, when the group
        // is settled: each move alone is checked against the bodies that stand.
        let passing: Vec<bool> = if self.scenario.turns == TurnMode::Simultaneous {
            self.recorder.alive().to_vec()
        } else {
            Vec::new()
        };
        let judging = Judging {
            passing: &passing,
            grid: standing.as_ref().map(SensedAgents::grid),
        };
        let Some(mut moves) = self.collect_group(monitor, step, turns, centre, judging)? else {
            self.progress.interrupted = true;
            return Ok(true);
        };
        if size > 0 {
            self.progress.groups.push(GroupSample {
                size,
                wall_us: began.elapsed().as_secs_f64() * 1e6,
            });
        }
        // A mate frozen after its move was judged does not move.
        moves.retain(|(agent, _)| self.recorder.alive()[*agent]);
        settle_group(monitor, self.recorder, step, moves, &passing);
        Ok(false)
    }

    /// Grant each live agent of `group` its turn, `sensing` telling what each senses
    /// (`None`: everything): whatever its channel holds is taken in
    /// first (none of it answers this turn), then its world is published and its turn
    /// rung, unless it polls its world ([`super::hand_over::HandOver::polls_world`]).
    fn grant_group(
        &mut self,
        step: usize,
        group: &[usize],
        centre: &Pose,
        ahead: &[Pose],
        sensing: Option<&SensedAgents>,
    ) -> anyhow::Result<Vec<Turn>> {
        let mut turns = Vec::with_capacity(group.len());
        // Agents moving at once know how every body moved over the last step.
        let velocities =
            (self.scenario.turns == TurnMode::Simultaneous).then(|| self.recorder.velocities());
        for &agent in group {
            self.drain(step, agent)?;
            if !self.recorder.alive()[agent] {
                continue;
            }
            let spec = &self.scenario.agents[agent];
            // Without sensing, every agent (no list built).
            let visible = sensing.map(|s| s.sensed_by(agent, spec));
            // Stamped before the world exists, so no answer to it can predate the stamp.
            let granted_at = Instant::now();
            let granted_ns = monotonic_ns();
            let world = TurnWorld {
                centre,
                heading_rad: self.recorder.headings()[agent],
                bodies: self.recorder.bodies(),
                alive: self.recorder.alive(),
                visible: visible.as_deref(),
                // As far as the agent looks ahead, and only with a top speed.
                ahead: match spec.max_step_m {
                    Some(_) => &ahead[..spec.horizon_steps.min(ahead.len())],
                    None => &[],
                },
                velocities: velocities.as_deref(),
            };
            let grant = self.ipc.publish_world(step, agent, &world)?;
            let rung = !self.hand_over.polls_world(agent, self.procs.pid(agent));
            if rung {
                self.ipc.notify_turn(agent)?;
            }
            if self.options.kills.contains(&(agent, step))
                && let Some(killed) = self.procs.signal_kill(agent)
            {
                self.recorder.note_fault(
                    step,
                    agent,
                    FaultKind::Killed,
                    format!("fault injection: SIGKILL to process {killed} during its turn"),
                    None,
                );
            }
            turns.push(Turn {
                agent,
                pid: self.procs.pid(agent),
                grant,
                granted_at,
                granted_ns,
                rung,
            });
        }
        Ok(turns)
    }

    /// Wait for the answer to each of `turns`, in order, and judge it alone, the agents
    /// `passing` marks taken as moving (simultaneous turns; none otherwise): the moves that
    /// passed the monitor on their own, or `None` if the run was interrupted.
    fn collect_group(
        &mut self,
        monitor: &SafetyMonitor,
        step: usize,
        turns: Vec<Turn>,
        centre: &Pose,
        judging: Judging<'_>,
    ) -> anyhow::Result<Option<Vec<(usize, Move)>>> {
        let mut moves = Vec::with_capacity(turns.len());
        for turn in turns {
            let agent = turn.agent;
            // Handled already while a group mate's answer was awaited (killed for
            // intruding, say, and maybe replaced): not this turn's agent any more.
            if !self.recorder.alive()[agent] || self.procs.pid(agent) != turn.pid {
                continue;
            }
            let slot = self.scenario.agents[agent].slot.ideal_position(centre);
            // How late an answer is, by this process's clock alone: from the grant, or
            // from when it began waiting for this agent if a group mate held it up
            // longer (the answer may have waited in its queue meanwhile: an agent is
            // never counted late for a mate's slowness).
            let waiting_from_ns = monotonic_ns().max(turn.granted_ns);
            match self.wait_answer(step, &turn)? {
                Answer::Move(msg) => {
                    let latency =
                        Duration::from_nanos(monotonic_ns().saturating_sub(waiting_from_ns));
                    if self.on_late_answer(step, agent, slot, latency)? {
                        continue;
                    }
                    if let Some(mv) = self.take_move(monitor, step, &turn, slot, *msg, judging) {
                        moves.push((agent, mv));
                    }
                }
                Answer::Malformed(why) => {
                    self.history.record(agent, Lateness::OnTime);
                    tracing::debug!("step {step}: agent {agent}'s answer refused: {why}");
                    self.recorder
                        .refuse(step, agent, slot, FaultKind::Malformed, why);
                }
                Answer::Dead(after) => {
                    self.on_death(step, agent, after, "died during its turn")?;
                }
                Answer::Missed => self.on_missed(step, agent, slot)?,
                Answer::Interrupted => return Ok(None),
            }
        }
        Ok(Some(moves))
    }

    /// Record the timing of the move `msg` that answered `turn`, and judge it with the
    /// monitor alone (against the bodies that stand: not those `passing` marks): the
    /// move if it passes.
    fn take_move(
        &mut self,
        monitor: &SafetyMonitor,
        step: usize,
        turn: &Turn,
        slot: Point,
        msg: StateMsg,
        judging: Judging<'_>,
    ) -> Option<Move> {
        let held_ns = monotonic_ns();
        let agent = turn.agent;
        let latency_ns = held_ns.saturating_sub(turn.granted_ns);
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
            split: TurnSplit::of(turn.granted_ns, &msg, held_ns),
            polled: !turn.rung,
        };
        self.progress.latency_us.push(sample.latency_us);
        self.progress.compute_us.push(sample.compute_us);
        self.progress.turn_samples.push(sample);
        judge_move(monitor, self.recorder, step, agent, slot, msg, judging)
    }
}
