//! The messages between the coordinator and the agents, each of fixed capacity and
//! written in place in shared memory.

mod capacity;
mod geometry;
mod state;
mod world;

pub use capacity::CapacityError;
pub use geometry::{WirePoint, WirePose};
pub use state::{AgentState, MAX_COMPUTE_NS, MalformedState, StateKind, StateMsg};
pub use world::{WireBody, World};
