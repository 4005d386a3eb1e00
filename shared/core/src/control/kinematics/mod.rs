//! Moves that a robot with a heading can drive, and their checks.
//!
//! A holonomic agent follows its planned polyline as it is. A differential-drive agent
//! (`unicycle.rs`) follows the same polyline by turning in place at each vertex and
//! driving straight along each segment: a disk turning in place sweeps no new ground, so
//! the polyline's safety checks hold unchanged for it, and only the time it takes
//! differs. The step's time is shared by driving and turning. A car-like agent
//! (`car.rs`) drives arcs no tighter than its turning radius; its polyline is the arcs'
//! chords, each of which stands for exactly one arc, and the safety checks add each
//! chord's error to its radius.

mod car;
mod unicycle;

pub use car::{
    CAR_CHORD_TURN_RAD, CAR_HEADING_TOLERANCE_RAD, CAR_TURN_TOLERANCE_RAD, CarLimits, CarMoveError,
    CarPiece, MIN_SEGMENT_M, MIN_SEGMENT_PER_M, car_piece, car_waypoints, check_car_move,
    curve_prefix,
};
pub use unicycle::{
    UnicycleLimits, UnicycleMove, drive_unicycle, driving_headings, unicycle_step_share,
};
