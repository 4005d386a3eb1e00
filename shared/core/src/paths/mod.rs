//! Paths: how a point or a robot gets from here to there among obstacles. Built on
//! [`geometry`](crate::geometry) only.
//!
//! - [`disk_path`]: the shortest collision-free path for a point among disks and polygons,
//!   and the proof that a point is out of reach;
//! - [`curve`]: curvature-bounded paths (arcs and lines) between poses;
//! - [`reeds_shepp`] and [`dubins`]: the shortest such paths, with and without reversing;
//! - [`hybrid_astar`]: the formation centre's planner in SE(2).

pub mod curve;
pub mod disk_path;
pub mod dubins;
pub mod hybrid_astar;
pub mod reeds_shepp;
