//! The formation controller's library: every algorithm, no I/O loop and no transport
//! (the messages between processes are in the `wire` crate, `shared/wire`).
//!
//! One concept per module:
//! - [`geometry`]: points, poses, disks, the field, the disk grid index, free space;
//! - [`formation`]: ideal slots (the paper's equation 2);
//! - [`best_point`]: the exact best point (Theorem 1) with reachability;
//! - [`disk_path`]: shortest collision-free path for a point among disks;
//! - [`reeds_shepp`] and [`dubins`]: shortest curvature-bounded paths between poses;
//! - [`hybrid_astar`]: the formation centre's planner;
//! - [`scenario`]: the TOML scenario model and its validation;
//! - [`turn`]: one agent's turn (slot, best point, path), shared by simulation and agents;
//! - [`safety`]: the safety invariant checked with plain geometry;
//! - [`run`]: the record of a run and its figures;
//! - [`simulate`]: the in-process reference simulation.
#![warn(missing_docs)]

pub mod best_point;
pub mod cbf;
pub mod clcbs;
pub mod disk_path;
pub mod dubins;
pub mod formation;
pub mod geometry;
pub mod hybrid_astar;
pub mod reeds_shepp;
pub mod run;
pub mod safety;
pub mod scenario;
pub mod simulate;
pub mod turn;
