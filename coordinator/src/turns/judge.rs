//! Judging a sample during a turn, and a move's safety.

use shared::geometry::Point;
use shared::record::Recorder;
use shared::vocabulary::{MAX_WAYPOINTS, Move, MoveStatus};
use wire::{StateKind, StateMsg};

use super::driver::Answer;
use crate::ipc::{Grant, Incoming};
use crate::monitor::SafetyMonitor;

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

/// Check a published move with the monitor (parry) and the recorder (plain geometry):
/// both must accept it.
pub(super) fn accept_or_reject(
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
