//! Properties of a unicycle agent's moves on random polylines: a move never takes more
//! than one step's time (driving and turning shared), it is a prefix of the polyline
//! asked for, it stops only where the step's time runs out, and the least turning is
//! found (checked against every choice of driving direction).

use std::f64::consts::{FRAC_PI_2, PI};

use proptest::prelude::*;
use shared::control::kinematics::{
    UnicycleLimits, drive_unicycle, driving_headings, unicycle_step_share,
};
use shared::geometry::{Point, polyline_length_m, wrap_angle_rad};

/// Random polylines, with lattice ones (right angles, half turns, repeated points) that
/// hit the ties and the degenerate segments.
fn polyline() -> impl Strategy<Value = Vec<Point>> {
    prop_oneof![
        prop::collection::vec((-5.0..5.0, -5.0..5.0), 1..7)
            .prop_map(|v| v.into_iter().map(|(x, y)| Point::new(x, y)).collect()),
        prop::collection::vec((-2i32..=2, -2i32..=2), 1..7).prop_map(|v| v
            .into_iter()
            .map(|(x, y)| Point::new(f64::from(x), f64::from(y)))
            .collect()),
    ]
}

fn limits() -> impl Strategy<Value = UnicycleLimits> {
    (0.05..3.0, 0.1..4.0, any::<bool>()).prop_map(|(max_step_m, max_turn_rad, reverse)| {
        UnicycleLimits {
            max_step_m,
            max_turn_rad,
            reverse,
        }
    })
}

fn heading() -> impl Strategy<Value = f64> {
    prop_oneof![-PI..PI, (-2i32..=2).prop_map(|k| f64::from(k) * FRAC_PI_2)]
}

/// The least turning along `waypoints` by trying every choice of direction per segment.
fn brute_force_turning(start: f64, waypoints: &[Point], end: Option<f64>, reverse: bool) -> f64 {
    let dirs: Vec<f64> = waypoints
        .windows(2)
        .filter(|w| (w[1] - w[0]).norm() > 1e-12)
        .map(|w| (w[1].y - w[0].y).atan2(w[1].x - w[0].x))
        .collect();
    let choices: u32 = if reverse { 1 << dirs.len() } else { 1 };
    let turn = |a: f64, b: f64| wrap_angle_rad(b - a).abs();
    (0..choices)
        .map(|mask| {
            let mut h = start;
            let mut total = 0.0;
            for (k, d) in dirs.iter().enumerate() {
                let next = d + if mask >> k & 1 == 1 { PI } else { 0.0 };
                total += turn(h, next);
                h = next;
            }
            total + end.map_or(0.0, |e| turn(h, e))
        })
        .fold(f64::INFINITY, f64::min)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn a_move_fits_in_one_step_and_is_a_prefix_of_the_polyline(
        start in heading(),
        path in polyline(),
        end in prop::option::of(heading()),
        limits in limits(),
    ) {
        let mv = drive_unicycle(start, &path, end, &limits);
        let share = unicycle_step_share(start, &mv.waypoints, mv.end_heading_rad, &limits);
        prop_assert!(share <= 1.0 + 1e-9, "share {share}");
        prop_assert!(polyline_length_m(&mv.waypoints) <= limits.max_step_m * (1.0 + 1e-9));
        // A prefix: every waypoint but the last is the polyline's, the last lies on the
        // segment after them.
        let k = mv.waypoints.len();
        prop_assert!(k >= 1 && k <= path.len());
        prop_assert_eq!(&mv.waypoints[..k - 1], &path[..k - 1]);
        let last = mv.waypoints[k - 1];
        if last != path[k - 1] {
            let (a, b) = (path[k - 2], path[k - 1]);
            let along = (last - a).dot(&(b - a)) / (b - a).norm_squared();
            prop_assert!((0.0..=1.0).contains(&along));
            prop_assert!(((a + (b - a) * along) - last).norm() < 1e-9);
            prop_assert!(!mv.complete);
        }
        if mv.complete {
            prop_assert_eq!(&mv.waypoints, &path);
            if let Some(end) = end {
                prop_assert!(wrap_angle_rad(mv.end_heading_rad - end).abs() < 1e-12);
            }
        } else {
            // It stops only when the step's time has run out.
            prop_assert!((share - 1.0).abs() < 1e-9, "stopped with {share} of the step used");
        }
    }

    #[test]
    fn the_least_turning_is_found(
        start in heading(),
        path in polyline(),
        end in prop::option::of(heading()),
        reverse in any::<bool>(),
    ) {
        let (_, turning) = driving_headings(start, &path, end, reverse);
        let best = brute_force_turning(start, &path, end, reverse);
        prop_assert!((turning - best).abs() < 1e-9, "{turning} vs {best}");
        if reverse {
            prop_assert!(turning <= driving_headings(start, &path, end, false).1 + 1e-12);
        }
    }

    #[test]
    fn a_heading_off_by_more_than_what_is_left_is_refused(
        start in heading(),
        path in polyline(),
        limits in limits(),
        off in 0.01..1.0f64,
    ) {
        let mv = drive_unicycle(start, &path, None, &limits);
        let used = unicycle_step_share(start, &mv.waypoints, mv.end_heading_rad, &limits);
        // The heading it last drove at (or started with), and the turn it made since.
        let (headings, _) = driving_headings(start, &mv.waypoints, None, limits.reverse);
        let driven = headings.iter().rev().flatten().next().copied().unwrap_or(start);
        let since = wrap_angle_rad(mv.end_heading_rad - driven);
        // Turning on the same way by more than the share left allows (and, with what it
        // turned already, less than a half turn, so the short way is this one) is more
        // than one step.
        let left_rad = (1.0 - used).max(0.0) * limits.max_turn_rad;
        let extra = left_rad + off;
        prop_assume!(since.abs() + extra < PI - 0.1);
        let turned = mv.end_heading_rad + if since < 0.0 { -extra } else { extra };
        let share = unicycle_step_share(start, &mv.waypoints, turned, &limits);
        // Without reverse the headings driven are forced, so only the end turn grows.
        if !limits.reverse {
            prop_assert!(share > 1.0, "share {share}");
        }
    }
}
