//! One agent of a scenario: where it belongs in the formation, how large it is, how far
//! it may move in one step and how far it sees.

use crate::formation::Slot;

/// One agent: its formation slot, body radius, top speed and sensing radius.
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
}

impl AgentSpec {
    /// An agent in `slot` with body radius `radius_m`, no top speed and full knowledge.
    pub fn new(slot: Slot, radius_m: f64) -> Self {
        Self {
            slot,
            radius_m,
            max_step_m: None,
            sensing_radius_m: None,
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
