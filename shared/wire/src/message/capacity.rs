//! Why a scenario or a move does not fit the fixed capacity of a message.

use shared::control::vocabulary::{MAX_AGENTS, MAX_OBSTACLES, MAX_WAYPOINTS};

/// Why a scenario does not fit the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CapacityError {
    /// More obstacles than [`MAX_OBSTACLES`].
    #[error("{0} obstacles exceed the wire capacity of {MAX_OBSTACLES}")]
    Obstacles(usize),
    /// More agents than [`MAX_AGENTS`].
    #[error("{0} agents exceed the wire capacity of {MAX_AGENTS}")]
    Agents(usize),
    /// More waypoints than [`MAX_WAYPOINTS`].
    #[error("{0} waypoints exceed the wire capacity of {MAX_WAYPOINTS}")]
    Waypoints(usize),
}
