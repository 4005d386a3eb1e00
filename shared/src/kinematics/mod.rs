//! Moves that a robot with a heading can drive, and their checks.
//!
//! A holonomic agent follows its planned polyline as it is. A differential-drive agent
//! (`unicycle.rs`) follows the same polyline by turning in place at each vertex and
//! driving straight along each segment: a disk turning in place sweeps no new ground, so
//! the polyline's safety checks hold unchanged for it, and only the time it takes
//! differs. The step's time is shared by driving and turning.

mod unicycle;

pub use unicycle::{
    UnicycleLimits, UnicycleMove, drive_unicycle, driving_headings, unicycle_step_share,
};
