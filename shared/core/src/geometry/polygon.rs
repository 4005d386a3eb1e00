//! Simple polygons: obstacles given by their corners, checked to be simple, kept
//! anticlockwise.

use super::{Point, distance_point_segment, distance_segment_segment};

/// Why corners do not make a simple polygon.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolygonError {
    /// Fewer than three corners.
    #[error("a polygon needs at least 3 vertices, got {count}")]
    TooFewVertices {
        /// How many were given.
        count: usize,
    },
    /// A coordinate that is NaN or infinite.
    #[error("vertex {index} is not finite")]
    NotFinite {
        /// The vertex, from 0.
        index: usize,
    },
    /// A corner equal to the one after it.
    #[error("vertex {index} repeats the vertex after it")]
    RepeatedVertex {
        /// The vertex, from 0.
        index: usize,
    },
    /// Two sides cross or touch, or a side folds back on the one before it.
    #[error("side {first} (vertices {first}-{}) meets side {second}: the polygon crosses itself", first + 1)]
    SelfIntersecting {
        /// The first side, from 0 (side i joins vertex i to vertex i + 1).
        first: usize,
        /// The second side.
        second: usize,
    },
    /// All corners on one line.
    #[error("the polygon has no area: its vertices are collinear")]
    NoArea,
}

/// A simple polygon (its sides meet only at shared corners), stored anticlockwise
/// whichever way it was given, convex or not.
///
/// ```
/// use shared::geometry::{Point, Polygon};
/// // An L, given clockwise: stored anticlockwise, 3 m^2.
/// let l = Polygon::new(vec![
///     Point::new(0.0, 0.0), Point::new(0.0, 2.0), Point::new(1.0, 2.0),
///     Point::new(1.0, 1.0), Point::new(2.0, 1.0), Point::new(2.0, 0.0),
/// ]).unwrap();
/// assert_eq!(l.area_m2(), 3.0);
/// assert!(l.contains(&Point::new(0.5, 1.5)) && !l.contains(&Point::new(1.5, 1.5)));
/// assert_eq!(l.distance_m(&Point::new(1.5, 1.5)), 0.5);
/// // A bow tie crosses itself.
/// let bow = vec![Point::new(0.0, 0.0), Point::new(1.0, 1.0), Point::new(1.0, 0.0), Point::new(0.0, 1.0)];
/// assert!(Polygon::new(bow).is_err());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    vertices: Vec<Point>,
    /// The corners, in increasing order, where this polygon meets a neighbour along a
    /// side (a piece of a map cut into tiles): no path bends round them, since the
    /// obstacle goes on beyond them. Empty for a polygon given whole.
    seams: Vec<usize>,
}

/// Twice the signed area of the polygon through `v` (anticlockwise positive).
fn area2(v: &[Point]) -> f64 {
    let n = v.len();
    (0..n)
        .map(|i| v[i].coords.perp(&v[(i + 1) % n].coords))
        .sum()
}

impl Polygon {
    /// The polygon through `vertices` in order (the last joins the first), checked to be
    /// simple; `O(n^2)` in the number of vertices.
    pub fn new(mut vertices: Vec<Point>) -> Result<Self, PolygonError> {
        let n = vertices.len();
        if n < 3 {
            return Err(PolygonError::TooFewVertices { count: n });
        }
        if let Some(index) = vertices
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(PolygonError::NotFinite { index });
        }
        if let Some(index) = (0..n).find(|&i| vertices[i] == vertices[(i + 1) % n]) {
            return Err(PolygonError::RepeatedVertex { index });
        }
        let side = |i: usize| (vertices[i], vertices[(i + 1) % n]);
        for i in 0..n {
            let (a0, a1) = side(i);
            // The next side must not fold back along this one.
            let (_, b1) = side((i + 1) % n);
            let (u, w) = (a1 - a0, b1 - a1);
            if u.perp(&w) == 0.0 && u.dot(&w) < 0.0 {
                return Err(PolygonError::SelfIntersecting {
                    first: i,
                    second: (i + 1) % n,
                });
            }
            // Sides that share no corner must not meet at all.
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue;
                }
                let (b0, b1) = side(j);
                if distance_segment_segment(&a0, &a1, &b0, &b1) == 0.0 {
                    return Err(PolygonError::SelfIntersecting {
                        first: i,
                        second: j,
                    });
                }
            }
        }
        let twice = area2(&vertices);
        if twice == 0.0 {
            return Err(PolygonError::NoArea);
        }
        if twice < 0.0 {
            vertices.reverse();
        }
        Ok(Self {
            vertices,
            seams: Vec::new(),
        })
    }

    /// The polygon through `vertices`, which the caller knows to be simple (three corners
    /// or more, finite, no side meeting another but its neighbours at their shared
    /// corners), without the `O(n^2)` check of [`Polygon::new`]: for the outlines of a
    /// map's cells, simple by construction. Stored anticlockwise.
    /// `seam(i)` tells whether corner `i` (as given) is a seam ([`Polygon::seams`]).
    pub(crate) fn new_trusted_simple(
        mut vertices: Vec<Point>,
        seam: impl Fn(usize) -> bool,
    ) -> Self {
        let n = vertices.len();
        let mut seams: Vec<usize> = (0..n).filter(|&i| seam(i)).collect();
        if area2(&vertices) < 0.0 {
            vertices.reverse();
            seams = seams.iter().rev().map(|&i| n - 1 - i).collect();
        }
        Self { vertices, seams }
    }

    /// The corners where this polygon meets a neighbour along a side, in increasing
    /// order: a map's piece cut from the rest of a wall there. Empty for a polygon given
    /// whole.
    pub fn seams(&self) -> &[usize] {
        &self.seams
    }

    /// The same polygon moved by `by` (its corners in the same order: a translation keeps
    /// it simple and anticlockwise).
    pub fn translated(&self, by: &super::Vector) -> Self {
        Self {
            vertices: self.vertices.iter().map(|v| v + by).collect(),
            seams: self.seams.clone(),
        }
    }

    /// The corners, anticlockwise.
    pub fn vertices(&self) -> &[Point] {
        &self.vertices
    }

    /// The sides, each from a corner to the next (the polygon on their left).
    pub fn sides(&self) -> impl Iterator<Item = (Point, Point)> + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| (self.vertices[i], self.vertices[(i + 1) % n]))
    }

    /// The corners of its bounding box, `(min, max)`.
    pub fn bounding_box(&self) -> (Point, Point) {
        let first = self.vertices[0];
        self.vertices.iter().fold((first, first), |(min, max), v| {
            (
                Point::new(min.x.min(v.x), min.y.min(v.y)),
                Point::new(max.x.max(v.x), max.y.max(v.y)),
            )
        })
    }

    /// The area, square metres.
    pub fn area_m2(&self) -> f64 {
        0.5 * area2(&self.vertices)
    }

    /// Whether `p` lies inside or on the boundary.
    pub fn contains(&self, p: &Point) -> bool {
        if self
            .sides()
            .any(|(a, b)| distance_point_segment(p, &a, &b) == 0.0)
        {
            return true;
        }
        // Even-odd rule, a ray towards +x.
        self.sides()
            .filter(|(a, b)| {
                (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x)
            })
            .count()
            % 2
            == 1
    }

    /// Distance from `p` to the polygon, 0 inside it.
    pub fn distance_m(&self, p: &Point) -> f64 {
        self.signed_distance_m(p).max(0.0)
    }

    /// Signed distance from `p` to the polygon's boundary: positive outside, negative
    /// inside.
    pub fn signed_distance_m(&self, p: &Point) -> f64 {
        let to_sides_m = self
            .sides()
            .map(|(a, b)| distance_point_segment(p, &a, &b))
            .fold(f64::INFINITY, f64::min);
        if self.contains(p) {
            -to_sides_m
        } else {
            to_sides_m
        }
    }

    /// Smallest distance from the segment `a`-`b` to the polygon, 0 when it enters it.
    pub fn distance_to_segment_m(&self, a: &Point, b: &Point) -> f64 {
        if self.contains(a) || self.contains(b) {
            return 0.0;
        }
        self.sides()
            .map(|(c, d)| distance_segment_segment(a, b, &c, &d))
            .fold(f64::INFINITY, f64::min)
    }

    /// The convex corners that are not [seams](Polygon::seams): the only corners a
    /// shortest path can bend round (at a seam the obstacle goes on in a neighbour).
    pub fn bend_corners(&self) -> impl Iterator<Item = usize> + '_ {
        self.convex_corners()
            .filter(|i| self.seams.binary_search(i).is_err())
    }

    /// The corners where the polygon is convex (the interior angle below 180 degrees):
    /// the only corners round which an inflated polygon has an arc.
    pub fn convex_corners(&self) -> impl Iterator<Item = usize> + '_ {
        let n = self.vertices.len();
        (0..n).filter(move |&i| {
            let (prev, here, next) = (
                self.vertices[(i + n - 1) % n],
                self.vertices[i],
                self.vertices[(i + 1) % n],
            );
            (here - prev).perp(&(next - here)) > 0.0
        })
    }
}
