//! Judging a move's safety: each move alone with the monitor (parry), then a group's
//! moves against each other, then the recorder's own checks (plain geometry).

use shared::geometry::Point;
use shared::groups::{GroupMove, group_meetings};
use shared::record::{FaultKind, Recorder};
use shared::vocabulary::{MAX_WAYPOINTS, Move, MoveStatus, TurnMode};
use wire::StateMsg;

use crate::monitor::{self, Refusal, SafetyMonitor};

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
        Some(status) => monitor::check_kinematics(
            recorder.scenario().agents[agent].kinematics,
            recorder.headings()[agent],
            &msg.waypoints,
            msg.end_heading_rad,
            max_step_m,
        )
        .and_then(|chord_errors_m| {
            monitor.check(
                agent,
                &from,
                &msg.waypoints,
                &msg.best,
                status == MoveStatus::UnderWay,
                recorder.bodies(),
                &chord_errors_m,
                MAX_WAYPOINTS,
            )
        })
        .and_then(|()| monitor::check_length(&msg.waypoints, max_step_m))
        .map(|()| status)
        .map_err(|r| r.to_string()),
    };
    match verdict {
        Ok(status) => Some(Move {
            end_heading_rad: msg.end_heading_rad,
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
/// against each other's whole move (both refused if they meet; in `simultaneous` turns,
/// where every agent moves at once at a constant speed, if they meet at the same time),
/// then the recorder checks and takes what is left.
pub(super) fn settle_group(recorder: &mut Recorder, step: usize, moves: Vec<(usize, Move)>) {
    let group: Vec<GroupMove<'_>> = moves
        .iter()
        .map(|(agent, mv)| GroupMove {
            radius_m: recorder.bodies()[*agent].radius_m,
            waypoints: &mv.waypoints,
            refused: false,
        })
        .collect();
    // Moves made at once at constant speeds (ORCA's own model) meet only if the agents
    // are close at the same time; a parallel group's timing is not known: anywhere.
    let meetings = if recorder.scenario().turns == TurnMode::Simultaneous {
        group_meetings(&group, monitor::distance_between_simultaneous_moves_m)
    } else {
        group_meetings(&group, monitor::distance_between_moves_m)
    };
    let mates: Vec<usize> = moves.iter().map(|(agent, _)| *agent).collect();
    let mut kept = Vec::with_capacity(moves.len());
    for ((agent, mv), meeting) in moves.into_iter().zip(meetings) {
        match meeting {
            None => kept.push((agent, mv)),
            Some(m) => {
                let why = Refusal::GroupMate {
                    agent: mates[m.mate],
                    distance_m: m.distance_m,
                    reach_m: m.reach_m,
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
