//! A polygon obstacle grown by a radius: the set of points nearer than the radius to the
//! polygon (the Minkowski sum of the polygon and an open disk).

use super::{Disk, Point, Vector};
use super::{Polygon, PolygonError};

/// A polygon grown by `radius_m`: a point is blocked when it is inside the polygon or
/// nearer than `radius_m` to it; a point exactly `radius_m` away is free.
///
/// Its boundary is made of two kinds of pieces only, which is what makes the geometry
/// on it exact:
/// - pieces of the **offset sides**: each side moved out by `radius_m` along its outward
///   normal ([`InflatedPolygon::offset_sides`]);
/// - arcs of the **corner circles**: a circle of `radius_m` round each convex corner
///   ([`InflatedPolygon::corner_disks`]); a reflex corner has no arc, its two offset sides
///   cross instead.
///
/// ```
/// use shared::geometry::{InflatedPolygon, Point};
/// let square = vec![Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(1.0, 1.0), Point::new(0.0, 1.0)];
/// let grown = InflatedPolygon::new(square, 0.5).unwrap();
/// // Beside a side the growth is flat; beyond a corner it is round.
/// assert_eq!(grown.signed_distance_m(&Point::new(2.0, 0.5)), 0.5);
/// assert!((grown.signed_distance_m(&Point::new(2.0, 2.0)) - (2f64.sqrt() - 0.5)).abs() < 1e-12);
/// // Deep inside: the depth counts from the grown boundary.
/// assert_eq!(grown.signed_distance_m(&Point::new(0.5, 0.5)), -1.0);
/// assert_eq!(grown.corner_disks().count(), 4);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct InflatedPolygon {
    polygon: Polygon,
    radius_m: f64,
    min: Point,
    max: Point,
}

impl InflatedPolygon {
    /// The polygon through `vertices` (either orientation, checked to be simple) grown
    /// by `radius_m` (finite, `>= 0`; a negative or non-finite radius counts as 0).
    pub fn new(vertices: Vec<Point>, radius_m: f64) -> Result<Self, PolygonError> {
        Ok(Self::from_polygon(Polygon::new(vertices)?, radius_m))
    }

    /// `polygon` grown by `radius_m` (a negative or non-finite radius counts as 0).
    pub fn from_polygon(polygon: Polygon, radius_m: f64) -> Self {
        let radius_m = if radius_m.is_finite() && radius_m > 0.0 {
            radius_m
        } else {
            0.0
        };
        let grow = Vector::new(radius_m, radius_m);
        let (min, max) = polygon.bounding_box();
        Self {
            polygon,
            radius_m,
            min: min - grow,
            max: max + grow,
        }
    }

    /// The same polygon grown by `by_m` more.
    pub fn inflated(&self, by_m: f64) -> Self {
        Self::from_polygon(self.polygon.clone(), self.radius_m + by_m)
    }

    /// The polygon before growing.
    pub fn polygon(&self) -> &Polygon {
        &self.polygon
    }

    /// How far it is grown, metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The corners of its bounding box, `(min, max)`.
    pub fn bounding_box(&self) -> (Point, Point) {
        (self.min, self.max)
    }

    /// Whether its bounding box meets the box `[min, max]`.
    pub fn box_meets(&self, min: &Point, max: &Point) -> bool {
        self.min.x <= max.x && self.min.y <= max.y && min.x <= self.max.x && min.y <= self.max.y
    }

    /// Signed distance from `p` to the grown boundary: positive outside, negative inside
    /// (then minus the depth below the boundary).
    pub fn signed_distance_m(&self, p: &Point) -> f64 {
        self.polygon.signed_distance_m(p) - self.radius_m
    }

    /// Whether the segment `a`-`b` meets its bounding box (`false`: the segment is clear
    /// of it by more than nothing): a quick test before the exact one.
    pub fn segment_meets_box(&self, a: &Point, b: &Point) -> bool {
        // Clip the segment's parameter range [0, 1] against the box's two slabs.
        let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
        for (p, d, lo, hi) in [
            (a.x, b.x - a.x, self.min.x, self.max.x),
            (a.y, b.y - a.y, self.min.y, self.max.y),
        ] {
            if d == 0.0 {
                if p < lo || p > hi {
                    return false;
                }
                continue;
            }
            let (u, v) = ((lo - p) / d, (hi - p) / d);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
            if t0 > t1 {
                return false;
            }
        }
        true
    }

    /// Signed distance from the segment `a`-`b` to the grown boundary: its smallest
    /// distance to the polygon minus the radius (a segment that enters the polygon gives
    /// at most `-radius_m`).
    pub fn signed_distance_to_segment_m(&self, a: &Point, b: &Point) -> f64 {
        if self.polygon.contains(a) || self.polygon.contains(b) {
            return self.signed_distance_m(a).min(self.signed_distance_m(b));
        }
        self.polygon.distance_to_segment_m(a, b) - self.radius_m
    }

    /// The circles round its convex corners, of its radius: the only arcs of its
    /// boundary, and the only places a shortest path can bend round it.
    pub fn corner_disks(&self) -> impl Iterator<Item = Disk> + '_ {
        let v = self.polygon.vertices();
        self.polygon
            .convex_corners()
            .map(move |i| Disk::new(v[i].x, v[i].y, self.radius_m))
    }

    /// The circles round its [bend corners](Polygon::bend_corners): the corner circles a
    /// shortest path or a nearest free point can use. A circle round a seam lies inside
    /// the neighbour's growth but for one point of an offset side.
    pub fn bend_disks(&self) -> impl Iterator<Item = Disk> + '_ {
        let v = self.polygon.vertices();
        self.polygon
            .bend_corners()
            .map(move |i| Disk::new(v[i].x, v[i].y, self.radius_m))
    }

    /// Its sides moved out by its radius, each as `(start, end)`, anticlockwise: the only
    /// straight pieces of its boundary lie on them.
    pub fn offset_sides(&self) -> impl Iterator<Item = (Point, Point)> + '_ {
        self.polygon.sides().map(move |(a, b)| {
            let along = b - a;
            // The polygon is anticlockwise, so its outside is on the right of each side.
            let outward = Vector::new(along.y, -along.x) / along.norm();
            (a + self.radius_m * outward, b + self.radius_m * outward)
        })
    }
}
