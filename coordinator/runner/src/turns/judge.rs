//! Judging a move's safety with the independent monitor (parry): each move alone, then a
//! group's moves against each other; the world's own checks (plain geometry) come after,
//! in the step loop (`shared::run::step_loop`).

use shared::control::vocabulary::{Body, MAX_WAYPOINTS, Move, MoveStatus, TurnMode};
use shared::geometry::Point;
use shared::run::record::{FaultKind, Recorder};
use shared::run::step_loop::Judge;
use shared::world::groups::{GroupMove, Meeting, group_meetings, simultaneous_meetings};

use crate::monitor::{self, MoveUnderCheck, Refusal, SafetyMonitor, Standing};

/// The independent safety monitor (parry) as the step loop's judge: it sees the moving
/// obstacles move, and judges every move alone and then a group's moves against each
/// other before the world's own checks.
pub(super) struct MonitorJudge {
    /// The monitor, with the static obstacles and the moving ones where they stand.
    pub(super) monitor: SafetyMonitor,
}

impl Judge for MonitorJudge {
    /// The monitor moves the moving obstacles too, and checks their motion against the
    /// agents standing still, independently of the recorder: the strikes it sees must be
    /// the ones the world recorded (a warning otherwise).
    fn open_step(&mut self, step: usize, recorder: &Recorder<'_>) {
        let scenario = recorder.scenario();
        if scenario.moving.is_empty() {
            return;
        }
        let sweeps: Vec<(Vec<Point>, f64)> = scenario
            .moving
            .iter()
            .map(|m| (m.sweep(step), m.radius_m))
            .collect();
        let mut seen = self.monitor.move_obstacles(
            &sweeps,
            recorder.world().bodies(),
            recorder.world().alive(),
        );
        let mut recorded: Vec<(usize, usize)> = recorder
            .world()
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

    /// Each move alone ([`judge_alone`]), then every pair of the moves that passed
    /// against each other's whole move: two that meet are both refused.
    ///
    /// In `simultaneous` turns, where every agent moves at once at a constant speed, a
    /// move alone is checked against the bodies of the agents not alive (they stand),
    /// and two moves meet if they come close at the same time; each move is also checked
    /// against every body that does not move this step (a mate whose move was refused
    /// stands where it is), again after each refusal
    /// ([`shared::world::groups::simultaneous_meetings`]).
    fn judge_group(
        &mut self,
        step: usize,
        moves: Vec<(usize, Move)>,
        recorder: &mut Recorder<'_>,
    ) -> Vec<(usize, Move)> {
        let simultaneous = recorder.scenario().turns == TurnMode::Simultaneous;
        let passing = if simultaneous {
            recorder.world().alive().to_vec()
        } else {
            Vec::new()
        };
        // A move is checked against the bodies near it, found with a grid over them, when
        // there are enough moves to pay for building it (the verdicts are the same).
        let grid = (moves.len() > 1)
            .then(|| shared::control::safety::bodies_grid(recorder.world().bodies()));
        let mut alone = Vec::with_capacity(moves.len());
        for (agent, mv) in moves {
            let standing = Standing {
                bodies: recorder.world().bodies(),
                passing: &passing,
                grid: grid.as_ref(),
            };
            match judge_alone(&self.monitor, recorder, agent, &mv, &standing) {
                Ok(()) => alone.push((agent, mv)),
                Err(why) => refuse(recorder, step, agent, &mv, why),
            }
        }
        // Moves made at once at constant speeds (ORCA's own model) meet only if the
        // agents are close at the same time; a parallel group's timing is not known:
        // anywhere. Each meeting names the mate by its agent index.
        let meetings = if simultaneous {
            meetings_at_once(recorder.world().bodies(), &alone)
        } else {
            let group: Vec<GroupMove<'_>> = alone
                .iter()
                .map(|(agent, mv)| GroupMove {
                    radius_m: recorder.world().bodies()[*agent].radius_m,
                    waypoints: &mv.waypoints,
                    refused: false,
                })
                .collect();
            group_meetings(&group, monitor::distance_between_moves_m)
                .into_iter()
                .map(|m| {
                    m.map(|m| Meeting {
                        mate: alone[m.mate].0,
                        ..m
                    })
                })
                .collect()
        };
        let mut kept = Vec::with_capacity(alone.len());
        for ((agent, mv), meeting) in alone.into_iter().zip(meetings) {
            match meeting {
                None => kept.push((agent, mv)),
                Some(m) => {
                    let why = Refusal::GroupMate {
                        agent: m.mate,
                        distance_m: m.distance_m,
                        reach_m: m.reach_m,
                    };
                    refuse(recorder, step, agent, &mv, why);
                }
            }
        }
        kept
    }
}

/// Check `agent`'s move `mv` alone with the monitor: against its kinematic model, the
/// bodies `standing` (but those it marks as moving at the same time), the obstacles
/// and the field, and its top speed.
fn judge_alone(
    monitor: &SafetyMonitor,
    recorder: &Recorder<'_>,
    agent: usize,
    mv: &Move,
    standing: &Standing<'_>,
) -> Result<(), Refusal> {
    let spec = &recorder.scenario().agents[agent];
    let chord_errors_m = monitor::check_kinematics(
        spec.kinematics,
        recorder.world().headings()[agent],
        &mv.waypoints,
        mv.end_heading_rad,
        spec.max_step_m,
    )?;
    let under_check = MoveUnderCheck {
        agent,
        from: &recorder.world().bodies()[agent].position,
        waypoints: &mv.waypoints,
        best: &mv.best,
        under_way: mv.status == MoveStatus::UnderWay,
        chord_errors_m: &chord_errors_m,
    };
    monitor.check(&under_check, standing, MAX_WAYPOINTS)?;
    monitor::check_length(&mv.waypoints, spec.max_step_m)
}

/// Record that the monitor refused `agent`'s move `mv` (`why`): it stays where it is.
fn refuse(recorder: &mut Recorder<'_>, step: usize, agent: usize, mv: &Move, why: Refusal) {
    let why = why.to_string();
    tracing::debug!("step {step}: agent {agent}'s move rejected by the monitor: {why}");
    recorder.refuse(step, agent, mv.slot, FaultKind::Rejected, why);
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
