//! Where circles cross circles and lines.

use super::{Point, Vector};

/// The points where the circles of radius `r1_m` around `c1` and `r2_m` around `c2` cross.
///
/// `None` when the circles do not meet (apart, or one strictly inside the other) or are
/// concentric. Tangent circles give their touching point twice. The two points are
/// ordered: the first lies to the left of the direction `c1 -> c2`.
pub fn circle_circle_intersections(
    c1: &Point,
    r1_m: f64,
    c2: &Point,
    r2_m: f64,
) -> Option<[Point; 2]> {
    let between = c2 - c1;
    let distance_m = between.norm();
    // Written so that NaN inputs give `None`.
    let circles_cross =
        distance_m > 0.0 && distance_m <= r1_m + r2_m && distance_m >= (r1_m - r2_m).abs();
    if !circles_cross {
        return None;
    }
    // Signed distance from c1, along c1 -> c2, to the chord through the crossings.
    let along_m = (distance_m * distance_m + r1_m * r1_m - r2_m * r2_m) / (2.0 * distance_m);
    // (r1 - a)(r1 + a) loses less precision than r1^2 - a^2; rounding may push it below
    // zero at a tangency.
    let half_chord_m = ((r1_m - along_m) * (r1_m + along_m)).max(0.0).sqrt();
    let axis = between / distance_m;
    let normal = Vector::new(-axis.y, axis.x);
    let foot = c1 + along_m * axis;
    Some([foot + half_chord_m * normal, foot - half_chord_m * normal])
}

/// The points where the circle of radius `radius_m` around `centre` crosses the line
/// through `line_point` with direction `line_direction` (any non-zero length).
///
/// `None` when the line misses the circle or the direction is zero. A tangent line gives
/// its touching point twice. The points are ordered along `line_direction`.
pub fn circle_line_intersections(
    centre: &Point,
    radius_m: f64,
    line_point: &Point,
    line_direction: &Vector,
) -> Option<[Point; 2]> {
    let length2 = line_direction.norm_squared();
    let has_direction = length2 > 0.0;
    if !has_direction {
        return None;
    }
    let foot = line_point + ((centre - line_point).dot(line_direction) / length2) * line_direction;
    let offset_m = (centre - foot).norm();
    let line_meets_circle = offset_m <= radius_m;
    if !line_meets_circle {
        return None;
    }
    // Half chord in units of the direction's length.
    let half_chord = ((radius_m - offset_m) * (radius_m + offset_m) / length2).sqrt();
    Some([
        foot - half_chord * line_direction,
        foot + half_chord * line_direction,
    ])
}

/// The point where the line through `p1` with direction `d1` crosses the line through
/// `p2` with direction `d2`, with its parameters `(t1, t2)` along each direction
/// (`p1 + t1 d1 = p2 + t2 d2`).
///
/// `None` when the lines are parallel (or a direction is zero), or the inputs are not
/// finite.
pub fn line_line_intersection(
    p1: &Point,
    d1: &Vector,
    p2: &Point,
    d2: &Vector,
) -> Option<(Point, f64, f64)> {
    let cross = d1.perp(d2);
    if cross == 0.0 || !cross.is_finite() {
        return None;
    }
    let between = p2 - p1;
    let t1 = between.perp(d2) / cross;
    let t2 = between.perp(d1) / cross;
    (t1.is_finite() && t2.is_finite()).then(|| (p1 + t1 * d1, t1, t2))
}
