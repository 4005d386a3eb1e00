//! The formation controller's library: every algorithm, no I/O loop and no transport
//! (the messages between processes are in the `wire` crate, `shared/wire`).
//!
//! The modules stand in layers, each built on those before it:
//! - [`geometry`]: points, poses, disks, polygons, the field, spatial indexes, free space;
//! - [`paths`]: shortest paths among obstacles (for a point among disks and polygons,
//!   curvature-bounded: Reeds-Shepp, Dubins) and the centre's Hybrid A* planner;
//! - [`control`]: what one agent decides in its turn: the shared vocabulary, the
//!   formation's slots, the exact best point (Theorem 1), tracking, kinematics, the safety
//!   invariant, the turn request and the controllers;
//! - [`world`]: what a scenario puts round the formation: the scenario model and its
//!   validation, maps, moving obstacles, the centre's course, sensing, parallel groups;
//! - [`run`]: the step engine, the world a turn reads, the record and its referee, the
//!   in-process reference simulation.
//!
//! One exception to the order, kept on purpose: a turn ([`control::turn`]) reads the
//! scenario's map and the moving obstacles of [`world`], the things it plans round. The
//! test `module_graph` checks the order and this exception.
//!
//! Beside the layers, two helpers for files a user hands in or gets back:
//! [`input_file`] (reading with a size bound that holds for devices, FIFOs and sparse
//! files) and [`output_file`] (writing into a folder that may hold someone else's links).
#![warn(missing_docs)]

pub mod control;
pub mod geometry;
pub mod input_file;
mod ordered;
pub mod output_file;
pub mod paths;
pub mod run;
pub mod world;
