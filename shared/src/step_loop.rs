//! The step loop, written once: the reference simulation ([`crate::simulate`]) and the
//! coordinator's run over agent processes both go through [`run_steps`], so a step is
//! the same thing in both by construction.
//!
//! One step, top to bottom:
//! 1. the centre's [`Course`] advances (it may wait or replan in a changing world);
//! 2. the world opens the step: the moving obstacles move ([`Recorder::begin_step`]), the
//!    [`Judge`] sees them move, and the [`MoveSource`] notes what happened since the last
//!    step (an agent process that died between turns);
//! 3. the live agents are formed into groups of turns ([`turn_groups_ordered`]: one agent
//!    a group when turns are sequential);
//! 4. for each group in order, the source takes the group's turns (plans them in
//!    process, or grants them to agent processes and collects the answers), the judge
//!    checks the moves, and the world takes those that also pass its own check of the
//!    safety invariant ([`Recorder::submit_group`]); a refused move leaves its agent
//!    where it stands, recorded as a fault;
//! 5. the world closes the step ([`Recorder::end_step`]) and the source is told (a run
//!    logs the step there, and may stop).

use std::ops::ControlFlow;

use crate::course::Course;
use crate::geometry::{Pose, Vector};
use crate::groups::turn_groups_ordered;
use crate::record::Recorder;
use crate::tracking::MAX_HORIZON_STEPS;
use crate::vocabulary::{Move, TurnMode};

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
    /// gave none stays where it is; its fault is recorded in the world).
    Taken(Vec<(usize, Move)>),
    /// The run was interrupted: it stops at once, the step not closed.
    Interrupted,
}

/// Where the moves of a run come from: the in-process controllers of the reference
/// simulation, or the agent processes of a run.
pub trait MoveSource {
    /// Why the run cannot go on (not an agent's fault: those are recorded in the world).
    type Error;

    /// Step `step` is open, its groups not formed yet: record in `world` what happened
    /// since the last step (an agent process that died between turns, say).
    fn open_step(&mut self, step: usize, world: &mut Recorder<'_>) -> Result<(), Self::Error> {
        let _ = (step, world);
        Ok(())
    }

    /// Take the turns of `turn`'s group, every move planned against `world` as it
    /// stands (faults recorded there).
    fn take_group(
        &mut self,
        turn: &GroupTurn<'_>,
        world: &mut Recorder<'_>,
    ) -> Result<GroupMoves, Self::Error>;

    /// Step `step` is closed and recorded in `world`, its turns taken in `groups`, the
    /// centre's `course` where it stands: `Break` ends the run after it.
    fn close_step(
        &mut self,
        step: usize,
        groups: &[Vec<usize>],
        course: &Course<'_>,
        world: &Recorder<'_>,
    ) -> Result<ControlFlow<()>, Self::Error> {
        let _ = (step, groups, course, world);
        Ok(ControlFlow::Continue(()))
    }
}

/// A check of the moves besides the world's own ([`Recorder::submit_group`]): the
/// coordinator's independent safety monitor. It must not change the world but for
/// refusals.
pub trait Judge {
    /// Step `step` is open and its moving obstacles have moved in `world` (whom their
    /// motion struck is recorded there: [`Recorder::struck_now`]).
    fn open_step(&mut self, step: usize, world: &Recorder<'_>);

    /// Judge the `moves` of one group (live agents, each move planned against `world` as
    /// it stands): the moves that pass, in order; each one refused is recorded in `world`
    /// ([`Recorder::refuse`]), its agent staying where it is.
    fn judge_group(
        &mut self,
        step: usize,
        moves: Vec<(usize, Move)>,
        world: &mut Recorder<'_>,
    ) -> Vec<(usize, Move)>;
}

/// No judge but the world's own checks: the reference simulation's.
#[derive(Clone, Copy, Debug, Default)]
pub struct WorldChecksOnly;

impl Judge for WorldChecksOnly {
    fn open_step(&mut self, _step: usize, _world: &Recorder<'_>) {}

    fn judge_group(
        &mut self,
        _step: usize,
        moves: Vec<(usize, Move)>,
        _world: &mut Recorder<'_>,
    ) -> Vec<(usize, Move)> {
        moves
    }
}

/// Run every step after `step` (0 for a new run; a resumed run's last step) until the
/// `course` ends, the `source` stops the run or fails: the moves from `source`, judged
/// by `judge` and then by the world, recorded in `world`. The course is noted in `world`
/// however the loop ends; the last step taken is returned.
///
/// ```
/// use shared::course::Course;
/// use shared::record::Recorder;
/// use shared::scenario::Scenario;
/// use shared::simulate::{agent_controllers, plan_centre_path};
/// use shared::step_loop::{GroupMoves, GroupTurn, MoveSource, WorldChecksOnly, run_steps};
/// use shared::turn::{TurnController, TurnRequest};
/// use shared::vocabulary::Move;
///
/// /// Every agent plans in this process, the sequential way (no look-ahead, no mates).
/// struct Planners(Vec<TurnController>);
///
/// impl MoveSource for Planners {
///     type Error = std::convert::Infallible;
///     fn take_group(
///         &mut self,
///         turn: &GroupTurn<'_>,
///         world: &mut Recorder<'_>,
///     ) -> Result<GroupMoves, Self::Error> {
///         let moves = turn.agents().iter().map(|&agent| {
///             let others = world.others(agent);
///             let me = world.bodies()[agent].position;
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
/// let mut world = Recorder::new(&scenario, course.pose());
/// let mut planners = Planners(agent_controllers(&scenario).unwrap());
/// let last = run_steps(&mut course, &mut world, 0, &mut planners, &mut WorldChecksOnly);
/// assert_eq!(last, Ok(path.len() - 1));
/// assert_eq!(world.finish(true).summary().collisions, 0);
/// ```
pub fn run_steps<S: MoveSource, J: Judge>(
    course: &mut Course<'_>,
    world: &mut Recorder<'_>,
    mut step: usize,
    source: &mut S,
    judge: &mut J,
) -> Result<usize, S::Error> {
    let ended = loop {
        let Some(centre) = course.advance(step + 1, world.bodies(), world.alive()) else {
            break Ok(step);
        };
        step += 1;
        match take_step(step, &centre, course, world, source, judge) {
            Ok(ControlFlow::Continue(())) => {}
            Ok(ControlFlow::Break(())) => break Ok(step),
            Err(e) => break Err(e),
        }
    };
    world.note_course(course);
    ended
}

/// Step `step` with the centre at `centre`, from its opening to its close (`Break`: the
/// run stops, the step closed or not as the source said).
fn take_step<S: MoveSource, J: Judge>(
    step: usize,
    centre: &Pose,
    course: &Course<'_>,
    world: &mut Recorder<'_>,
    source: &mut S,
    judge: &mut J,
) -> Result<ControlFlow<()>, S::Error> {
    let scenario = world.scenario();
    world.begin_step(step, *centre);
    judge.open_step(step, world);
    source.open_step(step, world)?;
    let groups = turn_groups_ordered(
        scenario.turns,
        scenario.turn_order,
        centre.heading_rad,
        &scenario.agents,
        world.bodies(),
        world.alive(),
    );
    world.note_groups(groups.len());
    // Every agent moving at once knows how each body moved over the last step.
    let velocities = (scenario.turns == TurnMode::Simultaneous).then(|| world.velocities());
    for index in 0..groups.len() {
        let turn = GroupTurn {
            step,
            centre,
            ahead: course.ahead(MAX_HORIZON_STEPS),
            groups: &groups,
            index,
            velocities: velocities.as_deref(),
        };
        let GroupMoves::Taken(mut moves) = source.take_group(&turn, world)? else {
            return Ok(ControlFlow::Break(()));
        };
        // An agent frozen after its move was planned (killed for intruding while a
        // group mate's answer was awaited, say) does not move.
        moves.retain(|(agent, _)| world.alive()[*agent]);
        let passed = judge.judge_group(step, moves, world);
        // A refused move is recorded by the world; its agent simply stays.
        let _ = world.submit_group(step, passed);
    }
    world.end_step(step);
    source.close_step(step, &groups, course, world)
}
