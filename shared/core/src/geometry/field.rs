//! The rectangular field.

use super::Point;

/// The playing field: the closed rectangle `[0, width_m] x [0, height_m]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    /// Extent along x, in metres.
    pub width_m: f64,
    /// Extent along y, in metres.
    pub height_m: f64,
}

impl Field {
    /// A field of the given size.
    pub fn new(width_m: f64, height_m: f64) -> Self {
        Self { width_m, height_m }
    }

    /// Whether `p` lies in the field, allowing `tolerance_m` outside its edges.
    pub fn contains(&self, p: &Point, tolerance_m: f64) -> bool {
        p.x >= -tolerance_m
            && p.y >= -tolerance_m
            && p.x <= self.width_m + tolerance_m
            && p.y <= self.height_m + tolerance_m
    }

    /// Distance from `p` to the nearest edge, negative outside the field.
    pub fn signed_inset_m(&self, p: &Point) -> f64 {
        p.x.min(p.y)
            .min(self.width_m - p.x)
            .min(self.height_m - p.y)
    }

    /// The nearest point of the field to `p` (`p` itself when inside).
    pub fn clamp(&self, p: &Point) -> Point {
        Point::new(p.x.clamp(0.0, self.width_m), p.y.clamp(0.0, self.height_m))
    }

    /// The four corners, counter-clockwise from the origin.
    pub fn corners(&self) -> [Point; 4] {
        [
            Point::new(0.0, 0.0),
            Point::new(self.width_m, 0.0),
            Point::new(self.width_m, self.height_m),
            Point::new(0.0, self.height_m),
        ]
    }
}
