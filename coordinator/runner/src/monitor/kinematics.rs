//! The monitor's check of a move against the agent's kinematic model, on its own
//! arithmetic (angles from dot and cross products, not the controllers' code).

use nalgebra::Vector2;
use shared::control::safety::SAFETY_TOLERANCE_M;
use shared::control::vocabulary::Kinematics;
use shared::geometry::Point;

use super::Refusal;

/// How far past a whole step a unicycle's turning and driving may reach: rounding only.
const STEP_SHARE_TOLERANCE: f64 = 1e-9;

/// How much more a car's arc may turn along one segment than its turning radius allows,
/// radians: the rounding of a short segment's direction only.
const TURN_TOLERANCE_RAD: f64 = 1e-7;

/// How far a car's end heading may differ from the one its arcs give, radians.
const END_HEADING_TOLERANCE_RAD: f64 = 1e-6;

/// Segments shorter than this have no direction: driven without turning.
const DEGENERATE_SEGMENT_M: f64 = 1e-12;

/// Check a move against the agent's kinematics, on its own arithmetic (angles from dot
/// and cross products, not the controllers' code): a holonomic agent reports no heading;
/// a unicycle facing `start_heading_rad` reports a finite `end_heading_rad`, and turning
/// in place at the vertices (the least turning over driving each segment forwards or,
/// with `reverse`, backwards) plus driving fits one step: turning / `max_turn_rad` +
/// length / `max_step_m` at most 1. A car's segments each stand for the arc that leaves
/// tangent to the heading (forwards, or backwards when the segment lies behind it):
/// each arc's radius is at least `turning_radius_m`, none is reversed unless `reverse`,
/// their length is within the top speed, and the end heading is the one they leave it
/// at. On success, each segment's chord error (none but for a car), for [`SafetyMonitor::check`].
pub fn check_kinematics(
    kinematics: Kinematics,
    start_heading_rad: Option<f64>,
    waypoints: &[Point],
    end_heading_rad: Option<f64>,
    max_step_m: Option<f64>,
) -> Result<Vec<f64>, Refusal> {
    let (max_turn_rad, reverse) = match kinematics {
        Kinematics::Unicycle {
            max_turn_rad,
            reverse,
        } => (max_turn_rad, reverse),
        Kinematics::Car {
            turning_radius_m,
            reverse,
        } => {
            return check_car(
                turning_radius_m,
                reverse,
                start_heading_rad,
                waypoints,
                end_heading_rad,
                max_step_m,
            );
        }
        Kinematics::Holonomic => {
            return match end_heading_rad {
                None => Ok(Vec::new()),
                Some(_) => Err(Refusal::UnexpectedHeading),
            };
        }
    };
    let (Some(start), Some(end)) = (start_heading_rad, end_heading_rad.filter(|h| h.is_finite()))
    else {
        return Err(Refusal::NoHeading);
    };
    let unit = |rad: f64| Vector2::new(rad.cos(), rad.sin());
    let angle = |a: &Vector2<f64>, b: &Vector2<f64>| (a.x * b.y - a.y * b.x).atan2(a.dot(b)).abs();
    // The least turning so far ending facing forwards [0] or backwards [1] along the
    // last segment, and the way it faces then.
    let mut cost = [0.0, f64::INFINITY];
    let mut facing = [unit(start), unit(start)];
    let mut length_m = 0.0;
    for w in waypoints.windows(2) {
        let d = w[1] - w[0];
        let norm = d.norm();
        length_m += norm;
        if norm <= DEGENERATE_SEGMENT_M {
            continue;
        }
        let ahead = d / norm;
        let options = [ahead, -ahead];
        let mut next = [f64::INFINITY; 2];
        for (o, way) in options.iter().enumerate().take(if reverse { 2 } else { 1 }) {
            for p in 0..2 {
                next[o] = next[o].min(cost[p] + angle(&facing[p], way));
            }
        }
        cost = next;
        facing = options;
    }
    let turning_rad = (0..2)
        .map(|p| cost[p] + angle(&facing[p], &unit(end)))
        .fold(f64::INFINITY, f64::min);
    let share = turning_rad / max_turn_rad + length_m / max_step_m.unwrap_or(f64::INFINITY);
    if share.is_nan() || share > 1.0 + STEP_SHARE_TOLERANCE {
        return Err(Refusal::TooMuchTurning { share });
    }
    Ok(Vec::new())
}

/// [`check_kinematics`] for a car: read each segment back as the arc tangent to the
/// heading through it, and check it.
fn check_car(
    turning_radius_m: f64,
    reverse: bool,
    start_heading_rad: Option<f64>,
    waypoints: &[Point],
    end_heading_rad: Option<f64>,
    max_step_m: Option<f64>,
) -> Result<Vec<f64>, Refusal> {
    let (Some(start), Some(end)) = (start_heading_rad, end_heading_rad.filter(|h| h.is_finite()))
    else {
        return Err(Refusal::NoHeading);
    };
    let mut heading = Vector2::new(start.cos(), start.sin());
    let mut length_m = 0.0;
    let mut errors_m = Vec::with_capacity(waypoints.len());
    for (segment, w) in waypoints.windows(2).enumerate() {
        let d = w[1] - w[0];
        let chord_m = d.norm();
        if chord_m <= DEGENERATE_SEGMENT_M {
            length_m += chord_m;
            errors_m.push(0.0);
            continue;
        }
        let backwards = heading.dot(&d) < 0.0;
        if backwards && !reverse {
            return Err(Refusal::Reversing(segment));
        }
        let way = if backwards { -heading } else { heading };
        // The chord's angle to the way driven: the arc turns by twice it.
        let angle_rad = (way.x * d.y - way.y * d.x).atan2(way.dot(&d));
        let sin = angle_rad.abs().sin();
        let most_rad = (0.5 * chord_m / turning_radius_m).min(1.0).asin();
        if angle_rad.abs() > most_rad + TURN_TOLERANCE_RAD {
            return Err(Refusal::TooTight {
                segment,
                radius_m: chord_m / (2.0 * sin),
            });
        }
        length_m += if sin > 0.0 {
            chord_m * angle_rad.abs() / sin
        } else {
            chord_m
        };
        errors_m.push(0.5 * chord_m * (0.5 * angle_rad.abs()).tan());
        heading = nalgebra::Rotation2::new(2.0 * angle_rad) * heading;
    }
    let want = Vector2::new(end.cos(), end.sin());
    let off_rad = (heading.x * want.y - heading.y * want.x)
        .atan2(heading.dot(&want))
        .abs();
    if off_rad.is_nan() || off_rad > END_HEADING_TOLERANCE_RAD {
        return Err(Refusal::EndHeading { off_rad });
    }
    if let Some(max_m) = max_step_m
        && (length_m.is_nan() || length_m > max_m + SAFETY_TOLERANCE_M)
    {
        return Err(Refusal::TooLong { length_m, max_m });
    }
    Ok(errors_m)
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNICYCLE: Kinematics = Kinematics::Unicycle {
        max_turn_rad: 2.0,
        reverse: false,
    };

    #[test]
    fn headings_are_required_of_unicycles_and_refused_of_holonomic_agents() {
        let path = [Point::new(0.0, 0.0), Point::new(0.5, 0.0)];
        let holonomic = Kinematics::Holonomic;
        assert_eq!(
            check_kinematics(holonomic, None, &path, None, None),
            Ok(Vec::new())
        );
        assert_eq!(
            check_kinematics(holonomic, None, &path, Some(0.0), None),
            Err(Refusal::UnexpectedHeading)
        );
        for end in [None, Some(f64::NAN), Some(f64::INFINITY)] {
            assert_eq!(
                check_kinematics(UNICYCLE, Some(0.0), &path, end, Some(1.0)),
                Err(Refusal::NoHeading)
            );
        }
        assert_eq!(
            check_kinematics(UNICYCLE, Some(0.0), &path, Some(0.0), Some(1.0)),
            Ok(Vec::new())
        );
    }

    #[test]
    fn turning_and_driving_share_the_step() {
        // Half a step's drive, then a quarter turn: 0.5 + (pi/2)/2 = 1.285 of a step.
        let path = [Point::new(0.0, 0.0), Point::new(0.5, 0.0)];
        let quarter = std::f64::consts::FRAC_PI_2;
        assert!(matches!(
            check_kinematics(UNICYCLE, Some(0.0), &path, Some(quarter), Some(1.0)),
            Err(Refusal::TooMuchTurning { share }) if (share - (0.5 + quarter / 2.0)).abs() < 1e-12
        ));
        // Half the turn fits with the drive: 0.5 + 1.0 / 2 = 1.
        assert_eq!(
            check_kinematics(UNICYCLE, Some(0.0), &path, Some(1.0), Some(1.0)),
            Ok(Vec::new())
        );
        // Backwards: a half turn first without reverse, none with it.
        let behind = [Point::new(0.0, 0.0), Point::new(-0.5, 0.0)];
        assert!(check_kinematics(UNICYCLE, Some(0.0), &behind, Some(0.0), Some(1.0)).is_err());
        let reversing = Kinematics::Unicycle {
            max_turn_rad: 2.0,
            reverse: true,
        };
        assert_eq!(
            check_kinematics(reversing, Some(0.0), &behind, Some(0.0), Some(1.0)),
            Ok(Vec::new())
        );
    }

    proptest::proptest! {
        /// The monitor and the controllers' own arithmetic agree on every polyline: the
        /// monitor takes exactly the moves whose share of the step is at most 1.
        #[test]
        fn the_turning_check_agrees_with_the_kinematics_module(
            start in -3.2f64..3.2,
            end in -3.2f64..3.2,
            reverse in proptest::bool::ANY,
            xs in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 0..5),
        ) {
            let limits = shared::control::kinematics::UnicycleLimits {
                max_step_m: 2.0,
                max_turn_rad: 3.0,
                reverse,
            };
            let mut path = vec![Point::origin()];
            path.extend(xs.iter().map(|&(x, y)| Point::new(x, y)));
            let share = shared::control::kinematics::unicycle_step_share(start, &path, end, &limits);
            let kinematics = Kinematics::Unicycle { max_turn_rad: 3.0, reverse };
            let verdict = check_kinematics(kinematics, Some(start), &path, Some(end), Some(2.0));
            if (share - 1.0).abs() > 1e-6 {
                proptest::prop_assert_eq!(verdict.is_ok(), share <= 1.0, "share {}", share);
            }
            if let Err(Refusal::TooMuchTurning { share: got }) = verdict {
                proptest::prop_assert!((got - share).abs() < 1e-9);
            }
        }

        /// On random polylines from a random heading, the monitor's car check (its own
        /// arithmetic) and the library's agree: both take the move or both refuse it,
        /// and where they take it they give the same chord errors.
        #[test]
        fn the_car_check_agrees_with_the_kinematics_module(
            start in -3.2f64..3.2,
            end_off in proptest::prop_oneof![proptest::strategy::Just(0.0), -0.1f64..0.1],
            rho_m in 0.1f64..2.0,
            reverse in proptest::bool::ANY,
            xs in proptest::collection::vec((-0.3f64..0.3, -0.3f64..0.3), 0..4),
        ) {
            let mut path = vec![Point::origin()];
            path.extend(xs.iter().map(|&(x, y)| Point::new(x, y)));
            // The end heading the chords give, give or take `end_off`.
            let mut heading = start;
            for w in path.windows(2) {
                heading += shared::control::kinematics::car_piece(heading, &w[0], &w[1]).turn_rad;
            }
            let end = heading + end_off;
            let limits = shared::control::kinematics::CarLimits {
                max_step_m: 1.5,
                turning_radius_m: rho_m,
                reverse,
            };
            let library = shared::control::kinematics::check_car_move(start, &path, Some(end), &limits);
            let kinematics = Kinematics::Car { turning_radius_m: rho_m, reverse };
            let monitor = check_kinematics(kinematics, Some(start), &path, Some(end), Some(1.5));
            proptest::prop_assert_eq!(library.is_ok(), monitor.is_ok(), "{:?} {:?}", library, monitor);
            if let (Ok(a), Ok(b)) = (library, monitor) {
                proptest::prop_assert_eq!(a.len(), b.len());
                for (x, y) in a.iter().zip(&b) {
                    proptest::prop_assert!((x - y).abs() < 1e-12);
                }
            }
        }
    }
}
