//! The step loop, written once: the reference simulation ([`crate::run::simulate`]) and the
//! coordinator's run over agent processes both go through [`run_steps`], so a step is
//! the same thing in both by construction.
//!
//! One step, top to bottom:
//! 1. the centre's [`Course`] advances (it may wait or replan in a changing world);
//! 2. the recorder opens the step: the moving obstacles move ([`Recorder::begin_step`]),
//!    the [`Judge`] sees them move, and the [`MoveSource`] notes what happened since the
//!    last step (an agent process that died between turns);
//! 3. the live agents are formed into groups of turns ([`turn_groups_ordered`]: one agent
//!    a group when turns are sequential);
//! 4. for each group in order, the source takes the group's turns (plans them in
//!    process, or grants them to agent processes and collects the answers), the judge
//!    checks the moves, and the recorder takes into the world ([`crate::run::World`])
//!    those that also pass its own check of the safety invariant
//!    ([`Recorder::submit_group`]); a refused move leaves its agent where it stands,
//!    recorded as a fault;
//! 5. the recorder closes the step ([`Recorder::end_step`]) and the source is told (a run
//!    logs the step there, and may stop).

use std::ops::ControlFlow;

use crate::control::tracking::MAX_HORIZON_STEPS;
use crate::control::vocabulary::{Move, TurnMode};
use crate::geometry::{Pose, Vector};
use crate::run::record::Recorder;
use crate::world::course::Course;
use crate::world::groups::turn_groups_ordered;

/// One group's turns, as the step loop hands them to a [`MoveSource`].
#[derive(Clone, Copy, Debug)]
pub struct GroupTurn<'t> {
    /// The step, from 1.
    pub step: usize,
    /// Where the formation centre stands at this step.
    pub centre: &'t Pose,
    /// The centre's next poses along its plan, one per step (as far as any agent may look
    /// ahead: [`MAX_HORIZON_STEPS`]).
    pub ahead: &'t [Pose],
    /// Every group of the step, in the order their turns are taken.
    pub groups: &'t [Vec<usize>],
    /// Which of `groups` takes its turns now.
    pub index: usize,
    /// How far each agent moved over the last step (metres per step), when every agent
    /// moves at once ([`TurnMode::Simultaneous`]); `None` otherwise.
    pub velocities: Option<&'t [Vector]>,
}

impl GroupTurn<'_> {
    /// The agents whose turns these are, in the order they are taken.
    pub fn agents(&self) -> &[usize] {
        &self.groups[self.index]
    }
}

/// What came of one group's turns ([`MoveSource::take_group`]).
#[derive(Clone, Debug, PartialEq)]
pub enum GroupMoves {
    /// Each live agent's move, with the agent's index, in the order taken (an agent that
    /// gave none stays where it is; its fault is recorded in the recorder).
    Taken(Vec<(usize, Move)>),
    /// The run was interrupted: it stops at once, the step not closed.
    Interrupted,
}

/// Where the moves of a run come from: the in-process controllers of the reference
/// simulation, or the agent processes of a run.
pub trait MoveSource {
    /// Why the run cannot go on (not an agent's fault: those are recorded by the
    /// recorder).
    type Error;

    /// Step `step` is open, its groups not formed yet: record in `recorder` what happened
    /// since the last step (an agent process that died between turns, say).
    fn open_step(&mut self, step: usize, recorder: &mut Recorder<'_>) -> Result<(), Self::Error> {
        let _ = (step, recorder);
        Ok(())
    }

    /// Take the turns of `turn`'s group, every move planned against the world as it
    /// stands ([`Recorder::world`]; faults recorded by the `recorder`).
    fn take_group(
        &mut self,
        turn: &GroupTurn<'_>,
        recorder: &mut Recorder<'_>,
    ) -> Result<GroupMoves, Self::Error>;

    /// Step `step` is closed and recorded in `recorder`, its turns taken in `groups`, the
    /// centre's `course` where it stands: `Break` ends the run after it.
    fn close_step(
        &mut self,
        step: usize,
        groups: &[Vec<usize>],
        course: &Course<'_>,
        recorder: &Recorder<'_>,
    ) -> Result<ControlFlow<()>, Self::Error> {
        let _ = (step, groups, course, recorder);
        Ok(ControlFlow::Continue(()))
    }
}

/// A check of the moves besides the recorder's own ([`Recorder::submit_group`]): the
/// coordinator's independent safety monitor. It changes nothing but by refusals.
pub trait Judge {
    /// Step `step` is open and its moving obstacles have moved in the recorder's world
    /// (whom their motion struck: [`crate::run::World::struck_now`]).
    fn open_step(&mut self, step: usize, recorder: &Recorder<'_>);

    /// Judge the `moves` of one group (live agents, each move planned against the world
    /// as it stands): the moves that pass, in order; each one refused is recorded by the
    /// `recorder` ([`Recorder::refuse`]), its agent staying where it is.
    fn judge_group(
        &mut self,
        step: usize,
        moves: Vec<(usize, Move)>,
        recorder: &mut Recorder<'_>,
    ) -> Vec<(usize, Move)>;
}

/// No judge but the recorder's own checks: the reference simulation's.
#[derive(Clone, Copy, Debug, Default)]
pub struct WorldChecksOnly;

impl Judge for WorldChecksOnly {
    fn open_step(&mut self, _step: usize, _recorder: &Recorder<'_>) {}

    fn judge_group(
        &mut self,
        _step: usize,
        moves: Vec<(usize, Move)>,
        _recorder: &mut Recorder<'_>,
    ) -> Vec<(usize, Move)> {
        moves
    }
}

/// Run every step after `step` (0 for a new run; a resumed run's last step) until the
/// `course` ends, the `source` stops the run or fails: the moves from `source`, judged
/// by `judge` and then by the recorder, recorded in `recorder`. The course is noted in `recorder`
/// however the loop ends; the last step taken is returned.
///
/// ```
/// use shared::world::course::Course;
/// use shared::run::record::Recorder;
/// use shared::world::scenario::Scenario;
/// use shared::run::simulate::{agent_controllers, plan_centre_path};
/// use shared::run::step_loop::{GroupMoves, GroupTurn, MoveSource, WorldChecksOnly, run_steps};
/// use shared::control::turn::{TurnController, TurnRequest};
/// use shared::control::vocabulary::Move;
///
/// /// Every agent plans in this process, the sequential way (no look-ahead, no mates).
/// struct Planners(Vec<TurnController>);
///
/// impl MoveSource for Planners {
///     type Error = std::convert::Infallible;
///     fn take_group(
///         &mut self,
///         turn: &GroupTurn<'_>,
///         recorder: &mut Recorder<'_>,
///     ) -> Result<GroupMoves, Self::Error> {
///         let moves = turn.agents().iter().map(|&agent| {
///             let others = recorder.world().others(agent);
///             let me = recorder.world().bodies()[agent].position;
///             let request = TurnRequest::new(*turn.centre, me, &others).at_step(turn.step);
///             (agent, self.0[agent].plan(&request))
///         });
///         Ok(GroupMoves::Taken(moves.collect()))
///     }
/// }
///
/// let scenario = Scenario::paper();
/// let path = plan_centre_path(&scenario).unwrap();
/// let mut course = Course::new(&scenario, &path);
/// let mut recorder = Recorder::new(&scenario, course.pose());
/// let mut planners = Planners(agent_controllers(&scenario).unwrap());
/// let last = run_steps(&mut course, &mut recorder, 0, &mut planners, &mut WorldChecksOnly);
/// assert_eq!(last, Ok(path.len() - 1));
/// assert_eq!(recorder.finish(true).summary().collisions, 0);
/// ```
pub fn run_steps<S: MoveSource, J: Judge>(
    course: &mut Course<'_>,
    recorder: &mut Recorder<'_>,
    mut step: usize,
    source: &mut S,
    judge: &mut J,
) -> Result<usize, S::Error> {
    let ended = loop {
        let Some(centre) = course.advance(
            step + 1,
            recorder.world().bodies(),
            recorder.world().alive(),
        ) else {
            break Ok(step);
        };
        step += 1;
        match take_step(step, &centre, course, recorder, source, judge) {
            Ok(ControlFlow::Continue(())) => {}
            Ok(ControlFlow::Break(())) => break Ok(step),
            Err(e) => break Err(e),
        }
    };
    recorder.note_course(course);
    ended
}

/// Step `step` with the centre at `centre`, from its opening to its close (`Break`: the
/// run stops, the step closed or not as the source said).
fn take_step<S: MoveSource, J: Judge>(
    step: usize,
    centre: &Pose,
    course: &Course<'_>,
    recorder: &mut Recorder<'_>,
    source: &mut S,
    judge: &mut J,
) -> Result<ControlFlow<()>, S::Error> {
    let scenario = recorder.scenario();
    recorder.begin_step(step, *centre);
    judge.open_step(step, recorder);
    source.open_step(step, recorder)?;
    let groups = turn_groups_ordered(
        scenario.turns,
        scenario.turn_order,
        centre.heading_rad,
        &scenario.agents,
        recorder.world().bodies(),
        recorder.world().alive(),
    );
    recorder.note_groups(groups.len());
    // Every agent moving at once knows how each body moved over the last step.
    let velocities =
        (scenario.turns == TurnMode::Simultaneous).then(|| recorder.world().velocities());
    for index in 0..groups.len() {
        let turn = GroupTurn {
            step,
            centre,
            ahead: course.ahead(MAX_HORIZON_STEPS),
            groups: &groups,
            index,
            velocities: velocities.as_deref(),
        };
        let GroupMoves::Taken(mut moves) = source.take_group(&turn, recorder)? else {
            return Ok(ControlFlow::Break(()));
        };
        // An agent frozen after its move was planned (killed for intruding while a
        // group mate's answer was awaited, say) does not move.
        moves.retain(|(agent, _)| recorder.world().alive()[*agent]);
        let passed = judge.judge_group(step, moves, recorder);
        // A refused move is recorded by the recorder; its agent simply stays.
        let _ = recorder.submit_group(step, passed);
    }
    recorder.end_step(step);
    source.close_step(step, &groups, course, recorder)
}
