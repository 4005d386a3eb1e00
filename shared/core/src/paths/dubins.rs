//! Dubins shortest paths: the shortest path between two poses for a car that only drives
//! forwards and turns no tighter than a given radius (Dubins 1957).
//!
//! A shortest Dubins path is one of six words of three segments, each an arc of exactly the
//! turning radius (`L` left, `R` right) or a straight line (`S`):
//!
//! - **CSC**: `LSL`, `RSR` (outer tangent between two circles turning the same way) and
//!   `LSR`, `RSL` (inner tangent between circles turning opposite ways);
//! - **CCC**: `RLR`, `LRL` (a middle arc longer than a half turn, tangent to both end
//!   circles), useful only when the poses are close.
//!
//! All six are evaluated in closed form (Shkel & Lumelsky 2001) and the shortest is kept.
//! Paths are [`CurvePath`]s (module [`crate::paths::curve`]) whose segment lengths are all
//! non-negative. Hybrid A* uses these when reversing is not allowed.

use std::f64::consts::TAU;

use crate::geometry::Pose;
use crate::paths::curve::{CurvePath, Steer, check_turning_radius, scaled_segment};

/// The shortest forward-only path from `from` to `to` for turning radius `turning_radius_m`.
///
/// Identical poses give a path without segments; zero-length (and negligible) segments are
/// omitted. Poses
/// must be finite; a non-finite pose gives a path of NaN length (one straight segment of NaN
/// length).
///
/// # Panics
///
/// If `turning_radius_m` is not finite and strictly positive (callers validate it).
pub fn shortest_path(from: &Pose, to: &Pose, turning_radius_m: f64) -> CurvePath {
    check_turning_radius(turning_radius_m);
    match solve(from, to, turning_radius_m) {
        Some(word) => CurvePath {
            segments: word
                .steers
                .iter()
                .zip(word.lengths)
                .filter_map(|(steer, length)| scaled_segment(*steer, length, turning_radius_m))
                .collect(),
            turning_radius_m,
        },
        None => CurvePath::unreachable(turning_radius_m),
    }
}

/// The length of the shortest forward-only path from `from` to `to`, in metres, without
/// building the path (no allocation).
///
/// Poses must be finite; a non-finite pose gives NaN.
///
/// # Panics
///
/// If `turning_radius_m` is not finite and strictly positive (callers validate it).
pub fn shortest_length_m(from: &Pose, to: &Pose, turning_radius_m: f64) -> f64 {
    check_turning_radius(turning_radius_m);
    solve(from, to, turning_radius_m).map_or(f64::NAN, |word| word.total * turning_radius_m)
}

/// Angles this close below a full turn are snapped to zero.
///
/// Rounding can turn a true zero-length arc into `2 pi - epsilon`, i.e. a needless full
/// loop; a full loop returns to the same pose, so dropping it is always exact up to
/// `epsilon`.
const FULL_TURN_SNAP_RAD: f64 = 1e-9;

/// Relative tolerance for the feasibility tests of the closed forms (see `solve`).
const ROUNDING: f64 = 1e-14;

/// Below this normalized distance between the two tangent circles of `LSL`/`RSR`, the
/// direction of the (vanishing) straight segment is numerical noise; the start heading is
/// used instead, so that coincident circles give a single arc.
const COINCIDENT_CIRCLES: f64 = 1e-10;

/// Wraps an angle into `[0, 2 pi)`, snapping values within [`FULL_TURN_SNAP_RAD`] of
/// `2 pi` to 0.
fn mod2pi(angle_rad: f64) -> f64 {
    let v = angle_rad.rem_euclid(TAU);
    if v >= TAU - FULL_TURN_SNAP_RAD {
        0.0
    } else {
        v
    }
}

/// A word in units of the turning radius: three steers, three non-negative lengths.
#[derive(Clone, Copy, Debug)]
struct Word {
    steers: [Steer; 3],
    lengths: [f64; 3],
    total: f64,
}

impl Word {
    fn new(steers: [Steer; 3], t: f64, p: f64, q: f64) -> Self {
        Word {
            steers,
            lengths: [t, p, q],
            total: t + p + q,
        }
    }
}

/// Shortest of the six words; `None` only for non-finite input.
fn solve(from: &Pose, to: &Pose, turning_radius_m: f64) -> Option<Word> {
    use Steer::{Left as L, Right as R, Straight as S};

    // Standard form (Shkel & Lumelsky): the goal lies on the x axis at distance d, and the
    // headings alpha (start) and beta (goal) are measured from that axis.
    let dx_m = to.x_m - from.x_m;
    let dy_m = to.y_m - from.y_m;
    let d = (dx_m * dx_m + dy_m * dy_m).sqrt() / turning_radius_m;
    let axis_rad = dy_m.atan2(dx_m);
    let alpha = mod2pi(from.heading_rad - axis_rad);
    let beta = mod2pi(to.heading_rad - axis_rad);
    let (sa, ca) = alpha.sin_cos();
    let (sb, cb) = beta.sin_cos();
    let cos_ab = (alpha - beta).cos();
    let d_sq = d * d;
    // Rounding error of the squared-distance expressions below: a tangency computed as
    // slightly infeasible is still accepted (as an exact tangency).
    let rounding = ROUNDING * (1.0 + d_sq);

    let mut best: Option<Word> = None;
    let mut consider = |word: Word| {
        if word.total.is_finite() && best.is_none_or(|b| word.total < b.total) {
            best = Some(word);
        }
    };

    // LSL: outer tangent of the two left circles. `p_sq` is the squared distance of their
    // centres, never negative but for rounding.
    let p_sq = 2.0 + d_sq - 2.0 * cos_ab + 2.0 * d * (sa - sb);
    let p = p_sq.max(0.0).sqrt();
    let tangent = if p < COINCIDENT_CIRCLES {
        alpha
    } else {
        (cb - ca).atan2(d + sa - sb)
    };
    consider(Word::new(
        [L, S, L],
        mod2pi(tangent - alpha),
        p,
        mod2pi(beta - tangent),
    ));

    // RSR: outer tangent of the two right circles (same remark on `p_sq`).
    let p_sq = 2.0 + d_sq - 2.0 * cos_ab + 2.0 * d * (sb - sa);
    let p = p_sq.max(0.0).sqrt();
    let tangent = if p < COINCIDENT_CIRCLES {
        alpha
    } else {
        (ca - cb).atan2(d - sa + sb)
    };
    consider(Word::new(
        [R, S, R],
        mod2pi(alpha - tangent),
        p,
        mod2pi(tangent - beta),
    ));

    // LSR: inner tangent from the left circle to the right circle; `p_sq` is the squared
    // centre distance minus 4, negative when the circles overlap.
    let p_sq = -2.0 + d_sq + 2.0 * cos_ab + 2.0 * d * (sa + sb);
    if p_sq >= -rounding {
        let p = p_sq.max(0.0).sqrt();
        let tangent = (-ca - cb).atan2(d + sa + sb) - (-2.0_f64).atan2(p);
        consider(Word::new(
            [L, S, R],
            mod2pi(tangent - alpha),
            p,
            mod2pi(tangent - beta),
        ));
    }

    // RSL: inner tangent from the right circle to the left circle.
    let p_sq = -2.0 + d_sq + 2.0 * cos_ab - 2.0 * d * (sa + sb);
    if p_sq >= -rounding {
        let p = p_sq.max(0.0).sqrt();
        let tangent = (ca + cb).atan2(d - sa - sb) - 2.0_f64.atan2(p);
        consider(Word::new(
            [R, S, L],
            mod2pi(alpha - tangent),
            p,
            mod2pi(beta - tangent),
        ));
    }

    // RLR: a left arc of more than half a turn between two right circles; `cos_p` is
    // `1 - D^2 / 8` for centre distance D, out of [-1, 1] when they are more than 4 apart.
    let cos_p = (6.0 - d_sq + 2.0 * cos_ab + 2.0 * d * (sa - sb)) / 8.0;
    if cos_p.abs() <= 1.0 + rounding {
        let p = mod2pi(TAU - cos_p.clamp(-1.0, 1.0).acos());
        let centre_axis = (ca - cb).atan2(d - sa + sb);
        let t = mod2pi(alpha - centre_axis + 0.5 * p);
        consider(Word::new([R, L, R], t, p, mod2pi(alpha - beta - t + p)));
    }

    // LRL: a right arc of more than half a turn between two left circles.
    let cos_p = (6.0 - d_sq + 2.0 * cos_ab + 2.0 * d * (sb - sa)) / 8.0;
    if cos_p.abs() <= 1.0 + rounding {
        let p = mod2pi(TAU - cos_p.clamp(-1.0, 1.0).acos());
        let centre_axis = (ca - cb).atan2(d + sa - sb);
        let t = mod2pi(-alpha - centre_axis + 0.5 * p);
        consider(Word::new([L, R, L], t, p, mod2pi(beta - alpha - t + p)));
    }

    best
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::paths::curve::{TOLERANCE, assert_pose_close};

    #[test]
    fn identical_poses_give_an_empty_path() {
        let pose = Pose::new(-3.0, 2.0, 2.5);
        let path = shortest_path(&pose, &pose, 1.5);
        assert!(path.segments.is_empty());
        assert_eq!(shortest_length_m(&pose, &pose, 1.5), 0.0);
    }

    #[test]
    fn straight_ahead_is_one_straight_segment() {
        let from = Pose::new(0.0, 0.0, 0.3);
        let to = Pose::new(10.0 * 0.3_f64.cos(), 10.0 * 0.3_f64.sin(), 0.3);
        let path = shortest_path(&from, &to, 1.0);
        assert_eq!(path.segments.len(), 1, "{path:?}");
        assert_eq!(path.segments[0].steer, Steer::Straight);
        assert!((path.length_m() - 10.0).abs() < TOLERANCE);
        assert_pose_close(&path.end_pose(&from), &to);
    }

    #[test]
    fn quarter_turn_right_is_one_right_arc() {
        let rho = 3.0;
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(rho, -rho, -PI / 2.0);
        let path = shortest_path(&from, &to, rho);
        assert_eq!(path.segments.len(), 1, "{path:?}");
        assert_eq!(path.segments[0].steer, Steer::Right);
        assert!((path.length_m() - rho * PI / 2.0).abs() < TOLERANCE);
        assert_pose_close(&path.end_pose(&from), &to);
    }

    #[test]
    fn tangent_circles_computed_as_overlapping_still_give_the_arc() {
        // The two right circles coincide here, and rounding makes their squared centre
        // distance slightly negative; the single right quarter turn must still be found.
        let from = Pose::new(0.0, -1.0, 0.0);
        let to = Pose::new(1.0, -2.0, -PI / 2.0);
        let path = shortest_path(&from, &to, 1.0);
        assert!((path.length_m() - PI / 2.0).abs() < TOLERANCE, "{path:?}");
        assert_pose_close(&path.end_pose(&from), &to);
    }

    #[test]
    fn u_turn_on_the_spot_is_ccc() {
        // Back to the same point facing the other way: the end circles are 2 rho apart, the
        // middle circle makes an equilateral triangle with them, so the middle arc is
        // 5 pi / 3 and the total 7 pi / 3 (shorter than any CSC word).
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(0.0, 0.0, PI);
        let path = shortest_path(&from, &to, 1.0);
        assert!(
            (path.length_m() - 7.0 * PI / 3.0).abs() < TOLERANCE,
            "{path:?}"
        );
        assert_pose_close(&path.end_pose(&from), &to);
    }

    #[test]
    fn behind_needs_no_reverse() {
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(-5.0, 0.0, 0.0);
        let path = shortest_path(&from, &to, 1.0);
        assert!(!path.has_reverse());
        assert_pose_close(&path.end_pose(&from), &to);
    }
}
