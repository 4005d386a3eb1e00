//! The step loop (`shared::run::step_loop::run_steps`) with sources and judges of the test's
//! own: it asks the judge about every move, takes only what the judge and the world
//! accept, and stops where the source says, closing the step or not as the contract has
//! it.

use shared::control::turn::{TurnController, TurnRequest};
use shared::control::vocabulary::{Move, MoveStatus};
use shared::geometry::Pose;
use shared::run::record::{FaultKind, Recorder};
use shared::run::simulate::{agent_controllers, plan_centre_path, simulate_along};
use shared::run::step_loop::{
    GroupMoves, GroupTurn, Judge, MoveSource, WorldChecksOnly, run_steps,
};
use shared::world::course::Course;
use shared::world::scenario::Scenario;

/// Every agent plans in this process (the paper's holonomic agents need no more than
/// the centre, where they stand and the others); the run is interrupted at
/// `interrupt_at`'s turns and stopped after `stop_after` is closed, when given.
struct Planners {
    controllers: Vec<TurnController>,
    interrupt_at: Option<usize>,
    stop_after: Option<usize>,
    /// The steps closed, in order.
    closed: Vec<usize>,
}

impl Planners {
    fn of(scenario: &Scenario) -> Self {
        Self {
            controllers: agent_controllers(scenario).expect("controllers"),
            interrupt_at: None,
            stop_after: None,
            closed: Vec::new(),
        }
    }
}

impl MoveSource for Planners {
    type Error = String;

    fn take_group(
        &mut self,
        turn: &GroupTurn<'_>,
        recorder: &mut Recorder<'_>,
    ) -> Result<GroupMoves, String> {
        if self.interrupt_at == Some(turn.step) {
            return Ok(GroupMoves::Interrupted);
        }
        let moves = turn.agents().iter().map(|&agent| {
            let others = recorder.world().others(agent);
            let me = recorder.world().bodies()[agent].position;
            let request = TurnRequest::new(*turn.centre, me, &others).at_step(turn.step);
            (agent, self.controllers[agent].plan(&request))
        });
        Ok(GroupMoves::Taken(moves.collect()))
    }

    fn close_step(
        &mut self,
        step: usize,
        _groups: &[Vec<usize>],
        _course: &Course<'_>,
        _world: &Recorder<'_>,
    ) -> Result<std::ops::ControlFlow<()>, String> {
        self.closed.push(step);
        Ok(match self.stop_after == Some(step) {
            true => std::ops::ControlFlow::Break(()),
            false => std::ops::ControlFlow::Continue(()),
        })
    }
}

/// Refuses every move it is shown, and counts them.
#[derive(Default)]
struct RefuseAll {
    shown: usize,
    steps_opened: Vec<usize>,
}

impl Judge for RefuseAll {
    fn open_step(&mut self, step: usize, _world: &Recorder<'_>) {
        self.steps_opened.push(step);
    }

    fn judge_group(
        &mut self,
        step: usize,
        moves: Vec<(usize, Move)>,
        recorder: &mut Recorder<'_>,
    ) -> Vec<(usize, Move)> {
        for (agent, mv) in moves {
            self.shown += 1;
            recorder.refuse(step, agent, mv.slot, FaultKind::Rejected, "refused".into());
        }
        Vec::new()
    }
}

fn paper() -> (Scenario, Vec<Pose>) {
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    (scenario, path)
}

/// Run the steps after `from` of `course` with `planners` and no extra judge.
fn run_planners(
    course: &mut Course<'_>,
    recorder: &mut Recorder<'_>,
    from: usize,
    planners: &mut Planners,
) -> Result<usize, String> {
    run_steps(course, recorder, from, planners, &mut WorldChecksOnly)
}

#[test]
fn a_source_of_plain_turns_reproduces_the_reference_on_the_paper() {
    let (scenario, path) = paper();
    let mut course = Course::new(&scenario, &path);
    let mut recorder = Recorder::new(&scenario, course.pose());
    let mut planners = Planners::of(&scenario);
    let last = run_planners(&mut course, &mut recorder, 0, &mut planners);
    assert_eq!(last, Ok(path.len() - 1));
    assert_eq!(planners.closed, (1..path.len()).collect::<Vec<_>>());
    let reference = simulate_along(&scenario, &path).expect("reference");
    assert_eq!(recorder.finish(true), reference);
}

#[test]
fn a_judge_that_refuses_every_move_leaves_every_agent_where_it_started() {
    let (scenario, path) = paper();
    let mut course = Course::new(&scenario, &path);
    let mut recorder = Recorder::new(&scenario, course.pose());
    let start: Vec<_> = recorder
        .world()
        .bodies()
        .iter()
        .map(|b| b.position)
        .collect();
    let mut judge = RefuseAll::default();
    let last = run_steps(
        &mut course,
        &mut recorder,
        0,
        &mut Planners::of(&scenario),
        &mut judge,
    );
    let steps = path.len() - 1;
    assert_eq!(last, Ok(steps));
    assert_eq!(judge.steps_opened, (1..=steps).collect::<Vec<_>>());
    // Every live agent's move was shown to the judge, and nothing else moved anyone.
    assert_eq!(judge.shown, steps * scenario.agents.len());
    let run = recorder.finish(true);
    for step in &run.steps {
        let now: Vec<_> = step.agents.iter().map(|a| a.position).collect();
        assert_eq!(now, start, "step {}", step.step);
    }
    assert!(
        run.steps[1..]
            .iter()
            .all(|s| s.agents.iter().all(|a| a.status == MoveStatus::Rejected))
    );
    assert_eq!(run.faults.len(), steps * scenario.agents.len());
    assert!(run.faults.iter().all(|f| f.kind == FaultKind::Rejected));
}

#[test]
fn an_interrupted_group_stops_the_loop_with_its_step_left_open() {
    let (scenario, path) = paper();
    let mut course = Course::new(&scenario, &path);
    let mut recorder = Recorder::new(&scenario, course.pose());
    let mut planners = Planners {
        interrupt_at: Some(5),
        ..Planners::of(&scenario)
    };
    let last = run_planners(&mut course, &mut recorder, 0, &mut planners);
    assert_eq!(last, Ok(5));
    assert_eq!(planners.closed, [1, 2, 3, 4]);
    let recorded: Vec<usize> = recorder.steps().iter().map(|s| s.step).collect();
    assert_eq!(recorded, [0, 1, 2, 3, 4], "step 5 is not closed");
}

#[test]
fn a_source_that_stops_after_a_step_ends_the_run_there_with_the_step_closed() {
    let (scenario, path) = paper();
    let mut course = Course::new(&scenario, &path);
    let mut recorder = Recorder::new(&scenario, course.pose());
    let mut planners = Planners {
        stop_after: Some(7),
        ..Planners::of(&scenario)
    };
    let last = run_planners(&mut course, &mut recorder, 0, &mut planners);
    assert_eq!(last, Ok(7));
    assert_eq!(recorder.steps().last().map(|s| s.step), Some(7));
    // Resumed from there, the loop goes on to the end, as the reference does.
    planners.stop_after = None;
    let last = run_planners(&mut course, &mut recorder, 7, &mut planners);
    assert_eq!(last, Ok(path.len() - 1));
    let reference = simulate_along(&scenario, &path).expect("reference");
    assert_eq!(recorder.finish(true), reference);
}
