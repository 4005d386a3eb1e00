//! Polylines: their length and the prefix of a given length (a move cut at the top
//! speed), and the distance between two of them: anywhere (two moves of one parallel
//! group, whose timing is not known) or at the same time (two moves of ORCA's own model,
//! made at once at constant speeds).

use super::{Point, Vector, distance_point_segment};

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

/// The lengths along the polyline `points` up to each of its points (0 first).
fn cumulative_lengths_m(points: &[Point]) -> Vec<f64> {
    let mut lengths_m = Vec::with_capacity(points.len());
    let mut sum_m = 0.0;
    lengths_m.push(0.0);
    for w in points.windows(2) {
        sum_m += (w[1] - w[0]).norm();
        lengths_m.push(sum_m);
    }
    lengths_m
}

/// Where a body that runs through the polyline `points` at a constant speed, from its
/// first point at time 0 to its last at time 1, is at time `t` (`lengths_m`: from
/// [`cumulative_lengths_m`]; a polyline of no length is its first point throughout).
fn position_at(points: &[Point], lengths_m: &[f64], t: f64) -> Point {
    let total_m = lengths_m.last().copied().unwrap_or(0.0);
    if total_m <= 0.0 {
        return points[0];
    }
    let at_m = t.clamp(0.0, 1.0) * total_m;
    for (i, w) in points.windows(2).enumerate() {
        let (from_m, to_m) = (lengths_m[i], lengths_m[i + 1]);
        if at_m <= to_m && to_m > from_m {
            return w[0] + (w[1] - w[0]) * ((at_m - from_m) / (to_m - from_m));
        }
    }
    points[points.len() - 1]
}

/// How body `a` stands from body `b` while both move at once, as straight pieces: each
/// body runs through its polyline at a constant speed, from its first point to its last
/// over the same time (a polyline of one point stands still), and between two corners of
/// either, `a - b` moves straight. Each piece is `(from, to)`; none when either polyline
/// is empty. The two bodies' closest approach is the least distance from the origin to a
/// piece ([`distance_at_the_same_time_m`]).
///
/// ```
/// use shared::geometry::{Point, Vector, relative_motion};
/// let a = [Point::new(0.0, 0.0), Point::new(2.0, 0.0)];
/// let b = [Point::new(0.0, 1.0)];
/// assert_eq!(relative_motion(&a, &b), vec![(Vector::new(0.0, -1.0), Vector::new(2.0, -1.0))]);
/// ```
pub fn relative_motion(a: &[Point], b: &[Point]) -> Vec<(Vector, Vector)> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let (la, lb) = (cumulative_lengths_m(a), cumulative_lengths_m(b));
    // The times at which either body turns a corner.
    let mut times: Vec<f64> = vec![0.0, 1.0];
    for (p, l) in [(a, &la), (b, &lb)] {
        let total_m = l.last().copied().unwrap_or(0.0);
        if total_m > 0.0 && p.len() > 2 {
            times.extend(l[1..l.len() - 1].iter().map(|at_m| at_m / total_m));
        }
    }
    times.sort_by(f64::total_cmp);
    times.dedup();
    let apart = |t: f64| position_at(a, &la, t) - position_at(b, &lb, t);
    times
        .windows(2)
        .map(|w| (apart(w[0]), apart(w[1])))
        .collect()
}

/// The smallest distance between two bodies moving at once, in metres: each runs through
/// its polyline at a constant speed, from its first point to its last over the same time
/// (a polyline of one point stands still; see [`relative_motion`]); `f64::INFINITY` when
/// either is empty. Never less than [`distance_polyline_polyline`], which also counts
/// the places one body passes before or after the other.
///
/// ```
/// use shared::geometry::{Point, distance_at_the_same_time_m, distance_polyline_polyline};
/// // Two bodies crossing the same point, one halfway through the step, the other at its end.
/// let a = [Point::new(-1.0, 0.0), Point::new(1.0, 0.0)];
/// let b = [Point::new(0.0, -2.0), Point::new(0.0, 0.0)];
/// assert_eq!(distance_polyline_polyline(&a, &b), 0.0);
/// assert!((distance_at_the_same_time_m(&a, &b) - 2f64.sqrt() / 2.0).abs() < 1e-12);
/// ```
pub fn distance_at_the_same_time_m(a: &[Point], b: &[Point]) -> f64 {
    relative_motion(a, b)
        .iter()
        .map(|(from, to)| {
            distance_point_segment(&Point::origin(), &Point::from(*from), &Point::from(*to))
        })
        .fold(f64::INFINITY, f64::min)
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

    /// Random polylines of one to four points in a 4 m square, from `seed`.
    fn random_polyline(seed: &mut u64) -> Vec<Point> {
        let mut next = || {
            // xorshift: enough spread for a test, no dependency.
            *seed ^= *seed << 13;
            *seed ^= *seed >> 7;
            *seed ^= *seed << 17;
            (*seed % 10_000) as f64 / 2_500.0
        };
        let n = 1 + (next() as usize % 4);
        (0..n).map(|_| Point::new(next(), next())).collect()
    }

    #[test]
    fn the_distance_at_the_same_time_is_the_least_of_the_sampled_instants() {
        let mut seed = 0x9e37_79b9_7f4a_7c15;
        for case in 0..500 {
            let (a, b) = (random_polyline(&mut seed), random_polyline(&mut seed));
            let (la, lb) = (cumulative_lengths_m(&a), cumulative_lengths_m(&b));
            let d = distance_at_the_same_time_m(&a, &b);
            // Never below the distance anywhere, and reached: within what 2 000 samples of
            // the time can miss (both bodies move at most their lengths over the step).
            assert!(
                d >= distance_polyline_polyline(&a, &b) - 1e-12,
                "case {case}"
            );
            let samples = 2_000;
            let sampled = (0..=samples)
                .map(|k| {
                    let t = f64::from(k) / f64::from(samples);
                    (position_at(&a, &la, t) - position_at(&b, &lb, t)).norm()
                })
                .fold(f64::INFINITY, f64::min);
            let step_m = (la.last().unwrap() + lb.last().unwrap()) / f64::from(samples);
            assert!(
                d <= sampled + 1e-12,
                "case {case}: {d} above a sample {sampled}"
            );
            assert!(
                d >= sampled - step_m - 1e-12,
                "case {case}: {d} far below {sampled}"
            );
        }
    }

    #[test]
    fn a_body_standing_still_is_met_anywhere_the_other_passes() {
        let still = [Point::new(1.0, 1.0)];
        let path = [
            Point::new(0.0, 0.0),
            Point::new(2.0, 0.0),
            Point::new(2.0, 2.0),
        ];
        let (now, anywhere) = (
            distance_at_the_same_time_m(&path, &still),
            distance_polyline_polyline(&path, &still),
        );
        assert!((now - anywhere).abs() < 1e-12, "{now} against {anywhere}");
        assert_eq!(distance_at_the_same_time_m(&[], &still), f64::INFINITY);
    }
}
