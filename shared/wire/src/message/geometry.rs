//! Points and poses as they cross the wire.

use iceoryx2::prelude::*;
use shared::geometry::{Point, Pose};

/// A point on the wire.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WirePoint")]
pub struct WirePoint {
    /// x, in metres.
    pub x_m: f64,
    /// y, in metres.
    pub y_m: f64,
}

impl From<Point> for WirePoint {
    fn from(p: Point) -> Self {
        Self { x_m: p.x, y_m: p.y }
    }
}

impl From<WirePoint> for Point {
    fn from(p: WirePoint) -> Self {
        Point::new(p.x_m, p.y_m)
    }
}

/// A pose on the wire.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WirePose")]
pub struct WirePose {
    /// x, in metres.
    pub x_m: f64,
    /// y, in metres.
    pub y_m: f64,
    /// Heading, in radians.
    pub heading_rad: f64,
}

impl From<Pose> for WirePose {
    fn from(p: Pose) -> Self {
        Self {
            x_m: p.x_m,
            y_m: p.y_m,
            heading_rad: p.heading_rad,
        }
    }
}

impl From<WirePose> for Pose {
    fn from(p: WirePose) -> Self {
        Pose::new(p.x_m, p.y_m, p.heading_rad)
    }
}
