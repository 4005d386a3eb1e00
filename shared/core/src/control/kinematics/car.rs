//! A car-like agent: it cannot turn in place, and its path bends no tighter than its
//! turning radius. Its moves are Reeds-Shepp paths (with reverse) or Dubins paths
//! (without), published as chords.
//!
//! A chord stands for exactly one arc: the one that leaves the chord's start tangent to
//! the heading there (driving forwards when the chord lies ahead of the heading, in
//! reverse when behind) and ends at the chord's end ([`car_piece`]). So a polyline and the
//! start heading give back the whole curve, and the checks read it exactly: its radius,
//! its length, the heading it ends at, and how far the arc bulges from its chord (the
//! chord error, `c/2 tan(a/2)` for a chord `c` at angle `a` to the heading), which the
//! swept-disk checks add to the agent's radius. The planner draws every arc with chords
//! of at most [`CAR_CHORD_TURN_RAD`] of turning and a chord error of at most the one asked
//! for ([`car_waypoints`]).

use crate::geometry::{Point, Pose, wrap_angle_rad};
use crate::paths::curve::{CurvePath, Segment, Steer};

/// Segments shorter than this are left out when a path is drawn: a chord of a few
/// nanometres has no direction to speak of (its ends are known to about 1e-15 m), and
/// leaving the segment out moves the rest of the path by no more than its length.
pub const MIN_SEGMENT_M: f64 = 1e-7;

/// Segments shorter than this share of the start's distance from the field's corner are
/// left out too: 100 m out, a point is known to about 1e-14 m only, so a chord of 1e-7 m
/// there has a direction known to 1e-7 rad, as much as a chord's turning may be off
/// ([`CAR_TURN_TOLERANCE_RAD`]); 1e-5 m, this share of 100 m, is known to 1e-9 rad.
pub const MIN_SEGMENT_PER_M: f64 = 1e-7;

/// Chords shorter than this carry no direction: they are read as standing still.
const DEGENERATE_CHORD_M: f64 = 1e-12;

/// The most an arc may turn along one chord, radians: well below the half turn at which
/// a chord's arc would no longer be told from the one driven the other way.
pub const CAR_CHORD_TURN_RAD: f64 = std::f64::consts::FRAC_PI_4;

/// How much more a chord's arc may turn than its turning radius allows, radians: the
/// rounding of a short chord's direction (a chord of 0.1 mm is known to about 1e-11 m).
pub const CAR_TURN_TOLERANCE_RAD: f64 = 1e-7;

/// How much longer than the top speed a move's arcs may be, metres: rounding only.
const LENGTH_TOLERANCE_M: f64 = 1e-9;

/// How far a move's end heading may differ from the heading its chords give, radians.
pub const CAR_HEADING_TOLERANCE_RAD: f64 = 1e-6;

/// How far a car agent may drive in one step, and how tightly it may bend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CarLimits {
    /// The longest drive in one step (arc length), metres.
    pub max_step_m: f64,
    /// The smallest radius its path may bend with, metres.
    pub turning_radius_m: f64,
    /// Whether it may drive backwards.
    pub reverse: bool,
}

/// One chord of a car's move read as the arc it stands for ([`car_piece`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CarPiece {
    /// Whether it is driven in reverse (the chord lies behind the heading).
    pub reverse: bool,
    /// The heading change along it, radians (positive: counter-clockwise).
    pub turn_rad: f64,
    /// Its radius, metres (infinite for a straight chord).
    pub radius_m: f64,
    /// Its arc length, metres.
    pub length_m: f64,
    /// The farthest the arc comes from its chord, metres.
    pub chord_error_m: f64,
}

/// The arc from `from`, leaving tangent to `heading_rad`, that ends at `to`.
///
/// ```
/// use shared::geometry::Point;
/// use shared::control::kinematics::car_piece;
/// // Facing +x, the chord of a quarter circle of radius 1 to the left.
/// let piece = car_piece(0.0, &Point::new(0.0, 0.0), &Point::new(1.0, 1.0));
/// assert!(!piece.reverse);
/// assert!((piece.radius_m - 1.0).abs() < 1e-12);
/// assert!((piece.turn_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// assert!((piece.length_m - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// // Its middle bulges 1 - cos(pi/4) from the chord.
/// assert!((piece.chord_error_m - (1.0 - 0.5f64.sqrt())).abs() < 1e-12);
/// ```
pub fn car_piece(heading_rad: f64, from: &Point, to: &Point) -> CarPiece {
    let d = to - from;
    let chord_m = d.norm();
    if chord_m <= DEGENERATE_CHORD_M {
        return CarPiece {
            reverse: false,
            turn_rad: 0.0,
            radius_m: f64::INFINITY,
            length_m: chord_m,
            chord_error_m: 0.0,
        };
    }
    let ahead = Point::new(heading_rad.cos(), heading_rad.sin()).coords;
    let reverse = ahead.dot(&d) < 0.0;
    let way = if reverse { -ahead } else { ahead };
    // The chord's angle to the way driven, in [-pi/2, pi/2]: the arc turns twice that.
    let angle_rad = (way.x * d.y - way.y * d.x).atan2(way.dot(&d));
    let half_sin = angle_rad.abs().sin();
    let radius_m = if half_sin > 0.0 {
        chord_m / (2.0 * half_sin)
    } else {
        f64::INFINITY
    };
    let length_m = if radius_m.is_finite() {
        radius_m * 2.0 * angle_rad.abs()
    } else {
        chord_m
    };
    CarPiece {
        reverse,
        turn_rad: 2.0 * angle_rad,
        radius_m,
        length_m,
        chord_error_m: 0.5 * chord_m * (0.5 * angle_rad.abs()).tan(),
    }
}

/// Why a car's move is not one it can drive.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum CarMoveError {
    /// A chord's arc bends tighter than the turning radius.
    #[error(
        "chord {chord} bends with radius {radius_m} m, tighter than the turning radius {turning_radius_m} m"
    )]
    TooTight {
        /// The chord, from 0.
        chord: usize,
        /// The radius of its arc.
        radius_m: f64,
        /// The car's turning radius.
        turning_radius_m: f64,
    },
    /// A chord lies behind the heading of a car that may not reverse.
    #[error("chord {chord} is driven in reverse, which this car may not")]
    Reverse {
        /// The chord, from 0.
        chord: usize,
    },
    /// The end heading is not the one the chords give (it would have turned in place).
    #[error("the move ends facing {off_rad} rad off the heading its arcs give")]
    EndHeading {
        /// The difference, radians.
        off_rad: f64,
    },
    /// The arcs are longer than the top speed allows.
    #[error("the move's arcs are {length_m} m long, beyond the top speed of {max_m} m per step")]
    TooLong {
        /// Their length.
        length_m: f64,
        /// The top speed, metres per step.
        max_m: f64,
    },
    /// The end heading is missing or not a number.
    #[error("the move gives no finite end heading")]
    NoHeading,
}

/// Check the move `waypoints` of a car facing `start_heading_rad` that says it ends
/// facing `end_heading_rad`: every chord's arc bends no tighter than the turning radius
/// and is driven forwards (unless reversing is allowed), the arcs together are no longer
/// than the top speed, and the end heading is the one they give. On success, each
/// chord's error (how far its arc bulges from it), for the swept-disk checks.
///
/// ```
/// use shared::geometry::Point;
/// use shared::control::kinematics::{CarLimits, CarMoveError, check_car_move};
/// let limits = CarLimits { max_step_m: 2.0, turning_radius_m: 1.0, reverse: false };
/// let quarter = [Point::new(0.0, 0.0), Point::new(1.0, 1.0)];
/// let pi_2 = std::f64::consts::FRAC_PI_2;
/// assert!(check_car_move(0.0, &quarter, Some(pi_2), &limits).is_ok());
/// // Turning in place at the end: refused.
/// assert!(matches!(
///     check_car_move(0.0, &quarter, Some(0.0), &limits),
///     Err(CarMoveError::EndHeading { .. })
/// ));
/// // A radius of 1 m is too tight for a turning radius of 1.5 m.
/// let wide = CarLimits { turning_radius_m: 1.5, ..limits };
/// assert!(matches!(
///     check_car_move(0.0, &quarter, Some(pi_2), &wide),
///     Err(CarMoveError::TooTight { chord: 0, .. })
/// ));
/// ```
pub fn check_car_move(
    start_heading_rad: f64,
    waypoints: &[Point],
    end_heading_rad: Option<f64>,
    limits: &CarLimits,
) -> Result<Vec<f64>, CarMoveError> {
    let Some(end_rad) = end_heading_rad.filter(|h| h.is_finite()) else {
        return Err(CarMoveError::NoHeading);
    };
    let mut heading_rad = start_heading_rad;
    let mut length_m = 0.0;
    let mut errors = Vec::with_capacity(waypoints.len().saturating_sub(1));
    for (chord, w) in waypoints.windows(2).enumerate() {
        let piece = car_piece(heading_rad, &w[0], &w[1]);
        // Its half turn against the most a chord this long allows at the turning radius.
        let chord_m = (w[1] - w[0]).norm();
        let most_rad = (0.5 * chord_m / limits.turning_radius_m).min(1.0).asin();
        if 0.5 * piece.turn_rad.abs() > most_rad + CAR_TURN_TOLERANCE_RAD {
            return Err(CarMoveError::TooTight {
                chord,
                radius_m: piece.radius_m,
                turning_radius_m: limits.turning_radius_m,
            });
        }
        if piece.reverse && !limits.reverse {
            return Err(CarMoveError::Reverse { chord });
        }
        heading_rad += piece.turn_rad;
        length_m += piece.length_m;
        errors.push(piece.chord_error_m);
    }
    let off_rad = wrap_angle_rad(end_rad - heading_rad).abs();
    if off_rad.is_nan() || off_rad > CAR_HEADING_TOLERANCE_RAD {
        return Err(CarMoveError::EndHeading { off_rad });
    }
    if length_m > limits.max_step_m + LENGTH_TOLERANCE_M {
        return Err(CarMoveError::TooLong {
            length_m,
            max_m: limits.max_step_m,
        });
    }
    Ok(errors)
}

/// The first `max_length_m` of `path` (all of it if shorter).
///
/// ```
/// use shared::paths::curve::{CurvePath, Segment, Steer};
/// use shared::control::kinematics::curve_prefix;
/// let path = CurvePath {
///     segments: vec![
///         Segment { steer: Steer::Left, length_m: 1.0 },
///         Segment { steer: Steer::Straight, length_m: -2.0 },
///     ],
///     turning_radius_m: 1.0,
/// };
/// let cut = curve_prefix(&path, 2.5);
/// assert_eq!(cut.segments[1], Segment { steer: Steer::Straight, length_m: -1.5 });
/// assert_eq!(curve_prefix(&path, 9.0), path);
/// ```
pub fn curve_prefix(path: &CurvePath, max_length_m: f64) -> CurvePath {
    let mut left_m = max_length_m.max(0.0);
    let mut segments = Vec::with_capacity(path.segments.len());
    for s in &path.segments {
        if left_m <= 0.0 {
            break;
        }
        let take_m = s.length_m.abs().min(left_m);
        segments.push(Segment {
            steer: s.steer,
            length_m: take_m.copysign(s.length_m),
        });
        left_m -= take_m;
    }
    CurvePath {
        segments,
        turning_radius_m: path.turning_radius_m,
    }
}

/// `path` followed from `start` as chords: one per straight segment, and along each arc
/// as many equal chords as keep each one's turning within [`CAR_CHORD_TURN_RAD`] and its
/// chord error within `max_chord_error_m`, segments shorter than [`MIN_SEGMENT_M`] (or
/// [`MIN_SEGMENT_PER_M`] of the start's largest coordinate) left
/// out; and the heading at the end (of the path so drawn).
///
/// ```
/// use shared::paths::curve::{CurvePath, Segment, Steer};
/// use shared::geometry::Pose;
/// use shared::control::kinematics::{CarLimits, car_waypoints, check_car_move};
/// let path = CurvePath {
///     segments: vec![Segment { steer: Steer::Left, length_m: std::f64::consts::PI }],
///     turning_radius_m: 1.0,
/// };
/// let (points, end_rad) = car_waypoints(&Pose::new(0.0, 0.0, 0.0), &path, 1e-3);
/// assert!((points.last().unwrap().y - 2.0).abs() < 1e-12, "a half turn");
/// let limits = CarLimits { max_step_m: 4.0, turning_radius_m: 1.0, reverse: false };
/// let errors = check_car_move(0.0, &points, Some(end_rad), &limits).unwrap();
/// assert!(errors.iter().all(|e| *e <= 1e-3 + 1e-15));
/// ```
pub fn car_waypoints(start: &Pose, path: &CurvePath, max_chord_error_m: f64) -> (Vec<Point>, f64) {
    let rho_m = path.turning_radius_m;
    // The turning of one chord whose error is the one asked for: rho (1 - cos(t/2)).
    let by_error_rad = 2.0 * (1.0 - (max_chord_error_m / rho_m).min(1.0)).acos();
    let per_chord_rad = CAR_CHORD_TURN_RAD.min(by_error_rad).max(1e-6);
    let mut points = vec![start.position()];
    let mut pose = *start;
    let min_m = MIN_SEGMENT_M.max(MIN_SEGMENT_PER_M * start.x_m.abs().max(start.y_m.abs()));
    for s in path.segments.iter().filter(|s| s.length_m.abs() >= min_m) {
        let pieces = match s.steer {
            Steer::Straight => 1,
            Steer::Left | Steer::Right => {
                ((s.length_m.abs() / rho_m / per_chord_rad).ceil() as usize).max(1)
            }
        };
        let one = CurvePath {
            segments: vec![*s],
            turning_radius_m: rho_m,
        };
        let total_m = s.length_m.abs();
        for k in 1..=pieces {
            let at = if k == pieces {
                one.end_pose(&pose)
            } else {
                one.pose_at(&pose, total_m * k as f64 / pieces as f64)
            };
            points.push(at.position());
            if k == pieces {
                pose = at;
            }
        }
    }
    (points, wrap_angle_rad(pose.heading_rad))
}
