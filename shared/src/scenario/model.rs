//! The validated scenario: what a run is made of.

use crate::geometry::{Disk, Field, Pose};
use crate::vocabulary::{AgentSpec, PlannerKind, PlannerSpec, TurnMode};

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
    /// The agents, in turn order.
    pub agents: Vec<AgentSpec>,
    /// Formation centre path settings.
    pub path: PathSpec,
    /// The controller and its settings.
    pub planner: PlannerSpec,
    /// One mover at a time, or parallel groups.
    pub turns: TurnMode,
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
}

impl Scenario {
    /// The same scenario run by another planner.
    pub fn with_planner(&self, kind: PlannerKind) -> Self {
        let mut s = self.clone();
        s.planner.kind = kind;
        s
    }

    /// Number of agents.
    pub fn agent_count(&self) -> usize {
        self.agents.len()
    }
}
