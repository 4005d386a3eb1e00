//! How far from free space a point may be and still count as free.

/// How far inside a disk (or outside the field) a start, a goal or any point of a path may
/// be, in metres.
pub const FREE_TOLERANCE_M: f64 = 1e-9;
