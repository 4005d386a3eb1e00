//! A differential-drive agent along a polyline: turn in place, drive straight, within one
//! step's time.
//!
//! In one step the agent may turn at most `max_turn_rad` or drive at most `max_step_m`,
//! and any mix of the two in proportion: turning by `a` and driving `d` take the share
//! `a / max_turn_rad + d / max_step_m` of the step, at most 1. It drives each segment of
//! the polyline facing along it (or, with `reverse`, facing away from it when that needs
//! less turning), turning the short way at each vertex; with a final heading asked for,
//! it turns to it at the end. Where the step's time runs out, the move stops: part way
//! along a segment, or part way through a turn.

use crate::geometry::{Point, wrap_angle_rad};

/// Segments shorter than this have no direction: they are driven without turning.
const DEGENERATE_SEGMENT_M: f64 = 1e-12;

/// How far a unicycle agent may drive and turn in one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnicycleLimits {
    /// The longest drive in one step, metres.
    pub max_step_m: f64,
    /// The largest heading change in one step, radians.
    pub max_turn_rad: f64,
    /// Whether it may drive backwards.
    pub reverse: bool,
}

/// One step of a unicycle agent along a polyline.
#[derive(Clone, Debug, PartialEq)]
pub struct UnicycleMove {
    /// The polyline driven this step, from the start: a prefix of the one asked for.
    pub waypoints: Vec<Point>,
    /// The heading at the end of the step, radians in `(-pi, pi]`.
    pub end_heading_rad: f64,
    /// Whether the whole polyline (and the final turn, if one was asked for) was done.
    pub complete: bool,
}

/// The turn from heading `from_rad` to `to_rad` the short way, radians (at most pi).
fn turn_rad(from_rad: f64, to_rad: f64) -> f64 {
    wrap_angle_rad(to_rad - from_rad).abs()
}

/// The heading each segment of `waypoints` is driven at, starting from
/// `start_heading_rad` and ending at `end_heading_rad` if given, that makes the total
/// turning least (forward where reversing does no better), and that total, radians.
/// Degenerate segments (shorter than 1e-12 m) get `None`: they are driven without
/// turning.
///
/// ```
/// use shared::geometry::Point;
/// use shared::control::kinematics::driving_headings;
/// // Facing +x, a path to the left: a quarter turn forward, or with reverse as well.
/// let path = [Point::new(0.0, 0.0), Point::new(0.0, 1.0)];
/// let (headings, turn) = driving_headings(0.0, &path, None, false);
/// assert!((headings[0].unwrap() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// assert!((turn - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// // A path behind it: forward, a half turn; with reverse, none.
/// let behind = [Point::new(0.0, 0.0), Point::new(-1.0, 0.0)];
/// assert!((driving_headings(0.0, &behind, None, false).1 - std::f64::consts::PI).abs() < 1e-12);
/// assert_eq!(driving_headings(0.0, &behind, None, true).1, 0.0);
/// ```
pub fn driving_headings(
    start_heading_rad: f64,
    waypoints: &[Point],
    end_heading_rad: Option<f64>,
    reverse: bool,
) -> (Vec<Option<f64>>, f64) {
    let directions: Vec<Option<f64>> = waypoints
        .windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            (d.norm() > DEGENERATE_SEGMENT_M).then(|| d.y.atan2(d.x))
        })
        .collect();
    // Least turning so far ending with each choice (forward, backward) at each segment
    // with a direction; `from` remembers the choice before, to read the best one back.
    let choices = if reverse { 2 } else { 1 };
    let heading_of = |dir: f64, c: usize| wrap_angle_rad(dir + c as f64 * std::f64::consts::PI);
    let mut cost = [0.0, f64::INFINITY];
    let mut last: Option<f64> = None;
    let mut from: Vec<[usize; 2]> = Vec::new();
    for dir in directions.iter().flatten() {
        let mut next = [f64::INFINITY; 2];
        let mut back = [0usize; 2];
        for (c, slot) in next.iter_mut().enumerate().take(choices) {
            let h = heading_of(*dir, c);
            for (p, &so_far) in cost.iter().enumerate().take(choices) {
                let before = match last {
                    None if p == 0 => start_heading_rad,
                    None => continue,
                    Some(prev) => heading_of(prev, p),
                };
                let total = so_far + turn_rad(before, h);
                // Strictly less: on a tie the earlier (forward) choice stays.
                if total < *slot {
                    *slot = total;
                    back[c] = p;
                }
            }
        }
        cost = next;
        from.push(back);
        last = Some(*dir);
    }
    // The last choice, with the final turn counted.
    let final_turn = |c: usize| match (last, end_heading_rad) {
        (Some(dir), Some(end)) => turn_rad(heading_of(dir, c), end),
        (None, Some(end)) => turn_rad(start_heading_rad, end),
        (_, None) => 0.0,
    };
    let mut best = 0;
    let mut total = cost[0] + final_turn(0);
    if last.is_some() && choices == 2 && cost[1] + final_turn(1) < total {
        best = 1;
        total = cost[1] + final_turn(1);
    }
    // Read the choices back, last to first.
    let mut picked = vec![0usize; from.len()];
    let mut c = best;
    for k in (0..from.len()).rev() {
        picked[k] = c;
        c = from[k][c];
    }
    let mut picked = picked.into_iter();
    let headings = directions
        .iter()
        .map(|d| d.map(|dir| heading_of(dir, picked.next().unwrap_or(0))))
        .collect();
    (headings, total)
}

/// Drive `waypoints` (from where the agent stands, facing `start_heading_rad`) for one
/// step within `limits`, turning to `end_heading_rad` at the end if given.
///
/// ```
/// use shared::geometry::Point;
/// use shared::control::kinematics::{UnicycleLimits, drive_unicycle};
/// let limits = UnicycleLimits { max_step_m: 1.0, max_turn_rad: 2.0, reverse: false };
/// // A quarter turn (0.785 of the step) leaves 0.215 of it to drive: 0.215 m.
/// let path = [Point::new(0.0, 0.0), Point::new(0.0, 2.0)];
/// let mv = drive_unicycle(0.0, &path, None, &limits);
/// assert!(!mv.complete);
/// let end = mv.waypoints.last().unwrap();
/// assert!((end.y - (1.0 - std::f64::consts::FRAC_PI_4)).abs() < 1e-12);
/// ```
pub fn drive_unicycle(
    start_heading_rad: f64,
    waypoints: &[Point],
    end_heading_rad: Option<f64>,
    limits: &UnicycleLimits,
) -> UnicycleMove {
    let (headings, _) = driving_headings(
        start_heading_rad,
        waypoints,
        end_heading_rad,
        limits.reverse,
    );
    let mut heading = wrap_angle_rad(start_heading_rad);
    let mut share = 1.0;
    let Some(&first) = waypoints.first() else {
        return UnicycleMove {
            waypoints: Vec::new(),
            end_heading_rad: heading,
            complete: true,
        };
    };
    let mut driven = vec![first];
    // Turn towards `to` as far as the share left allows; whether the turn was done.
    let turn = |heading: &mut f64, share: &mut f64, to: f64| -> bool {
        let need = turn_rad(*heading, to) / limits.max_turn_rad;
        if need <= *share {
            *share -= need;
            *heading = wrap_angle_rad(to);
            return true;
        }
        let delta = wrap_angle_rad(to - *heading);
        *heading = wrap_angle_rad(*heading + delta.signum() * *share * limits.max_turn_rad);
        *share = 0.0;
        false
    };
    for (w, h) in waypoints.windows(2).zip(&headings) {
        if let Some(h) = h
            && !turn(&mut heading, &mut share, *h)
        {
            return UnicycleMove {
                waypoints: driven,
                end_heading_rad: heading,
                complete: false,
            };
        }
        let length_m = (w[1] - w[0]).norm();
        let need = length_m / limits.max_step_m;
        if need > share {
            let part_m = share * limits.max_step_m;
            driven.push(w[0] + (w[1] - w[0]) * (part_m / length_m));
            return UnicycleMove {
                waypoints: driven,
                end_heading_rad: heading,
                complete: false,
            };
        }
        share -= need;
        driven.push(w[1]);
    }
    let complete = match end_heading_rad {
        Some(end) => turn(&mut heading, &mut share, end),
        None => true,
    };
    UnicycleMove {
        waypoints: driven,
        end_heading_rad: heading,
        complete,
    }
}

/// The share of one step that driving `waypoints` from `start_heading_rad` and ending at
/// `end_heading_rad` takes at the least, within `limits`: a move is drivable in one step
/// if and only if this is at most 1 (up to rounding). The check of a move a unicycle
/// agent publishes.
///
/// ```
/// use shared::geometry::Point;
/// use shared::control::kinematics::{UnicycleLimits, drive_unicycle, unicycle_step_share};
/// let limits = UnicycleLimits { max_step_m: 0.5, max_turn_rad: 2.0, reverse: false };
/// // 0.2 m ahead (0.4 of the step), then a quarter turn left: 1.2 rad of it fit.
/// let path = [Point::new(0.0, 0.0), Point::new(0.2, 0.0), Point::new(0.2, 1.0)];
/// let mv = drive_unicycle(0.0, &path, None, &limits);
/// assert!(!mv.complete);
/// assert!((mv.end_heading_rad - 1.2).abs() < 1e-12);
/// let share = unicycle_step_share(0.0, &mv.waypoints, mv.end_heading_rad, &limits);
/// assert!((share - 1.0).abs() < 1e-9, "a move cut at the step's end takes all of it");
/// // The same polyline ending turned farther takes more than the step.
/// assert!(unicycle_step_share(0.0, &mv.waypoints, 2.0, &limits) > 1.0);
/// ```
pub fn unicycle_step_share(
    start_heading_rad: f64,
    waypoints: &[Point],
    end_heading_rad: f64,
    limits: &UnicycleLimits,
) -> f64 {
    let (_, turning_rad) = driving_headings(
        start_heading_rad,
        waypoints,
        Some(end_heading_rad),
        limits.reverse,
    );
    turning_rad / limits.max_turn_rad
        + crate::geometry::polyline_length_m(waypoints) / limits.max_step_m
}
