//! The shared vocabulary: the words the controllers, the scenario model, the record of a run
//! and the wire types all speak.
//!
//! This module is a leaf of the library's module graph: it uses only
//! [`geometry`](crate::geometry) and [`formation`](crate::control::formation), so anything may use
//! it without an import cycle (the test `shared/core/tests/it/module_graph.rs` keeps it so).
//!
//! - [`Body`]: a disk at a position, as the controllers see the other agents;
//! - [`Move`] and [`MoveStatus`]: the outcome of one agent's turn;
//! - [`AgentSpec`]: one agent of a scenario (its slot, radius, top speed and sensing
//!   radius);
//! - [`Kinematics`]: how an agent can move (holonomic, a unicycle or a car with a heading);
//! - [`Named`]: the values files and the command line spell by name, read and written
//!   through one helper;
//! - [`TurnMode`]: one mover at a time, or parallel groups;
//! - [`TurnOrder`]: in which order the agents of a step take their turns;
//! - [`ControllerKind`] and [`ControllerSpec`]: which controller moves the agents, with which
//!   settings;
//! - [`CbfSettings`]: the barrier-function controllers' settings and their validation;
//! - [`MAX_AGENTS`], [`MAX_OBSTACLES`], [`MAX_WAYPOINTS`]: the fixed capacities every
//!   part agrees on (the wire messages hold no more).

mod agent;
mod body;
mod capacity;
mod cbf_settings;
mod controller;
mod kinematics;
mod moves;
pub mod named;
mod turn_mode;
mod turn_order;

pub use agent::AgentSpec;
pub use body::Body;
pub use capacity::{MAX_AGENTS, MAX_OBSTACLES, MAX_WAYPOINTS};
pub use cbf_settings::{
    CBF_MARGIN_M, CBF_STALL_SHARE, CbfSettings, CbfSettingsError, DEFAULT_CBF_SUBSTEPS,
    DEFAULT_LSE_SHARPNESS_PER_M, MAX_CBF_SUBSTEPS,
};
pub use controller::{ControllerKind, ControllerSpec, OrcaSettings};
pub use kinematics::Kinematics;
pub use moves::{Move, MoveStatus};
pub use named::Named;
pub use turn_mode::TurnMode;
pub use turn_order::TurnOrder;
