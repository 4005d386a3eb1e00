//! One agent of a scenario: where it belongs in the formation and how large it is.

use crate::formation::Slot;

/// One agent: its formation slot and body radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AgentSpec {
    /// Its slot in the formation.
    pub slot: Slot,
    /// Radius of its body, in metres.
    pub radius_m: f64,
}
