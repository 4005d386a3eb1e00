//! The path type: straight segments and circular arcs, continuous from start to goal.

use crate::geometry::{Point, Vector};

/// One piece of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathPiece {
    /// Straight segment.
    Segment {
        /// First point.
        from: Point,
        /// Last point.
        to: Point,
    },
    /// Arc of the circle (`centre`, `radius_m`) starting at angle `start_rad`, sweeping
    /// `sweep_rad` (positive = counter-clockwise).
    Arc {
        /// Centre of the circle.
        centre: Point,
        /// Radius of the circle, in metres.
        radius_m: f64,
        /// Angle of the first point, counter-clockwise from +x, in radians.
        start_rad: f64,
        /// Signed swept angle, in radians (positive = counter-clockwise).
        sweep_rad: f64,
    },
}

/// The point of the circle (`centre`, `radius_m`) at angle `angle_rad`.
fn circle_point(centre: &Point, radius_m: f64, angle_rad: f64) -> Point {
    let (sin, cos) = angle_rad.sin_cos();
    centre + radius_m * Vector::new(cos, sin)
}

impl PathPiece {
    /// First point of the piece.
    pub fn start(&self) -> Point {
        match self {
            Self::Segment { from, .. } => *from,
            Self::Arc {
                centre,
                radius_m,
                start_rad,
                ..
            } => circle_point(centre, *radius_m, *start_rad),
        }
    }

    /// Last point of the piece.
    pub fn end(&self) -> Point {
        match self {
            Self::Segment { to, .. } => *to,
            Self::Arc {
                centre,
                radius_m,
                start_rad,
                sweep_rad,
            } => circle_point(centre, *radius_m, start_rad + sweep_rad),
        }
    }

    /// Length of the piece, in metres.
    pub fn length_m(&self) -> f64 {
        match self {
            Self::Segment { from, to } => (to - from).norm(),
            Self::Arc {
                radius_m,
                sweep_rad,
                ..
            } => radius_m * sweep_rad.abs(),
        }
    }

    /// The point at fraction `t` of the piece's length (`0` = start, `1` = end; clamped).
    pub fn point_at_fraction(&self, t: f64) -> Point {
        let t = t.clamp(0.0, 1.0);
        match self {
            Self::Segment { from, to } => from + t * (to - from),
            Self::Arc {
                centre,
                radius_m,
                start_rad,
                sweep_rad,
            } => circle_point(centre, *radius_m, start_rad + t * sweep_rad),
        }
    }
}

/// A path made of segments and arcs, continuous from start to goal.
///
/// Paths returned by [`shortest_path`](super::shortest_path()) are exactly continuous (each
/// piece starts at the previous piece's [`PathPiece::end`], bit for bit), start exactly at
/// the requested start and end exactly at the requested goal. They are never empty: a path
/// from a point to itself is a single zero-length segment.
#[derive(Clone, Debug, PartialEq)]
pub struct DiskPath {
    /// The pieces, in travel order.
    pub pieces: Vec<PathPiece>,
    /// Where the path starts when `pieces` is empty.
    origin: Point,
}

impl DiskPath {
    /// A path made of `pieces`, starting at `origin` when `pieces` is empty (otherwise the
    /// first piece's start is the path's start).
    pub fn new(origin: Point, pieces: Vec<PathPiece>) -> Self {
        Self { pieces, origin }
    }

    /// The straight path from `from` to `to` (a single segment, possibly of zero length).
    pub fn straight(from: Point, to: Point) -> Self {
        Self::new(from, vec![PathPiece::Segment { from, to }])
    }

    /// Total length, in metres.
    pub fn length_m(&self) -> f64 {
        self.pieces.iter().map(PathPiece::length_m).sum()
    }

    /// First point of the path.
    pub fn start(&self) -> Point {
        self.pieces.first().map_or(self.origin, PathPiece::start)
    }

    /// Last point of the path.
    pub fn end(&self) -> Point {
        self.pieces.last().map_or(self.origin, PathPiece::end)
    }

    /// The first `max_length_m` metres of the path (a top speed's worth), or `None` when
    /// the path is no longer than that. The cut piece keeps its kind: an arc is cut on its
    /// circle, so the prefix ends on the path itself, never on a chord inside a disk.
    ///
    /// ```
    /// use shared::paths::disk_path::{DiskPath, PathPiece};
    /// use shared::geometry::Point;
    /// let quarter = PathPiece::Arc {
    ///     centre: Point::new(0.0, 0.0),
    ///     radius_m: 2.0,
    ///     start_rad: 0.0,
    ///     sweep_rad: std::f64::consts::FRAC_PI_2,
    /// };
    /// let path = DiskPath::new(Point::new(2.0, 0.0), vec![quarter]);
    /// let half = path.prefix(0.5 * path.length_m()).unwrap();
    /// let end = half.end();
    /// assert!((end.coords.norm() - 2.0).abs() < 1e-12, "on the circle");
    /// assert!((half.length_m() - 0.5 * path.length_m()).abs() < 1e-12);
    /// assert_eq!(path.prefix(10.0), None);
    /// ```
    pub fn prefix(&self, max_length_m: f64) -> Option<DiskPath> {
        let mut travelled_m = 0.0;
        for (i, piece) in self.pieces.iter().enumerate() {
            let piece_m = piece.length_m();
            if travelled_m + piece_m > max_length_m {
                let t = ((max_length_m - travelled_m) / piece_m).clamp(0.0, 1.0);
                let mut pieces = self.pieces[..i].to_vec();
                let cut = match *piece {
                    PathPiece::Segment { from, to } => PathPiece::Segment {
                        from,
                        to: from + t * (to - from),
                    },
                    PathPiece::Arc {
                        centre,
                        radius_m,
                        start_rad,
                        sweep_rad,
                    } => PathPiece::Arc {
                        centre,
                        radius_m,
                        start_rad,
                        sweep_rad: t * sweep_rad,
                    },
                };
                if t > 0.0 {
                    pieces.push(cut);
                }
                return Some(DiskPath::new(self.start(), pieces));
            }
            travelled_m += piece_m;
        }
        None
    }

    /// Polyline vertices following the path, start and end included, such that every chord
    /// stays within `max_chord_error_m` of the true arc (inscribed chords: vertices exactly
    /// on the arcs, so a chord cuts at most `max_chord_error_m` into an arc's disk).
    ///
    /// Segments contribute their end points only. `max_chord_error_m` below `1e-9` m (or
    /// NaN) is treated as `1e-9` m.
    pub fn polyline(&self, max_chord_error_m: f64) -> Vec<Point> {
        self.polyline_with_chords(max_chord_error_m, f64::INFINITY)
    }

    /// [`Self::polyline`] with every chord of an arc also at most `max_chord_m` long: the
    /// polyline a unicycle drives, which may stop only at a vertex where a chord cuts
    /// into an arc's disk, so short chords lose it little of a step.
    ///
    /// `max_chord_m` below `1e-9` m (or NaN) is treated as `1e-9` m; infinite: no limit.
    ///
    /// ```
    /// use shared::paths::disk_path::{DiskPath, PathPiece};
    /// use shared::geometry::Point;
    /// let quarter = PathPiece::Arc {
    ///     centre: Point::origin(),
    ///     radius_m: 1.0,
    ///     start_rad: 0.0,
    ///     sweep_rad: std::f64::consts::FRAC_PI_2,
    /// };
    /// let path = DiskPath::new(Point::new(1.0, 0.0), vec![quarter]);
    /// let points = path.polyline_with_chords(0.1, 0.05);
    /// assert!(points.windows(2).all(|w| (w[1] - w[0]).norm() <= 0.05 + 1e-12));
    /// assert!(points.iter().all(|p| (p.coords.norm() - 1.0).abs() < 1e-12), "on the arc");
    /// ```
    pub fn polyline_with_chords(&self, max_chord_error_m: f64, max_chord_m: f64) -> Vec<Point> {
        let error_m = max_chord_error_m.max(1e-9);
        let chord_m = max_chord_m.max(1e-9);
        let mut out = vec![self.start()];
        for piece in &self.pieces {
            match piece {
                PathPiece::Segment { to, .. } => out.push(*to),
                PathPiece::Arc {
                    radius_m,
                    sweep_rad,
                    ..
                } => {
                    // Sagitta of a chord spanning `step`: r (1 - cos(step / 2)).
                    let max_step_rad = if error_m >= *radius_m {
                        std::f64::consts::PI
                    } else {
                        (2.0 * (1.0 - error_m / radius_m).acos()).min(std::f64::consts::PI)
                    };
                    // A chord spanning `step` is 2 r sin(step / 2) long.
                    let max_step_rad = if chord_m >= 2.0 * radius_m {
                        max_step_rad
                    } else {
                        max_step_rad.min(2.0 * (0.5 * chord_m / radius_m).asin())
                    };
                    let n = chord_count(sweep_rad.abs(), max_step_rad);
                    for i in 1..=n {
                        out.push(piece.point_at_fraction(i as f64 / n as f64));
                    }
                }
            }
        }
        out
    }

    /// Points along the path at most `spacing_m` apart along the path (so also in
    /// straight-line distance), start and end included, every one exactly on the path.
    ///
    /// `spacing_m` below `1e-9` m (or NaN) is treated as `1e-9` m.
    pub fn sample(&self, spacing_m: f64) -> Vec<Point> {
        let spacing_m = spacing_m.max(1e-9);
        let mut out = vec![self.start()];
        for piece in &self.pieces {
            let n = chord_count(piece.length_m(), spacing_m);
            for i in 1..=n {
                out.push(piece.point_at_fraction(i as f64 / n as f64));
            }
        }
        out
    }
}

/// Number of equal steps, at least one, so that `total / steps <= max_step`.
fn chord_count(total: f64, max_step: f64) -> usize {
    let n = (total / max_step).ceil();
    if n.is_finite() && n >= 1.0 {
        n as usize
    } else {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polyline_vertices_lie_on_arcs_and_respect_the_chord_error() {
        let arc = PathPiece::Arc {
            centre: Point::new(1.0, 2.0),
            radius_m: 2.0,
            start_rad: 0.3,
            sweep_rad: -2.5,
        };
        let path = DiskPath::new(arc.start(), vec![arc]);
        for e in [1e-1, 1e-3, 1e-6] {
            let poly = path.polyline(e);
            assert_eq!(poly[0], path.start());
            assert_eq!(*poly.last().expect("vertices"), path.end());
            for w in poly.windows(2) {
                assert!(((w[0] - Point::new(1.0, 2.0)).norm() - 2.0).abs() < 1e-12);
                let mid = nalgebra::center(&w[0], &w[1]);
                assert!(2.0 - (mid - Point::new(1.0, 2.0)).norm() <= e + 1e-12);
            }
        }
    }
}
