//! The entry points: the shortest Reeds-Shepp path between two poses, and its length.

use super::word::solve;
use crate::geometry::Pose;
use crate::paths::curve::{CurvePath, check_turning_radius};

/// The shortest Reeds-Shepp path from `from` to `to` for turning radius `turning_radius_m`.
///
/// Identical poses give a path without segments. Poses must be finite; a non-finite pose
/// gives a path of NaN length (one straight segment of NaN length).
///
/// # Panics
///
/// If `turning_radius_m` is not finite and strictly positive (callers validate it).
pub fn shortest_path(from: &Pose, to: &Pose, turning_radius_m: f64) -> CurvePath {
    check_turning_radius(turning_radius_m);
    match solve(from, to, turning_radius_m) {
        Some(word) => CurvePath {
            segments: word.segments(turning_radius_m).collect(),
            turning_radius_m,
        },
        None => CurvePath::unreachable(turning_radius_m),
    }
}

/// The length of the shortest Reeds-Shepp path from `from` to `to`, in metres, without
/// building the path (no allocation). Equal to `shortest_path(from, to, rho).length_m()` up to
/// rounding.
///
/// Poses must be finite; a non-finite pose gives NaN.
///
/// # Panics
///
/// If `turning_radius_m` is not finite and strictly positive (callers validate it).
///
/// ```
/// use std::f64::consts::FRAC_PI_2;
///
/// use shared::geometry::Pose;
/// use shared::paths::{dubins, reeds_shepp};
///
/// let rho = 2.0;
/// let start = Pose::new(0.0, 0.0, 0.0);
/// // A quarter turn to the left, exactly on the turning circle: one arc.
/// let quarter = Pose::new(rho, rho, FRAC_PI_2);
/// let length_m = reeds_shepp::shortest_length_m(&start, &quarter, rho);
/// assert!((length_m - rho * FRAC_PI_2).abs() < 1e-9);
/// // 3 m straight behind: reversing is shortest; driving forwards only must turn around.
/// let behind = Pose::new(-3.0, 0.0, 0.0);
/// let reverse_m = reeds_shepp::shortest_length_m(&start, &behind, rho);
/// assert!((reverse_m - 3.0).abs() < 1e-9);
/// assert!(dubins::shortest_length_m(&start, &behind, rho) > reverse_m + rho);
/// ```
pub fn shortest_length_m(from: &Pose, to: &Pose, turning_radius_m: f64) -> f64 {
    check_turning_radius(turning_radius_m);
    solve(from, to, turning_radius_m).map_or(f64::NAN, |word| word.total * turning_radius_m)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::paths::curve::Steer;
    use crate::paths::curve::{TOLERANCE, assert_pose_close};

    #[test]
    fn identical_poses_give_an_empty_path() {
        let pose = Pose::new(1.5, -2.0, 0.7);
        let path = shortest_path(&pose, &pose, 2.0);
        assert!(path.segments.is_empty());
        assert_eq!(path.length_m(), 0.0);
        assert_eq!(shortest_length_m(&pose, &pose, 2.0), 0.0);
        assert_pose_close(&path.end_pose(&pose), &pose);
        assert_eq!(path.sample(&pose, 0.1).len(), 2);
    }

    #[test]
    fn straight_ahead_is_one_straight_segment() {
        let from = Pose::new(1.0, 1.0, PI / 4.0);
        let to = Pose::new(4.0, 4.0, PI / 4.0);
        let path = shortest_path(&from, &to, 1.0);
        assert_eq!(path.segments.len(), 1);
        assert_eq!(path.segments[0].steer, Steer::Straight);
        assert!((path.segments[0].length_m - 18.0_f64.sqrt()).abs() < TOLERANCE);
        assert_pose_close(&path.end_pose(&from), &to);
    }

    #[test]
    fn straight_behind_is_driven_in_reverse() {
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(-3.0, 0.0, 0.0);
        let path = shortest_path(&from, &to, 1.0);
        assert_eq!(path.segments.len(), 1);
        assert!(path.has_reverse());
        assert!((path.segments[0].length_m + 3.0).abs() < TOLERANCE);
        assert_pose_close(&path.end_pose(&from), &to);
    }

    #[test]
    fn quarter_turn_is_one_left_arc() {
        let rho = 2.0;
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(rho, rho, PI / 2.0);
        let path = shortest_path(&from, &to, rho);
        assert_eq!(path.segments.len(), 1);
        assert_eq!(path.segments[0].steer, Steer::Left);
        assert!((path.length_m() - rho * PI / 2.0).abs() < TOLERANCE);
        assert_pose_close(&path.end_pose(&from), &to);
        // Halfway round the arc.
        let half = path.pose_at(&from, rho * PI / 4.0);
        let expected = Pose::new(
            rho * (PI / 4.0).sin(),
            rho * (1.0 - (PI / 4.0).cos()),
            PI / 4.0,
        );
        assert_pose_close(&half, &expected);
    }

    #[test]
    fn pose_at_clamps_to_the_path() {
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(1.0, 3.0, 2.0);
        let path = shortest_path(&from, &to, 1.0);
        assert_pose_close(&path.pose_at(&from, -1.0), &from);
        assert_pose_close(&path.pose_at(&from, f64::NAN), &from);
        assert_pose_close(&path.pose_at(&from, 1e9), &to);
    }

    #[test]
    fn length_scales_with_the_turning_radius() {
        let from = Pose::new(0.0, 0.0, 0.3);
        let to = Pose::new(0.5, -0.2, 2.9);
        let unit = shortest_length_m(&from, &to, 1.0);
        let scaled_to = Pose::new(2.5, -1.0, 2.9);
        let scaled = shortest_length_m(&from, &scaled_to, 5.0);
        assert!((scaled - 5.0 * unit).abs() < 1e-9 * scaled);
    }

    #[test]
    fn parallel_parking_uses_reverse() {
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(0.0, 1.0, 0.0);
        let path = shortest_path(&from, &to, 1.0);
        assert!(path.has_reverse());
        assert_pose_close(&path.end_pose(&from), &to);
    }

    #[test]
    fn non_finite_pose_gives_nan() {
        let from = Pose::new(0.0, 0.0, 0.0);
        let to = Pose::new(f64::NAN, 0.0, 0.0);
        assert!(shortest_length_m(&from, &to, 1.0).is_nan());
        assert!(shortest_path(&from, &to, 1.0).length_m().is_nan());
    }

    #[test]
    #[should_panic(expected = "turning radius")]
    fn zero_turning_radius_panics() {
        let pose = Pose::new(0.0, 0.0, 0.0);
        shortest_length_m(&pose, &pose, 0.0);
    }
}
