//! One agent of a scenario: where it belongs in the formation, how large it is, how far
//! it may move in one step and how far it sees.

use super::Kinematics;
use crate::control::formation::Slot;

/// One agent: its formation slot, body radius, top speed, sensing radius and kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AgentSpec {
    /// Its slot in the formation.
    pub slot: Slot,
    /// Radius of its body, in metres.
    pub radius_m: f64,
    /// Its top speed: the longest move it makes in one step, in metres (`None`: no
    /// limit, the paper's model).
    pub max_step_m: Option<f64>,
    /// How far it senses: it plans with only the obstacles and agents whose disks come
    /// within this distance of its centre, in metres (`None`: it knows every body, the
    /// paper's Assumption 5).
    pub sensing_radius_m: Option<f64>,
    /// How it can move (holonomic: in any direction at once).
    pub kinematics: Kinematics,
    /// Its heading at the start relative to the centre's, radians (for an agent with a
    /// heading).
    pub heading_offset_rad: f64,
    /// Whether it ends each move facing the centre's heading (for an agent with a
    /// heading; otherwise its heading at the best point is free).
    pub align_heading: bool,
    /// How many steps ahead along the centre's plan it looks when its top speed keeps it
    /// from following its slot ([`crate::control::tracking`]): 0 chases where the slot is now.
    pub horizon_steps: usize,
}

impl AgentSpec {
    /// An agent in `slot` with body radius `radius_m`, no top speed and full knowledge.
    pub fn new(slot: Slot, radius_m: f64) -> Self {
        Self {
            slot,
            radius_m,
            max_step_m: None,
            sensing_radius_m: None,
            kinematics: Kinematics::Holonomic,
            heading_offset_rad: 0.0,
            align_heading: false,
            horizon_steps: 0,
        }
    }

    /// Whether this agent senses a disk centred at `centre` of radius `radius_m` when it
    /// stands at `me`: always without a sensing radius.
    pub fn senses(
        &self,
        me: &crate::geometry::Point,
        centre: &crate::geometry::Point,
        radius_m: f64,
    ) -> bool {
        match self.sensing_radius_m {
            None => true,
            Some(s) => (centre - me).norm() - radius_m <= s,
        }
    }
}
