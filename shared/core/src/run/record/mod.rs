//! The record of a run: what every agent did at every step, the faults, and the figures
//! the paper reports (deviation, Fig. 9) plus the safety figures (clearance).
//!
//! One concept a file: the record itself here ([`Run`], [`Step`], [`AgentStep`]), the
//! faults and their kinds in `fault.rs`, the figures of a run in `summary.rs` (those of
//! agents with a heading in `headings.rs`), and in `recorder.rs` the [`Recorder`], the
//! run's referee: it owns the world every turn reads ([`crate::run::World`]), changes
//! it only by the moves that keep the safety invariant, and keeps this record; the step
//! loop ([`crate::run::step_loop`]) drives it for the reference simulation and the coordinator
//! alike.

use crate::control::vocabulary::{Body, MoveStatus};
use crate::geometry::{Point, Pose, polyline_length_m};
use crate::world::course::{Course, Replan, Wait};
use crate::world::scenario::Scenario;

mod fault;
mod headings;
mod recorder;
mod replay;
mod summary;

pub use fault::{Fault, FaultKind, UnknownFaultKind};
pub use headings::HeadingSummary;
pub use recorder::Recorder;
pub use replay::replay_course;
pub use summary::{ReplanNote, Summary, WaitNote};

/// One agent at the end of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct AgentStep {
    /// Where the agent stands.
    pub position: Point,
    /// Its ideal slot at this step.
    pub slot: Point,
    /// The best point it chose (its position when it did not move); with a top speed it
    /// may stand short of it ([`MoveStatus::UnderWay`]).
    pub best: Point,
    /// `||position - slot||`, in metres.
    pub deviation_m: f64,
    /// Distance to the nearest other body (obstacle or agent) minus both radii, in metres.
    pub clearance_m: f64,
    /// What it did this step.
    pub status: MoveStatus,
    /// Whether it still belongs to the formation (its process is alive).
    pub alive: bool,
    /// The polyline it followed this step (its position alone when it did not move).
    pub waypoints: Vec<Point>,
    /// Where it faces, radians in `(-pi, pi]`, for an agent with a heading
    /// (a unicycle or a car, [`Kinematics`](crate::control::vocabulary::Kinematics)); `None` for a holonomic
    /// one.
    pub heading_rad: Option<f64>,
}

/// Every agent at the end of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// Step number; step 0 is the formation at the start pose.
    pub step: usize,
    /// The formation centre.
    pub centre: Pose,
    /// One entry per agent, in agent order.
    pub agents: Vec<AgentStep>,
    /// How many groups of turns the step took (one per live agent in sequential mode).
    pub groups: usize,
    /// Where each moving obstacle stands during the step's turns, in scenario order.
    pub moving: Vec<Point>,
    /// `(moving obstacle, agent, distance in metres)` for each live agent that a moving
    /// obstacle's motion at the start of the step came within their radii sum of: empty
    /// in a safe run.
    pub struck: Vec<(usize, usize, f64)>,
}

impl Step {
    /// Every agent's body where this step left it, with its radius from `scenario`.
    pub fn bodies(&self, scenario: &Scenario) -> Vec<Body> {
        scenario
            .agents
            .iter()
            .zip(&self.agents)
            .map(|(spec, row)| Body {
                position: row.position,
                radius_m: spec.radius_m,
            })
            .collect()
    }

    /// The longest move of the step, in metres.
    pub fn max_move_m(&self) -> f64 {
        self.agents
            .iter()
            .map(|a| polyline_length_m(&a.waypoints))
            .fold(0.0, f64::max)
    }

    /// Smallest clearance between any two bodies at the end of the step, in metres.
    pub fn min_clearance_m(&self) -> f64 {
        self.agents
            .iter()
            .map(|a| a.clearance_m)
            .fold(f64::INFINITY, f64::min)
    }

    /// Mean deviation of the live agents (the paper's red curve in Fig. 9); 0 when none
    /// is alive.
    pub fn mean_deviation_m(&self) -> f64 {
        let live: Vec<f64> = self
            .agents
            .iter()
            .filter(|a| a.alive)
            .map(|a| a.deviation_m)
            .collect();
        if live.is_empty() {
            0.0
        } else {
            live.iter().sum::<f64>() / live.len() as f64
        }
    }
}

/// A whole run.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The scenario's name.
    pub scenario: String,
    /// The formation centre's poses, one per step.
    pub centre_path: Vec<Pose>,
    /// Every step recorded, starting with step 0.
    pub steps: Vec<Step>,
    /// Every fault, in order.
    pub faults: Vec<Fault>,
    /// Whether the run went through the whole centre path.
    pub completed: bool,
    /// What the centre's course did in a changing world: replans, waits, obstacles found.
    pub course: CourseRecord,
}

/// What the centre's course did during a run ([`Course`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CourseRecord {
    /// Every replanning, found or not.
    pub replans: Vec<Replan>,
    /// Every step the centre held its pose.
    pub waits: Vec<Wait>,
    /// For each `[[obstacles.unknown]]` obstacle, the step it became known.
    pub found_at: Vec<Option<usize>>,
    /// Whether the run ended because no way through was found for too long.
    pub gave_up: bool,
}

impl CourseRecord {
    /// The record of `course` so far.
    pub fn of(course: &Course) -> Self {
        Self {
            replans: course.replans().to_vec(),
            waits: course.waits().to_vec(),
            found_at: course.found_at().to_vec(),
            gave_up: course.gave_up(),
        }
    }
}

impl Run {
    /// The centre path actually followed, one pose per step (waits repeat a pose).
    pub fn followed_path(&self) -> Vec<Pose> {
        self.steps.iter().map(|s| s.centre).collect()
    }
}
