//! The world a turn reads ([`World`]): where every agent stands and faces, who is alive,
//! where the moving obstacles stand, how each body moved over the last step. The
//! [`Recorder`](crate::run::record::Recorder) owns it, changes it only through the moves it
//! takes, and keeps the record of what happened apart.

use crate::control::turn::MateView;
use crate::control::vocabulary::{Body, Move};
use crate::geometry::{Point, Pose, Vector, wrap_angle_rad};
use crate::world::scenario::Scenario;

/// The world during a run, as every turn reads it.
#[derive(Clone, Debug)]
pub struct World<'a> {
    /// The scenario being run.
    scenario: &'a Scenario,
    /// Every agent's body, in agent order.
    bodies: Vec<Body>,
    /// Where each agent with a heading faces (`None` for a holonomic agent).
    headings: Vec<Option<f64>>,
    /// Whether each agent is alive (belongs to the formation).
    alive: Vec<bool>,
    /// Where each moving obstacle stands now.
    moving: Vec<Point>,
    /// The agents a moving obstacle's motion struck at the start of this step:
    /// `(moving obstacle, agent, distance in metres)`.
    struck: Vec<(usize, usize, f64)>,
    /// Every agent's position at the end of the last two recorded steps (the last one
    /// second), as far as there are any: what velocities are made of.
    last_two: Vec<Vec<Point>>,
}

impl<'a> World<'a> {
    /// The world of `scenario` with the centre at `start`: every agent at its ideal slot
    /// (facing the centre's heading plus its offset, if it has a heading), alive; every
    /// moving obstacle at its first waypoint.
    pub fn new(scenario: &'a Scenario, start: Pose) -> Self {
        let bodies: Vec<Body> = scenario
            .agents
            .iter()
            .map(|a| Body {
                position: a.slot.ideal_position(&start),
                radius_m: a.radius_m,
            })
            .collect();
        let headings = scenario
            .agents
            .iter()
            .map(|a| {
                a.kinematics
                    .has_heading()
                    .then(|| wrap_angle_rad(start.heading_rad + a.heading_offset_rad))
            })
            .collect();
        Self {
            scenario,
            alive: vec![true; bodies.len()],
            bodies,
            headings,
            moving: scenario.moving.iter().map(|m| m.position_at(0)).collect(),
            struck: Vec::new(),
            last_two: Vec::new(),
        }
    }

    /// The world of `scenario` as a recorded run left it (a run resumed): every agent's
    /// body, heading and whether it is alive, where each moving obstacle stands, and every
    /// agent's position at the end of the last two recorded steps (the last one second;
    /// one if only one was recorded).
    pub(crate) fn resumed(
        scenario: &'a Scenario,
        bodies: Vec<Body>,
        headings: Vec<Option<f64>>,
        alive: Vec<bool>,
        moving: Vec<Point>,
        last_two: Vec<Vec<Point>>,
    ) -> Self {
        Self {
            scenario,
            bodies,
            headings,
            alive,
            moving,
            struck: Vec::new(),
            last_two,
        }
    }

    /// The scenario being run.
    pub fn scenario(&self) -> &'a Scenario {
        self.scenario
    }

    /// Every agent's body, in agent order.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// Where each agent faces, in agent order: `None` for a holonomic agent.
    pub fn headings(&self) -> &[Option<f64>] {
        &self.headings
    }

    /// Whether each agent is alive, in agent order.
    pub fn alive(&self) -> &[bool] {
        &self.alive
    }

    /// Every body but `agent`'s: the other agents, dead or alive, which stand still.
    pub fn others(&self, agent: usize) -> Vec<Body> {
        self.bodies
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != agent)
            .map(|(_, b)| *b)
            .collect()
    }

    /// Every agent as the world shows it to its mates ([`MateView`]), in index order
    /// (for [`crate::control::turn::TurnController::mate_views`]).
    pub fn views(&self) -> impl Iterator<Item = MateView> + '_ {
        self.bodies
            .iter()
            .zip(&self.alive)
            .enumerate()
            .map(|(agent, (b, &alive))| MateView {
                agent,
                position: b.position,
                alive,
            })
    }

    /// How far each agent moved over the last recorded step (metres per step: its
    /// velocity), from the positions recorded at the end of the last two steps; zero
    /// before two steps are recorded. What agents moving simultaneously know of each
    /// other ([`crate::control::vocabulary::TurnMode::Simultaneous`]).
    pub fn velocities(&self) -> Vec<Vector> {
        match &self.last_two[..] {
            [before, now] => now
                .iter()
                .zip(before)
                .map(|(now, before)| now - before)
                .collect(),
            _ => vec![Vector::zeros(); self.bodies.len()],
        }
    }

    /// Where each moving obstacle stands now, in scenario order.
    pub fn moving_positions(&self) -> &[Point] {
        &self.moving
    }

    /// `(moving obstacle, agent, distance in metres)` for each strike of this step's
    /// obstacle motion ([`crate::run::record::Recorder::begin_step`]).
    pub fn struck_now(&self) -> &[(usize, usize, f64)] {
        &self.struck
    }

    /// Move `agent` to where `mv` ends, facing where it leaves it (an agent with a
    /// heading).
    pub(crate) fn take_move(&mut self, agent: usize, mv: &Move) {
        self.bodies[agent].position = mv.end();
        if self.headings[agent].is_some() {
            self.headings[agent] = mv.end_heading_rad.map(wrap_angle_rad);
        }
    }

    /// Take `agent` out of the formation (it stays where it stands) or put it back.
    pub(crate) fn set_alive(&mut self, agent: usize, alive: bool) {
        self.alive[agent] = alive;
    }

    /// Moving obstacle `m` now stands at `at`.
    pub(crate) fn place_moving(&mut self, m: usize, at: Point) {
        self.moving[m] = at;
    }

    /// Record that moving obstacle `m`'s motion struck `agent`, `distance_m` away.
    pub(crate) fn note_strike(&mut self, m: usize, agent: usize, distance_m: f64) {
        self.struck.push((m, agent, distance_m));
    }

    /// The step ends: its strikes, handed over, and every agent's position kept for the
    /// velocities.
    pub(crate) fn end_step(&mut self) -> Vec<(usize, usize, f64)> {
        if self.last_two.len() == 2 {
            self.last_two.remove(0);
        }
        self.last_two
            .push(self.bodies.iter().map(|b| b.position).collect());
        std::mem::take(&mut self.struck)
    }
}
