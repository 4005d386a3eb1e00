//! Polylines: their length and the prefix of a given length (a move cut at the top
//! speed), and the distance between two of them (two moves of one parallel group).

use super::{Point, distance_point_segment};

/// The length of the polyline through `points`, in metres (0 for fewer than two).
///
/// ```
/// use shared::geometry::{Point, polyline_length_m};
/// let l = polyline_length_m(&[Point::new(0.0, 0.0), Point::new(3.0, 4.0), Point::new(3.0, 5.0)]);
/// assert_eq!(l, 6.0);
/// ```
pub fn polyline_length_m(points: &[Point]) -> f64 {
    points.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// The first `max_length_m` metres of the polyline through `points`, or `None` when the
/// polyline is no longer than that (it is its own prefix).
///
/// The prefix keeps every waypoint before the cut and ends at the point of the cut
/// segment at the remaining length, so it lies on the polyline and its length (summed
/// segment by segment, as [`polyline_length_m`] does) does not exceed `max_length_m` by
/// more than rounding.
///
/// ```
/// use shared::geometry::{Point, polyline_prefix};
/// let path = [Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(2.0, 2.0)];
/// let cut = polyline_prefix(&path, 3.0).unwrap();
/// assert_eq!(cut, vec![Point::new(0.0, 0.0), Point::new(2.0, 0.0), Point::new(2.0, 1.0)]);
/// assert_eq!(polyline_prefix(&path, 4.0), None);
/// ```
pub fn polyline_prefix(points: &[Point], max_length_m: f64) -> Option<Vec<Point>> {
    let mut travelled_m = 0.0;
    for (i, w) in points.windows(2).enumerate() {
        let segment_m = (w[1] - w[0]).norm();
        if travelled_m + segment_m > max_length_m {
            let left_m = (max_length_m - travelled_m).max(0.0);
            let mut prefix = points[..=i].to_vec();
            if left_m > 0.0 {
                // `left_m / segment_m < 1`: the cut lies strictly inside the segment.
                let cut = w[0] + (w[1] - w[0]) * (left_m / segment_m);
                prefix.push(cut);
            }
            return Some(prefix);
        }
        travelled_m += segment_m;
    }
    None
}

/// The smallest distance between a point of polyline `a` and a point of polyline `b`, in
/// metres (`f64::INFINITY` when either is empty). A polyline of one point is that point.
pub fn distance_polyline_polyline(a: &[Point], b: &[Point]) -> f64 {
    let segments = |p: &[Point]| -> Vec<(Point, Point)> {
        match p {
            [] => Vec::new(),
            [only] => vec![(*only, *only)],
            _ => p.windows(2).map(|w| (w[0], w[1])).collect(),
        }
    };
    let (sa, sb) = (segments(a), segments(b));
    let mut best = f64::INFINITY;
    for (a0, a1) in &sa {
        for (b0, b1) in &sb {
            best = best.min(distance_segment_segment(a0, a1, b0, b1));
        }
    }
    best
}

/// The smallest distance between segment `a0 a1` and segment `b0 b1`, in metres.
pub fn distance_segment_segment(a0: &Point, a1: &Point, b0: &Point, b1: &Point) -> f64 {
    if segments_cross(a0, a1, b0, b1) {
        return 0.0;
    }
    distance_point_segment(a0, b0, b1)
        .min(distance_point_segment(a1, b0, b1))
        .min(distance_point_segment(b0, a0, a1))
        .min(distance_point_segment(b1, a0, a1))
}

/// Whether two segments cross properly (each separates the other's ends).
fn segments_cross(a0: &Point, a1: &Point, b0: &Point, b1: &Point) -> bool {
    let side = |p: &Point, q: &Point, r: &Point| (q - p).perp(&(r - p));
    let (d1, d2) = (side(b0, b1, a0), side(b0, b1, a1));
    let (d3, d4) = (side(a0, a1, b0), side(a0, a1, b1));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prefix_is_never_longer_than_asked() {
        let path = [
            Point::new(0.1, 0.3),
            Point::new(1.7, 2.9),
            Point::new(-0.4, 5.5),
            Point::new(3.3, 3.3),
        ];
        let total = polyline_length_m(&path);
        for k in 1..100 {
            let max = total * f64::from(k) / 100.0;
            let cut = polyline_prefix(&path, max).expect("shorter than the path");
            assert!(polyline_length_m(&cut) <= max + 1e-12, "k = {k}");
            assert!((polyline_length_m(&cut) - max).abs() < 1e-9, "k = {k}");
            assert_eq!(cut[0], path[0]);
        }
        assert_eq!(polyline_prefix(&path, total + 1e-9), None);
    }

    #[test]
    fn crossing_segments_are_at_distance_zero() {
        let d = distance_segment_segment(
            &Point::new(0.0, 0.0),
            &Point::new(2.0, 2.0),
            &Point::new(0.0, 2.0),
            &Point::new(2.0, 0.0),
        );
        assert_eq!(d, 0.0);
        let apart = distance_polyline_polyline(
            &[Point::new(0.0, 0.0), Point::new(1.0, 0.0)],
            &[
                Point::new(0.5, 2.0),
                Point::new(3.0, 2.0),
                Point::new(3.0, 0.5),
            ],
        );
        // Nearest: the first point of B above the segment A, 2 m up.
        assert_eq!(apart, 2.0);
    }
}
