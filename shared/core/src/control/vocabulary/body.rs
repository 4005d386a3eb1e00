//! A body in the plane, as a controller sees the other agents.

use crate::geometry::Point;

/// A body in the plane: a disk at a position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Centre of the body.
    pub position: Point,
    /// Radius of the body, in metres.
    pub radius_m: f64,
}
