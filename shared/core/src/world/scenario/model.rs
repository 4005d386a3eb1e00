//! The validated scenario: what a run is made of.

use crate::geometry::{Disk, Field, Polygon, Pose};
use crate::world::moving_obstacle::MovingObstacle;

use super::ScenarioMap;
use crate::control::vocabulary::{AgentSpec, ControllerKind, ControllerSpec, TurnMode, TurnOrder};

/// A validated scenario: every number finite and in range, every body placed legally.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Name, used in output folder names and plot titles.
    pub name: String,
    /// Seed for every random choice.
    pub seed: u64,
    /// The playing field.
    pub field: Field,
    /// Every obstacle with its true (not inflated) radius, explicit ones first, then the
    /// generated ones.
    pub obstacles: Vec<Disk>,
    /// Obstacles that move along routes ([`MovingObstacle`]), in file order.
    pub moving: Vec<MovingObstacle>,
    /// Real static obstacles the formation centre's planner does not know at the start:
    /// each joins the known map the moment an agent senses it (agents plan around them as
    /// around any obstacle they sense).
    pub unknown: Vec<Disk>,
    /// Static polygon obstacles, known from the start: those of `[[obstacles.polygon]]`
    /// in file order, then the pieces of the map's blocked cells, if it has a map.
    pub polygons: Vec<Polygon>,
    /// The occupancy map of `[map]`, if any (its pieces are in `polygons`).
    pub map: Option<ScenarioMap>,
    /// The agents, in slot order (agent 0 first).
    pub agents: Vec<AgentSpec>,
    /// Formation centre path settings.
    pub path: PathSpec,
    /// The controller and its settings.
    pub controller: ControllerSpec,
    /// One mover at a time, or parallel groups.
    pub turns: TurnMode,
    /// In which order the agents of a step take their turns.
    pub turn_order: TurnOrder,
}

/// Settings of the formation centre's path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSpec {
    /// Start pose of the centre.
    pub start: Pose,
    /// Goal pose of the centre.
    pub goal: Pose,
    /// Minimum turning radius of the centre, in metres.
    pub turning_radius_m: f64,
    /// Centre travel between two steps, in metres.
    pub step_m: f64,
    /// Clearance the centre keeps from every obstacle boundary and field edge, in metres.
    pub centre_clearance_m: f64,
    /// Whether the centre may drive backwards.
    pub allow_reverse: bool,
    /// The centre holds while a live agent's deviation exceeds this, in metres (absent:
    /// it never waits for stragglers).
    pub max_lag_m: Option<f64>,
}

impl Scenario {
    /// The same scenario run by another controller.
    pub fn with_controller(&self, kind: ControllerKind) -> Self {
        let mut s = self.clone();
        s.controller.kind = kind;
        s
    }

    /// Why this scenario cannot be run by controller `kind` (`None`: it can): only the
    /// best-point controller plans round polygon obstacles yet, and simultaneous turns
    /// are ORCA's own model, for the orca controller alone.
    pub fn refuses_controller(&self, kind: ControllerKind) -> Option<String> {
        if self.turns == TurnMode::Simultaneous && kind != ControllerKind::Orca {
            return Some(format!(
                "controller {}: scenario {:?} takes simultaneous turns, ORCA's own model, for the orca controller only",
                kind.name(),
                self.name
            ));
        }
        (!self.polygons.is_empty() && kind != ControllerKind::BestPoint).then(|| {
            format!(
                "controller {}: scenario {:?} has polygon obstacles, which only best-point plans round yet",
                kind.name(),
                self.name
            )
        })
    }

    /// Whether anything in the world changes during a run: moving obstacles, obstacles
    /// found on the way, or a centre that waits for stragglers. A static scenario follows
    /// the centre path planned before the run, as the paper does.
    pub fn changes(&self) -> bool {
        !self.moving.is_empty() || !self.unknown.is_empty() || self.path.max_lag_m.is_some()
    }

    /// Every static obstacle, known or not: the real field the agents move in.
    pub fn static_obstacles(&self) -> Vec<Disk> {
        let mut all = self.obstacles.clone();
        all.extend_from_slice(&self.unknown);
        all
    }

    /// Number of agents.
    pub fn agent_count(&self) -> usize {
        self.agents.len()
    }
}
