//! The world before a turn: the coordinator's message to the agent whose turn it is.

use iceoryx2::prelude::*;
use iceoryx2_bb_container::vector::{StaticVec, Vector};
use shared::control::tracking::MAX_HORIZON_STEPS;
use shared::control::vocabulary::{Body, MAX_AGENTS};
use shared::geometry::{self, Pose};

use crate::{CapacityError, WirePoint, WirePose};

/// One agent's body in the world message.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WireBody")]
pub struct WireBody {
    /// Where the agent stands.
    pub position: WirePoint,
    /// 1 while the agent belongs to the formation, 0 once it is frozen as an obstacle.
    pub alive: u32,
    /// The agent's index (the radius is in the mission).
    pub agent: u32,
    /// How far it moved over the last step (metres per step), with simultaneous turns
    /// (zero otherwise).
    pub velocity: WirePoint,
}

/// The world before a turn: published by the coordinator, read by the agent whose turn it
/// is.
#[repr(C)]
#[derive(Debug, Default, ZeroCopySend, PlacementDefault)]
#[type_name("formation::World")]
pub struct World {
    /// Increases with every world published; a state answering it echoes it.
    pub seq: u64,
    /// The step (centre pose index).
    pub step: u64,
    /// The turn's token: drawn for this turn alone from a generator seeded by the OS
    /// random source, so no process can answer a turn before it is granted; the move
    /// answering it carries it back.
    pub token: u64,
    /// Whose turn it is.
    pub turn_agent: u32,
    /// 1 when the turn's agent has a heading (a unicycle), given in `heading_rad`; 0 for
    /// a holonomic agent.
    pub has_heading: u32,
    /// The formation centre at this step.
    pub centre: WirePose,
    /// Where the turn's agent faces, in rad, when `has_heading` is 1 (else 0).
    pub heading_rad: f64,
    /// The agents the turn's agent may sense, itself included, in increasing agent order,
    /// dead ones included (they are obstacles): every agent without a sensing radius.
    pub bodies: StaticVec<WireBody, MAX_AGENTS>,
    /// The centre's next poses along its current plan, as many as the turn's agent looks
    /// ahead (none for an agent without a top speed or a look-ahead).
    pub ahead: StaticVec<WirePose, MAX_HORIZON_STEPS>,
}

impl World {
    /// Set the turn agent's heading (`None`: the agent has none).
    pub fn set_heading(&mut self, heading_rad: Option<f64>) {
        self.has_heading = u32::from(heading_rad.is_some());
        self.heading_rad = heading_rad.unwrap_or(0.0);
    }

    /// The turn agent's heading, as the coordinator wrote it (`None`: it has none; a
    /// flag other than 0 or 1 reads as none too).
    pub fn heading(&self) -> Option<f64> {
        (self.has_heading == 1).then_some(self.heading_rad)
    }

    /// Replace the centre's poses ahead with the first [`MAX_HORIZON_STEPS`] of `ahead`.
    pub fn set_ahead(&mut self, ahead: &[Pose]) {
        self.ahead.clear();
        for p in ahead.iter().take(MAX_HORIZON_STEPS) {
            // Within the capacity: cannot fail.
            let _ = self.ahead.push((*p).into());
        }
    }

    /// Give each body listed its agent's entry of `velocities` (indexed by agent; a body
    /// without one keeps zero). Call after [`Self::set_bodies`].
    pub fn set_velocities(&mut self, velocities: &[geometry::Vector]) {
        for b in self.bodies.iter_mut() {
            if let Some(v) = velocities.get(b.agent as usize) {
                b.velocity = WirePoint { x_m: v.x, y_m: v.y };
            }
        }
    }

    /// Replace the bodies with the agents `visible` (indices, increasing) of `bodies`
    /// (positions) with their `alive` flags.
    pub fn set_bodies(
        &mut self,
        bodies: &[Body],
        alive: &[bool],
        visible: impl IntoIterator<Item = usize>,
    ) -> Result<(), CapacityError> {
        self.bodies.clear();
        for i in visible {
            let (Some(b), Some(&a)) = (bodies.get(i), alive.get(i)) else {
                continue;
            };
            self.bodies
                .push(WireBody {
                    position: b.position.into(),
                    alive: u32::from(a),
                    agent: i as u32,
                    velocity: WirePoint::default(),
                })
                .map_err(|_| CapacityError::Agents(bodies.len()))?;
        }
        Ok(())
    }
}
