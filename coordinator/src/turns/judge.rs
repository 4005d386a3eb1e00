//! Judging a sample during a turn, and a move's safety.

use shared::geometry::Point;
use shared::record::{FaultKind, Recorder};
use shared::safety::SAFETY_TOLERANCE_M;
use shared::vocabulary::{MAX_WAYPOINTS, Move, MoveStatus};
use wire::{StateKind, StateMsg};

use super::driver::Answer;
use crate::ipc::{Grant, Incoming};
use crate::monitor::{self, Refusal, SafetyMonitor};

/// What a sample from the agent's own process means during its turn.
pub(super) enum Judged {
    /// It ends the turn.
    Answer(Answer),
    /// It answers no turn (a replay, a guess, a handshake): counted, ignored.
    Unsolicited,
    /// A late echo: no fault.
    Ignore,
}

/// Judge `incoming` during the turn of `grant` at `step`, from the agent's process `pid`.
pub(super) fn judge_answer(
    incoming: Incoming,
    grant: Grant,
    step: usize,
    pid: Option<u32>,
) -> Judged {
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

/// Check a published move with the monitor (parry) alone, against the bodies where they
/// stand: the move if it passes, else `None` with the refusal recorded (the agent stays).
/// The recorder's own checks come when the group is settled ([`settle_group`]).
pub(super) fn judge_move(
    monitor: &SafetyMonitor,
    recorder: &mut Recorder,
    step: usize,
    agent: usize,
    slot: Point,
    msg: StateMsg,
) -> Option<Move> {
    let from = recorder.bodies()[agent].position;
    let max_step_m = recorder.scenario().agents[agent].max_step_m;
    let verdict = match msg.move_status() {
        None => Err(format!("unknown move status code {}", msg.status)),
        Some(status) if !status.set_by_agent() => {
            Err(format!("an agent may not report status {}", status.name()))
        }
        Some(status) => monitor
            .check(
                agent,
                &from,
                &msg.waypoints,
                &msg.best,
                status == MoveStatus::UnderWay,
                recorder.bodies(),
                MAX_WAYPOINTS,
            )
            .and_then(|()| monitor::check_length(&msg.waypoints, max_step_m))
            .map(|()| status)
            .map_err(|r| r.to_string()),
    };
    match verdict {
        Ok(status) => Some(Move {
            slot: msg.slot,
            best: msg.best,
            status,
            waypoints: msg.waypoints,
        }),
        Err(why) => {
            tracing::debug!("step {step}: agent {agent}'s move rejected by the monitor: {why}");
            recorder.refuse(step, agent, slot, FaultKind::Rejected, why);
            None
        }
    }
}

/// Take the moves of one group that passed [`judge_move`]: the monitor checks every pair
/// against each other's whole move (both refused if they meet), then the recorder checks
/// and takes what is left.
pub(super) fn settle_group(recorder: &mut Recorder, step: usize, moves: Vec<(usize, Move)>) {
    let radius = |a: usize| recorder.bodies()[a].radius_m;
    // Every point of a move lies within its length of its start: far-apart pairs need
    // no segment query.
    let lengths_m: Vec<f64> = moves
        .iter()
        .map(|(_, mv)| {
            mv.waypoints
                .windows(2)
                .map(|w| nalgebra::distance(&w[0], &w[1]))
                .sum()
        })
        .collect();
    let mut meets: Vec<Option<(usize, f64)>> = vec![None; moves.len()];
    for i in 0..moves.len() {
        for j in 0..i {
            let ((a, ma), (b, mb)) = (&moves[i], &moves[j]);
            let reach_m = lengths_m[i] + lengths_m[j] + radius(*a) + radius(*b);
            if nalgebra::distance(&ma.waypoints[0], &mb.waypoints[0]) > reach_m {
                continue;
            }
            let distance_m = monitor::distance_between_moves_m(&ma.waypoints, &mb.waypoints);
            if distance_m < radius(*a) + radius(*b) - SAFETY_TOLERANCE_M {
                meets[i] = Some((*b, distance_m));
                meets[j] = Some((*a, distance_m));
            }
        }
    }
    let mut kept = Vec::with_capacity(moves.len());
    for ((agent, mv), meet) in moves.into_iter().zip(meets) {
        match meet {
            None => kept.push((agent, mv)),
            Some((other, distance_m)) => {
                let why = Refusal::GroupMate {
                    agent: other,
                    distance_m,
                }
                .to_string();
                tracing::debug!("step {step}: agent {agent}'s move rejected by the monitor: {why}");
                recorder.refuse(step, agent, mv.slot, FaultKind::Rejected, why);
            }
        }
    }
    let agents: Vec<usize> = kept.iter().map(|(a, _)| *a).collect();
    for (agent, verdict) in agents.into_iter().zip(recorder.submit_group(step, kept)) {
        if let Err(v) = verdict {
            tracing::debug!("step {step}: agent {agent}'s move rejected: {v}");
        }
    }
}
