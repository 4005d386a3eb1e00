//! Judging a move's safety: each move alone with the monitor (parry), then a group's
//! moves against each other, then the recorder's own checks (plain geometry).

use shared::geometry::{DiskGrid, Point};
use shared::groups::{GroupMove, Meeting, group_meetings, simultaneous_meetings};
use shared::record::{FaultKind, Recorder};
use shared::vocabulary::{Body, MAX_WAYPOINTS, Move, MoveStatus, TurnMode};
use wire::StateMsg;

use crate::monitor::{self, MoveUnderCheck, Refusal, SafetyMonitor, Standing};

/// What the moves of one group are judged against, besides the bodies where they stand.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Judging<'a> {
    /// The agents taken as moving at the same time (`simultaneous` turns: the group's
    /// agents; empty otherwise).
    pub(super) passing: &'a [bool],
    /// A grid over the bodies where they stand, built when the group's turns were
    /// granted (no body moves before the group is settled); `None`: none was built.
    pub(super) grid: Option<&'a DiskGrid>,
}

/// Check a published move with the monitor (parry) alone, against the bodies where they
/// stand (but those `judging.passing` marks: in `simultaneous` turns, the group's agents,
/// which move at the same time): the move if it passes, else `None` with the refusal recorded
/// (the agent stays). The moves against each other, and the recorder's own checks, come
/// when the group is settled ([`settle_group`]).
pub(super) fn judge_move(
    monitor: &SafetyMonitor,
    recorder: &mut Recorder,
    step: usize,
    agent: usize,
    slot: Point,
    msg: StateMsg,
    judging: Judging<'_>,
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
            let mv = MoveUnderCheck {
                agent,
                from: &from,
                waypoints: &msg.waypoints,
                best: &msg.best,
                under_way: status == MoveStatus::UnderWay,
                chord_errors_m: &chord_errors_m,
            };
            let standing = Standing {
                bodies: recorder.bodies(),
                passing: judging.passing,
                grid: judging.grid,
            };
            monitor.check(&mv, &standing, MAX_WAYPOINTS)
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
/// against each other's whole move (both refused if they meet), then the recorder checks
/// and takes what is left.
///
/// In `simultaneous` turns, where every agent moves at once at a constant speed, two
/// moves meet if they come close at the same time, and each move is also checked
/// against every body that does not move this step (a mate whose answer was refused or
/// missing stands where it is), again after each refusal
/// ([`shared::groups::simultaneous_meetings`]). `judged_passing` are the agents taken as
/// moving when each move was judged alone ([`judge_move`]).
pub(super) fn settle_group(
    monitor: &SafetyMonitor,
    recorder: &mut Recorder,
    step: usize,
    moves: Vec<(usize, Move)>,
    judged_passing: &[bool],
) {
    let simultaneous = recorder.scenario().turns == TurnMode::Simultaneous;
    // Moving at once, a move was judged alone against the bodies of the agents not
    // alive when the answers began to be collected. One that died since stands frozen:
    // each move is judged alone against it now, as the reference judges a move alone
    // against an agent frozen before the turns (a live mate whose move is refused, or
    // who gave none, stands too: the rounds below look at it, as the reference does).
    // If none died, each move was judged alone against these very bodies already.
    let moves = if simultaneous && recorder.alive() != judged_passing {
        let movers = recorder.alive().to_vec();
        let mut kept = Vec::with_capacity(moves.len());
        for (agent, mv) in moves {
            let under_check = MoveUnderCheck {
                agent,
                from: &recorder.bodies()[agent].position,
                waypoints: &mv.waypoints,
                best: &mv.best,
                under_way: mv.status == MoveStatus::UnderWay,
                chord_errors_m: &[],
            };
            let standing = Standing {
                bodies: recorder.bodies(),
                passing: &movers,
                grid: None,
            };
            let verdict = monitor.check(&under_check, &standing, MAX_WAYPOINTS);
            match verdict {
                Ok(()) => kept.push((agent, mv)),
                Err(r) => {
                    let why = r.to_string();
                    tracing::debug!(
                        "step {step}: agent {agent}'s move rejected by the monitor: {why}"
                    );
                    recorder.refuse(step, agent, mv.slot, FaultKind::Rejected, why);
                }
            }
        }
        kept
    } else {
        moves
    };
    // Moves made at once at constant speeds (ORCA's own model) meet only if the agents
    // are close at the same time; a parallel group's timing is not known: anywhere. Each
    // meeting names the mate by its agent index.
    let meetings = if simultaneous {
        meetings_at_once(recorder.bodies(), &moves)
    } else {
        let group: Vec<GroupMove<'_>> = moves
            .iter()
            .map(|(agent, mv)| GroupMove {
                radius_m: recorder.bodies()[*agent].radius_m,
                waypoints: &mv.waypoints,
                refused: false,
            })
            .collect();
        group_meetings(&group, monitor::distance_between_moves_m)
            .into_iter()
            .map(|m| {
                m.map(|m| Meeting {
                    mate: moves[m.mate].0,
                    ..m
                })
            })
            .collect()
    };
    let mut kept = Vec::with_capacity(moves.len());
    for ((agent, mv), meeting) in moves.into_iter().zip(meetings) {
        match meeting {
            None => kept.push((agent, mv)),
            Some(m) => {
                let why = Refusal::GroupMate {
                    agent: m.mate,
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

/// For each of `moves` (made at once), its meeting with a mate in time, the mate named by
/// its agent index: every agent of `bodies` takes part, those without a move standing
/// where they are ([`simultaneous_meetings`]).
fn meetings_at_once(bodies: &[Body], moves: &[(usize, Move)]) -> Vec<Option<Meeting>> {
    let mut moving: Vec<Option<&Move>> = vec![None; bodies.len()];
    for (agent, mv) in moves {
        moving[*agent] = Some(mv);
    }
    let stands: Vec<[Point; 1]> = bodies.iter().map(|b| [b.position]).collect();
    let all: Vec<GroupMove<'_>> = bodies
        .iter()
        .zip(&moving)
        .zip(&stands)
        .map(|((body, mv), stand)| GroupMove {
            radius_m: body.radius_m,
            waypoints: mv.map_or(&stand[..], |mv| &mv.waypoints[..]),
            refused: mv.is_none(),
        })
        .collect();
    let found = simultaneous_meetings(&all, monitor::distance_between_simultaneous_moves_m);
    moves.iter().map(|(agent, _)| found[*agent]).collect()
}
