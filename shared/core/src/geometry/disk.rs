//! A closed disk, and the distance from a point to a segment.

use super::{Point, Vector};

/// A closed disk: the set of points within `radius_m` of `centre`.
///
/// Controllers work with *inflated* disks: an obstacle or another agent grown by the moving
/// agent's own radius, so that the moving agent becomes a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Centre of the disk.
    pub centre: Point,
    /// Radius of the disk, in metres (strictly positive).
    pub radius_m: f64,
}

impl Disk {
    /// A disk of radius `radius_m` around (`x_m`, `y_m`).
    pub fn new(x_m: f64, y_m: f64, radius_m: f64) -> Self {
        Self {
            centre: Point::new(x_m, y_m),
            radius_m,
        }
    }

    /// The same disk with its radius grown by `by_m`.
    pub fn inflated(&self, by_m: f64) -> Self {
        Self {
            centre: self.centre,
            radius_m: self.radius_m + by_m,
        }
    }

    /// Signed distance from `p` to the disk's boundary: negative inside, zero on it.
    pub fn signed_distance_m(&self, p: &Point) -> f64 {
        (p - self.centre).norm() - self.radius_m
    }

    /// The point of the boundary circle at angle `angle_rad` (counter-clockwise from +x).
    pub fn boundary_point(&self, angle_rad: f64) -> Point {
        self.centre + self.radius_m * Vector::new(angle_rad.cos(), angle_rad.sin())
    }

    /// Smallest distance from the segment `a`-`b` to the centre, minus the radius:
    /// negative when the segment enters the open disk.
    pub fn signed_distance_to_segment_m(&self, a: &Point, b: &Point) -> f64 {
        distance_point_segment(&self.centre, a, b) - self.radius_m
    }
}

/// Distance from `p` to the segment `a`-`b`.
pub fn distance_point_segment(p: &Point, a: &Point, b: &Point) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 == 0.0 {
        return (p - a).norm();
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    (p - (a + t * ab)).norm()
}
