//! The world: what a scenario puts round the formation and how it changes during a run.
//! Built on [`geometry`](crate::geometry), [`paths`](crate::paths) and
//! [`control`](crate::control) (a scenario names its agents' controllers).
//!
//! - [`scenario`]: the TOML scenario model and its validation;
//! - [`maps`]: occupancy-grid maps (ROS map_server YAML with a PGM or PNG image) and their
//!   blocked cells merged into exact polygon outlines;
//! - [`moving_obstacle`]: obstacles driven along routes, and when they move;
//! - [`course`]: the centre's course in a changing world (obstacles found on the way,
//!   online replanning, waits);
//! - [`sensing`]: which agents an agent senses (limited sensing);
//! - [`groups`]: parallel turns: which agents may move at once.

pub mod course;
pub mod groups;
pub mod maps;
pub mod moving_obstacle;
pub mod scenario;
pub mod sensing;
