//! One group's turns over agent processes: every agent of the group granted its turn at
//! once (each sees the same snapshot, filtered to what it senses), the agent of the next
//! group told it comes next, then each answer collected in order (the step loop,
//! `shared::run::step_loop`, has the group's moves judged and taken).

use std::time::{Duration, Instant};

use shared::control::vocabulary::Move;
use shared::geometry::{Point, Pose};
use shared::run::record::{FaultKind, Recorder};
use shared::run::step_loop::{GroupMoves, GroupTurn};
use shared::world::sensing::SensedAgents;
use wire::{StateMsg, monotonic_ns};

use super::answer::{Answer, Turn};
use super::driver::Driver;
use super::lateness::Lateness;
use super::outcome::{GroupSample, TurnSample};
use crate::ipc::{TurnSplit, TurnWorld};

impl Driver<'_> {
    /// Take the turns of `turn`'s group in `recorder`, and tell the first live agent of the
    /// next group that its turn comes next: the moves that came back well formed (the
    /// step loop has them judged), unless the run was interrupted.
    pub(super) fn take_group(
        &mut self,
        recorder: &mut Recorder<'_>,
        turn: &GroupTurn<'_>,
    ) -> anyhow::Result<GroupMoves> {
        let (step, group) = (turn.step, turn.agents());
        let next = self.hand_over.next_after(
            turn.groups,
            turn.index,
            self.scenario.turns,
            recorder.world().alive(),
        );
        self.kill_before_turns(recorder, step, group);
        let began = Instant::now();
        let turns = self.grant_group(recorder, turn)?;
        let size = turns.len();
        self.hand_over
            .tell_next(self.ipc, self.procs, recorder.world().alive(), group, &next);
        let Some(moves) = self.collect_group(recorder, step, turns, turn.centre)? else {
            self.progress.interrupted = true;
            return Ok(GroupMoves::Interrupted);
        };
        if size > 0 {
            self.progress.groups.push(GroupSample {
                size,
                wall_us: began.elapsed().as_secs_f64() * 1e6,
            });
        }
        Ok(GroupMoves::Taken(moves))
    }

    /// Grant each live agent of `turn`'s group its turn: whatever its channel holds is
    /// taken in first (none of it answers this turn), then its world (what it senses of
    /// `recorder`) is published and its turn rung, unless it polls its world
    /// ([`super::hand_over::HandOver::polls_world`]).
    fn grant_group(
        &mut self,
        recorder: &mut Recorder<'_>,
        turn: &GroupTurn<'_>,
    ) -> anyhow::Result<Vec<Turn>> {
        let (step, group, ahead) = (turn.step, turn.agents(), turn.ahead);
        // The bodies where they stand, in a grid, for sensing (no body moves before the
        // group is settled).
        let sensing = self
            .senses
            .then(|| SensedAgents::new(recorder.world().bodies()));
        let mut turns = Vec::with_capacity(group.len());
        for &agent in group {
            self.drain(recorder, step, agent)?;
            if !recorder.world().alive()[agent] {
                continue;
            }
            let spec = &self.scenario.agents[agent];
            // Without sensing, every agent (no list built).
            let visible = sensing.as_ref().map(|s| s.sensed_by(agent, spec));
            // Stamped before the world exists, so no answer to it can predate the stamp.
            let granted_at = Instant::now();
            let granted_ns = monotonic_ns();
            let view = TurnWorld {
                centre: turn.centre,
                heading_rad: recorder.world().headings()[agent],
                bodies: recorder.world().bodies(),
                alive: recorder.world().alive(),
                visible: visible.as_deref(),
                // As far as the agent looks ahead, and only with a top speed.
                ahead: match spec.max_step_m {
                    Some(_) => &ahead[..spec.horizon_steps.min(ahead.len())],
                    None => &[],
                },
                velocities: turn.velocities,
            };
            let grant = self.ipc.publish_world(step, agent, &view)?;
            let rung = !self.hand_over.polls_world(agent, self.procs.pid(agent));
            if rung {
                self.ipc.notify_turn(agent)?;
            }
            if self.options.faults.kills_during_turn(agent, step)
                && let Some(killed) = self.procs.signal_kill(agent)
            {
                recorder.note_fault(
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

    /// Wait for the answer to each of `turns`, in order: the moves that came back well
    /// formed, or `None` if the run was interrupted.
    fn collect_group(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        turns: Vec<Turn>,
        centre: &Pose,
    ) -> anyhow::Result<Option<Vec<(usize, Move)>>> {
        let mut moves = Vec::with_capacity(turns.len());
        for turn in turns {
            let agent = turn.agent;
            // Handled already while a group mate's answer was awaited (killed for
            // intruding, say, and maybe replaced): not this turn's agent any more.
            if !recorder.world().alive()[agent] || self.procs.pid(agent) != turn.pid {
                continue;
            }
            let slot = self.scenario.agents[agent].slot.ideal_position(centre);
            // How late an answer is, by this process's clock alone: from the grant, or
            // from when it began waiting for this agent if a group mate held it up
            // longer (the answer may have waited in its queue meanwhile: an agent is
            // never counted late for a mate's slowness).
            let waiting_from_ns = monotonic_ns().max(turn.granted_ns);
            match self.wait_answer(recorder, step, &turn)? {
                Answer::Move(msg) => {
                    let latency =
                        Duration::from_nanos(monotonic_ns().saturating_sub(waiting_from_ns));
                    if self.on_late_answer(recorder, step, agent, slot, latency)? {
                        continue;
                    }
                    if let Some(mv) = self.take_move(recorder, step, &turn, slot, *msg) {
                        moves.push((agent, mv));
                    }
                }
                Answer::Malformed(why) => {
                    self.history.record(agent, Lateness::OnTime);
                    tracing::debug!("step {step}: agent {agent}'s answer refused: {why}");
                    recorder.refuse(step, agent, slot, FaultKind::Malformed, why);
                }
                Answer::Dead(after) => {
                    self.on_death(recorder, step, agent, after, "died during its turn")?;
                }
                Answer::Missed => self.on_missed(recorder, step, agent, slot)?,
                Answer::Interrupted => return Ok(None),
            }
        }
        Ok(Some(moves))
    }

    /// Record the timing of the move `msg` that answered `turn`: the move if its status
    /// is one an agent may report (else it is refused, the agent staying).
    fn take_move(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        turn: &Turn,
        slot: Point,
        msg: StateMsg,
    ) -> Option<Move> {
        let held_ns = monotonic_ns();
        let agent = turn.agent;
        let latency_ns = held_ns.saturating_sub(turn.granted_ns);
        if msg.compute_ns > latency_ns {
            recorder.note_fault(
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
        match move_of(msg) {
            Ok(mv) => Some(mv),
            Err(why) => {
                tracing::debug!("step {step}: agent {agent}'s move rejected: {why}");
                recorder.refuse(step, agent, slot, FaultKind::Rejected, why);
                None
            }
        }
    }
}

/// The move `msg` carries, if its status is one an agent may report.
fn move_of(msg: StateMsg) -> Result<Move, String> {
    match msg.move_status() {
        None => Err(format!("unknown move status code {}", msg.status)),
        Some(status) if !status.set_by_agent() => {
            Err(format!("an agent may not report status {}", status.name()))
        }
        Some(status) => Ok(Move {
            end_heading_rad: msg.end_heading_rad,
            slot: msg.slot,
            best: msg.best,
            status,
            waypoints: msg.waypoints,
        }),
    }
}
