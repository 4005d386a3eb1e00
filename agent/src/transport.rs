//! What the agent's turn loop needs from the outside world.

use std::time::Duration;

use shared::control::turn::{MateView, TurnController};
use shared::control::vocabulary::{AgentSpec, ControllerSpec, Move, TurnMode};
use shared::geometry::{Disk, Field, Point, Polygon, Pose, Vector};
use shared::world::moving_obstacle::MovingObstacle;

/// The static scenario as an agent sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionView {
    /// The field.
    pub field: Field,
    /// Every static obstacle, true radii: those the centre knows and those it finds on
    /// the way (an agent senses both alike).
    pub obstacles: Vec<Disk>,
    /// The static polygon obstacles.
    pub polygons: Vec<Polygon>,
    /// The map the polygons from its `first_piece` on come from, if any.
    pub map: Option<shared::world::scenario::ScenarioMap>,
    /// The moving obstacles; where they stand follows from the turn's step.
    pub moving: Vec<MovingObstacle>,
    /// Every agent, in agent order.
    pub agents: Vec<AgentSpec>,
    /// The controller and its settings.
    pub controller: ControllerSpec,
    /// How the agents take their turns.
    pub turns: TurnMode,
}

impl MissionView {
    /// What an agent sees of `scenario`: every obstacle with its true radius, known or
    /// not.
    pub fn of(scenario: shared::world::scenario::Scenario) -> Self {
        Self {
            field: scenario.field,
            obstacles: scenario.static_obstacles(),
            polygons: scenario.polygons,
            map: scenario.map,
            moving: scenario.moving,
            agents: scenario.agents,
            controller: scenario.controller,
            turns: scenario.turns,
        }
    }
}

/// The world at the start of this agent's turn.
#[derive(Clone, Debug, PartialEq)]
pub struct TurnInput {
    /// The world's sequence number (echoed in the answer).
    pub seq: u64,
    /// The step.
    pub step: u64,
    /// The turn's token (echoed in the answer: it binds the move to this turn).
    pub token: u64,
    /// The formation centre.
    pub centre: Pose,
    /// Where this agent faces, if it has a heading (a unicycle): the coordinator keeps
    /// every agent's pose and hands it over with each turn.
    pub heading_rad: Option<f64>,
    /// The centre's next poses along its plan, as far as this agent looks ahead.
    pub ahead: Vec<Pose>,
    /// The agents this agent may sense, itself included, as (agent index, position) in
    /// increasing index order (every agent when it has no sensing radius); their radii
    /// are in the mission.
    pub bodies: Vec<(usize, Point)>,
    /// With simultaneous turns, how far each body of `bodies` moved over the last step
    /// (metres per step, same order); empty otherwise.
    pub velocities: Vec<Vector>,
    /// The agents of `bodies` frozen as obstacles (dead), by index: they stand for good.
    pub frozen: Vec<usize>,
}

impl TurnInput {
    /// The mates this turn lists for agent `agent` as `controller` plans with them: every
    /// body but its own, with whether it is frozen; none when the controller does not give
    /// way ([`TurnController::gives_way`]: listing them is a turn's cost at 200 agents).
    pub fn mates_for(&self, agent: usize, controller: &TurnController) -> Vec<MateView> {
        let views = self.bodies.iter().map(|&(j, position)| MateView {
            agent: j,
            position,
            alive: !self.frozen.contains(&j),
        });
        controller.mate_views(agent, views)
    }
}

/// What the coordinator asks.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Take a turn in this world.
    Turn(TurnInput),
    /// Leave now (asked to, or the coordinator is gone).
    Quit,
}

/// An agent's answer to one turn, as it goes to the coordinator.
#[derive(Clone, Copy, Debug)]
pub struct Reply<'a> {
    /// The turn answered (its sequence number and token are echoed).
    pub turn: &'a TurnInput,
    /// The move.
    pub mv: &'a Move,
    /// The status code sent: normally `mv.status as u32`; a test mode may send another.
    pub status: u32,
    /// The time spent computing the move.
    pub compute: Duration,
}

impl<'a> Reply<'a> {
    /// The reply carrying `mv` with its own status.
    pub fn new(turn: &'a TurnInput, mv: &'a Move, compute: Duration) -> Self {
        Self {
            turn,
            mv,
            status: mv.status as u32,
            compute,
        }
    }
}

/// The agent's link to the coordinator.
pub trait Transport {
    /// Tell the coordinator this agent is ready for turns.
    fn announce_ready(&mut self) -> anyhow::Result<()>;
    /// Block (without using CPU) until the next command.
    fn next_command(&mut self) -> anyhow::Result<Command>;
    /// The static scenario (available from the first turn on).
    fn mission(&mut self) -> anyhow::Result<MissionView>;
    /// Publish this turn's move.
    fn publish_move(&mut self, reply: Reply<'_>) -> anyhow::Result<()>;
}
