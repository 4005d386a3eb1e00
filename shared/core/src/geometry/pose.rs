//! A pose: a position and a heading.

use super::Point;

/// A pose in SE(2): position and heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position x, in metres.
    pub x_m: f64,
    /// Position y, in metres.
    pub y_m: f64,
    /// Heading, counter-clockwise from +x, in radians.
    pub heading_rad: f64,
}

impl Pose {
    /// A pose at (`x_m`, `y_m`) facing `heading_rad`.
    pub fn new(x_m: f64, y_m: f64, heading_rad: f64) -> Self {
        Self {
            x_m,
            y_m,
            heading_rad,
        }
    }

    /// The position as a point.
    pub fn position(&self) -> Point {
        Point::new(self.x_m, self.y_m)
    }
}

/// Wrap an angle into `(-pi, pi]`.
pub fn wrap_angle_rad(angle_rad: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut a = angle_rad % two_pi;
    if a <= -std::f64::consts::PI {
        a += two_pi;
    } else if a > std::f64::consts::PI {
        a -= two_pi;
    }
    a
}
