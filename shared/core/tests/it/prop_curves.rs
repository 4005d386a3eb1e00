//! Properties of Reeds-Shepp and Dubins paths on random poses.

use std::f64::consts::{FRAC_PI_4, PI, TAU};

use proptest::prelude::*;
use shared::geometry::Pose;
use shared::paths::curve::{CurvePath, Steer};
use shared::paths::{dubins, reeds_shepp};

/// Relative tolerance for comparing lengths.
fn tolerance_m(length_m: f64) -> f64 {
    1e-9 * length_m.max(1.0)
}

/// Random poses, plus lattice poses (integer metres, multiples of 45 degrees) that hit the
/// degenerate cases: collinear poses, equal headings, half turns.
fn pose() -> impl Strategy<Value = Pose> {
    prop_oneof![
        (-20.0..20.0, -20.0..20.0, -PI..PI).prop_map(|(x, y, h)| Pose::new(x, y, h)),
        (-4i32..=4, -4i32..=4, -4i32..=4).prop_map(|(x, y, h)| Pose::new(
            f64::from(x),
            f64::from(y),
            f64::from(h) * FRAC_PI_4
        )),
    ]
}

/// A start pose and a goal pose, sometimes very close to each other.
fn pose_pair() -> impl Strategy<Value = (Pose, Pose)> {
    prop_oneof![
        3 => (pose(), pose()),
        1 => (pose(), -1e-3..1e-3, -1e-3..1e-3, -1e-3..1e-3).prop_map(|(a, dx, dy, dh)| {
            (a, Pose::new(a.x_m + dx, a.y_m + dy, a.heading_rad + dh))
        }),
        1 => pose().prop_map(|a| (a, a)),
    ]
}

fn turning_radius_m() -> impl Strategy<Value = f64> {
    prop_oneof![Just(1.0), Just(0.5), Just(2.0), 0.1..5.0]
}

fn assert_reaches(path: &CurvePath, from: &Pose, to: &Pose) -> Result<(), TestCaseError> {
    let end = path.end_pose(from);
    let position_error_m = (end.position() - to.position()).norm();
    let heading_error_rad = (end.heading_rad - to.heading_rad).rem_euclid(TAU);
    let heading_error_rad = heading_error_rad.min(TAU - heading_error_rad);
    prop_assert!(
        position_error_m <= 1e-6 && heading_error_rad <= 1e-6,
        "path {path:?} ends at {end:?}, goal {to:?}"
    );
    Ok(())
}

fn assert_sample_spacing(
    path: &CurvePath,
    from: &Pose,
    spacing_m: f64,
) -> Result<(), TestCaseError> {
    let poses = path.sample(from, spacing_m);
    prop_assert!(poses.len() >= 2);
    prop_assert_eq!(poses[0].position(), from.position());
    let end = path.end_pose(from);
    prop_assert_eq!(poses[poses.len() - 1], end);
    for pair in poses.windows(2) {
        let gap_m = (pair[1].position() - pair[0].position()).norm();
        prop_assert!(
            gap_m <= spacing_m + 1e-9,
            "consecutive samples {:?} and {:?} are {gap_m} m apart (spacing {spacing_m} m)",
            pair[0],
            pair[1]
        );
    }
    // Enough samples to respect the spacing along the arc length too.
    let needed = (path.length_m() / spacing_m).ceil() as usize + 1;
    prop_assert!(poses.len() >= needed.max(2));
    Ok(())
}

/// Every arc segment has curvature exactly `1 / turning_radius`: its points stay on the
/// circle of that radius tangent to the segment's start pose, and the heading turns by
/// `length / turning_radius`.
fn assert_arc_curvature(path: &CurvePath, from: &Pose) -> Result<(), TestCaseError> {
    let rho = path.turning_radius_m;
    let mut start_s_m = 0.0;
    for segment in &path.segments {
        let length_m = segment.length_m.abs();
        if segment.steer != Steer::Straight {
            prop_assert_eq!(segment.curvature_per_m(rho).abs(), 1.0 / rho);
            let sign = segment.steer.curvature_sign();
            let start = path.pose_at(from, start_s_m);
            let centre_x_m = start.x_m - sign * rho * start.heading_rad.sin();
            let centre_y_m = start.y_m + sign * rho * start.heading_rad.cos();
            for fraction in [0.25, 0.5, 0.75, 1.0] {
                let s_m = start_s_m + fraction * length_m;
                let pose = path.pose_at(from, s_m);
                let radius_m = (pose.x_m - centre_x_m).hypot(pose.y_m - centre_y_m);
                prop_assert!(
                    (radius_m - rho).abs() <= 1e-9 * rho.max(1.0) * 10.0,
                    "arc {segment:?}: point at {s_m} m is {radius_m} m from the centre, rho {rho}"
                );
                let expected_turn_rad = sign * fraction * segment.length_m / rho;
                let turn_error_rad =
                    (pose.heading_rad - start.heading_rad - expected_turn_rad).rem_euclid(TAU);
                prop_assert!(
                    turn_error_rad.min(TAU - turn_error_rad) <= 1e-9,
                    "arc {segment:?}: heading at {s_m} m is {} rad",
                    pose.heading_rad
                );
            }
        }
        start_s_m += length_m;
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn reeds_shepp_length_is_symmetric((a, b) in pose_pair(), rho in turning_radius_m()) {
        let ab_m = reeds_shepp::shortest_length_m(&a, &b, rho);
        let ba_m = reeds_shepp::shortest_length_m(&b, &a, rho);
        prop_assert!((ab_m - ba_m).abs() <= tolerance_m(ab_m), "{ab_m} != {ba_m}");
    }

    #[test]
    fn reeds_shepp_is_no_longer_than_dubins((a, b) in pose_pair(), rho in turning_radius_m()) {
        let rs_m = reeds_shepp::shortest_length_m(&a, &b, rho);
        let dubins_m = dubins::shortest_length_m(&a, &b, rho);
        prop_assert!(rs_m <= dubins_m + tolerance_m(dubins_m), "RS {rs_m} > Dubins {dubins_m}");
    }

    #[test]
    fn dubins_equals_a_forward_only_reeds_shepp_optimum(
        (a, b) in pose_pair(),
        rho in turning_radius_m(),
    ) {
        // A shortest Reeds-Shepp path that never reverses is also a shortest Dubins path.
        let rs = reeds_shepp::shortest_path(&a, &b, rho);
        if !rs.has_reverse() {
            let dubins_m = dubins::shortest_length_m(&a, &b, rho);
            prop_assert!(
                (rs.length_m() - dubins_m).abs() <= tolerance_m(dubins_m),
                "forward-only RS {rs:?} is {} m, Dubins {dubins_m} m",
                rs.length_m()
            );
        }
    }

    #[test]
    fn reeds_shepp_is_no_shorter_than_the_straight_line(
        (a, b) in pose_pair(),
        rho in turning_radius_m(),
    ) {
        let rs_m = reeds_shepp::shortest_length_m(&a, &b, rho);
        let euclidean_m = (b.position() - a.position()).norm();
        prop_assert!(rs_m + tolerance_m(rs_m) >= euclidean_m, "{rs_m} < {euclidean_m}");
    }

    #[test]
    fn reeds_shepp_path_reaches_the_goal((a, b) in pose_pair(), rho in turning_radius_m()) {
        let path = reeds_shepp::shortest_path(&a, &b, rho);
        let length_m = reeds_shepp::shortest_length_m(&a, &b, rho);
        prop_assert!((path.length_m() - length_m).abs() <= tolerance_m(length_m));
        assert_reaches(&path, &a, &b)?;
    }

    #[test]
    fn dubins_path_is_forward_and_reaches_the_goal(
        (a, b) in pose_pair(),
        rho in turning_radius_m(),
    ) {
        let path = dubins::shortest_path(&a, &b, rho);
        prop_assert!(!path.has_reverse(), "{path:?}");
        let length_m = dubins::shortest_length_m(&a, &b, rho);
        prop_assert!((path.length_m() - length_m).abs() <= tolerance_m(length_m));
        assert_reaches(&path, &a, &b)?;
    }

    #[test]
    fn samples_are_no_farther_apart_than_the_spacing(
        (a, b) in pose_pair(),
        rho in turning_radius_m(),
        spacing_m in 0.05..3.0,
    ) {
        assert_sample_spacing(&reeds_shepp::shortest_path(&a, &b, rho), &a, spacing_m)?;
        assert_sample_spacing(&dubins::shortest_path(&a, &b, rho), &a, spacing_m)?;
    }

    #[test]
    fn arcs_have_curvature_one_over_the_turning_radius(
        (a, b) in pose_pair(),
        rho in turning_radius_m(),
    ) {
        assert_arc_curvature(&reeds_shepp::shortest_path(&a, &b, rho), &a)?;
        assert_arc_curvature(&dubins::shortest_path(&a, &b, rho), &a)?;
    }
}
