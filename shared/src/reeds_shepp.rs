//! Reeds-Shepp shortest paths: the shortest path between two poses for a car that turns no
//! tighter than a given radius and may drive both forwards and in reverse (Reeds & Shepp,
//! "Optimal paths for a car that goes both forwards and backwards", 1990).
//!
//! # Path words
//!
//! A path is a *word* of at most five segments. Each segment is either an arc of exactly the
//! minimum turning radius (`L` turns left, `R` turns right, `C` is either) or a straight line
//! (`S`), driven forwards (`+`) or in reverse (`-`); `|` marks a cusp, where the car changes
//! between forward and reverse. Reeds and Shepp proved that a shortest path is always one of
//! 48 words. Up to two symmetries they reduce to nine closed-form formulas (numbered as in
//! section 8 of the paper), grouped into five families:
//!
//! - **CSC** (8.1, 8.2): arc, straight, arc, all in the same direction, e.g. `L+ S+ L+`,
//!   `L+ S+ R+`. These are the Dubins words plus their all-reverse mirrors.
//! - **CCC** (8.3, 8.4): three arcs with one or two cusps, `C|C|C`, `C|CC` and `CC|C`.
//! - **CCCC** (8.7, 8.8): four arcs whose two middle arcs have the same length `u`,
//!   `C Cu|Cu C` and `C|Cu Cu|C`.
//! - **CCSC** (8.9, 8.10): `C|C(pi/2) S C` and its reverse `C S C(pi/2)|C`, where `C(pi/2)` is a
//!   quarter turn.
//! - **CCSCC** (8.11): `C|C(pi/2) S C(pi/2)|C`.
//!
//! Each formula solves for the base word (starting with `L+`) and is applied to the goal
//! under the two symmetries of the problem: *time-flip* (drive the word in reverse, which
//! negates every segment length) and *reflection* (mirror across the start heading, which
//! swaps `L` and `R`). The `CCC` and `CCSC` formulas are also applied *backwards* (the word
//! read from the goal to the start). That is 44 evaluations covering the 48 words.
//!
//! The solver follows OMPL's `ReedsSheppStateSpace` step by step (same formulas, same
//! acceptance tolerances, same evaluation order), so lengths agree with OMPL to rounding;
//! `tests/oracle_reeds_shepp.rs` checks this against OMPL 2.0.1.
//!
//! Paths are [`CurvePath`]s (module [`crate::curve`], shared with the Dubins solver); the
//! types are re-exported here, so `shared::reeds_shepp::CurvePath` names the same type.

use std::f64::consts::{PI, TAU};

pub use crate::curve::{CurvePath, Segment, Steer};
use crate::curve::{check_turning_radius, scaled_segment};
use crate::geometry::Pose;

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
    let segments = match solve(from, to, turning_radius_m) {
        Some(word) => word.segments(turning_radius_m).collect(),
        None => vec![Segment {
            steer: Steer::Straight,
            length_m: f64::NAN,
        }],
    };
    CurvePath {
        segments,
        turning_radius_m,
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
/// use shared::{dubins, reeds_shepp};
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

// ---------------------------------------------------------------------------------------
// The solver. Everything below works in the start pose's frame, scaled so that the turning
// radius is 1: the goal is (x, y, phi) and lengths are in units of the turning radius.
// Names (t, u, v, xi, eta, ...) follow the Reeds-Shepp paper, as OMPL does.
// ---------------------------------------------------------------------------------------

/// Acceptance tolerance of the formulas for "non-negative" and "non-positive" lengths
/// (OMPL's `ZERO`): a tiny wrong-signed length from rounding still counts.
const ZERO: f64 = 10.0 * f64::EPSILON;

/// A candidate word in normalized units: up to five steers with signed lengths.
#[derive(Clone, Copy, Debug)]
struct Word {
    steers: [Steer; 5],
    lengths: [f64; 5],
    count: usize,
    /// Sum of absolute lengths.
    total: f64,
}

impl Word {
    /// The placeholder before any word is found: infinitely long.
    const NONE: Word = Word {
        steers: [Steer::Straight; 5],
        lengths: [0.0; 5],
        count: 0,
        total: f64::INFINITY,
    };

    fn new<const N: usize>(steers: [Steer; N], lengths: [f64; N]) -> Self {
        let mut word = Word {
            count: N,
            total: 0.0,
            ..Word::NONE
        };
        word.steers[..N].copy_from_slice(&steers);
        word.lengths[..N].copy_from_slice(&lengths);
        word.total = word.lengths.iter().map(|l| l.abs()).sum();
        word
    }

    /// Time-flip: the same steers driven in the opposite direction.
    fn time_flipped(mut self) -> Self {
        for length in &mut self.lengths[..self.count] {
            *length = -*length;
        }
        self
    }

    /// Reflection across the start heading: left and right swapped.
    fn reflected(mut self) -> Self {
        for steer in &mut self.steers[..self.count] {
            *steer = steer.mirrored();
        }
        self
    }

    /// The word's non-negligible segments, scaled to metres.
    fn segments(&self, turning_radius_m: f64) -> impl Iterator<Item = Segment> + '_ {
        self.steers[..self.count]
            .iter()
            .zip(&self.lengths[..self.count])
            .filter_map(move |(steer, length)| scaled_segment(*steer, *length, turning_radius_m))
    }
}

/// Finds the shortest word from `from` to `to`; `None` only for non-finite input.
fn solve(from: &Pose, to: &Pose, turning_radius_m: f64) -> Option<Word> {
    let dx_m = to.x_m - from.x_m;
    let dy_m = to.y_m - from.y_m;
    let (sin, cos) = from.heading_rad.sin_cos();
    let x = (cos * dx_m + sin * dy_m) / turning_radius_m;
    let y = (-sin * dx_m + cos * dy_m) / turning_radius_m;
    let phi = to.heading_rad - from.heading_rad;
    let word = solve_normalized(x, y, phi);
    word.total.is_finite().then_some(word)
}

/// Minimum over all families, in OMPL's order (which only decides ties).
fn solve_normalized(x: f64, y: f64, phi: f64) -> Word {
    use Steer::{Left as L, Right as R, Straight as S};
    const HALF_PI: f64 = 0.5 * PI;
    let mut best = Word::NONE;
    // The goal as seen from the end of a word read backwards (for CC|C and C S C|C).
    let (sin_phi, cos_phi) = phi.sin_cos();
    let xb = x * cos_phi + y * sin_phi;
    let yb = x * sin_phi - y * cos_phi;

    // CSC: L+S+L+ and L+S+R+.
    let mut search = Search::new(&mut best, 0.0);
    search.all_symmetries((x, y, phi), lp_sp_lp, |t, u, v| {
        Word::new([L, S, L], [t, u, v])
    });
    search.all_symmetries((x, y, phi), lp_sp_rp, |t, u, v| {
        Word::new([L, S, R], [t, u, v])
    });

    // CCC: L+R-L(+/-), and the same read backwards.
    let mut search = Search::new(&mut best, 0.0);
    search.all_symmetries((x, y, phi), lp_rm_l, |t, u, v| {
        Word::new([L, R, L], [t, u, v])
    });
    search.all_symmetries((xb, yb, phi), lp_rm_l, |t, u, v| {
        Word::new([L, R, L], [v, u, t])
    });

    // CCCC: L+R+u L-u R- and L+R-u L-u R+ (the cost counts the middle length u twice).
    let mut search = Search::new(&mut best, 0.0).with_double_middle();
    search.all_symmetries((x, y, phi), lp_rup_lum_rm, |t, u, v| {
        Word::new([L, R, L, R], [t, u, -u, v])
    });
    search.all_symmetries((x, y, phi), lp_rum_lum_rp, |t, u, v| {
        Word::new([L, R, L, R], [t, u, u, v])
    });

    // CCSC: L+R-(pi/2) S- L- and L+R-(pi/2) S- R-, and both read backwards.
    let mut search = Search::new(&mut best, HALF_PI);
    search.all_symmetries((x, y, phi), lp_rm_sm_lm, |t, u, v| {
        Word::new([L, R, S, L], [t, -HALF_PI, u, v])
    });
    search.all_symmetries((x, y, phi), lp_rm_sm_rm, |t, u, v| {
        Word::new([L, R, S, R], [t, -HALF_PI, u, v])
    });
    search.all_symmetries((xb, yb, phi), lp_rm_sm_lm, |t, u, v| {
        Word::new([L, S, R, L], [v, u, -HALF_PI, t])
    });
    search.all_symmetries((xb, yb, phi), lp_rm_sm_rm, |t, u, v| {
        Word::new([R, S, R, L], [v, u, -HALF_PI, t])
    });

    // CCSCC: L+R-(pi/2) S- L-(pi/2) R+.
    let mut search = Search::new(&mut best, PI);
    search.all_symmetries((x, y, phi), lp_rm_s_lm_rp, |t, u, v| {
        Word::new([L, R, S, L, R], [t, -HALF_PI, u, -HALF_PI, v])
    });

    best
}

/// One family's search state, mirroring OMPL: a candidate replaces the best word when its
/// formula cost `|t| + |u| + |v|` (or `|t| + 2|u| + |v|` for CCCC) is below `bound`, which
/// starts at the best total minus the family's fixed arc lengths.
struct Search<'a> {
    best: &'a mut Word,
    bound: f64,
    double_middle: bool,
}

impl<'a> Search<'a> {
    fn new(best: &'a mut Word, fixed_arcs: f64) -> Self {
        let bound = best.total - fixed_arcs;
        Search {
            best,
            bound,
            double_middle: false,
        }
    }

    fn with_double_middle(mut self) -> Self {
        self.double_middle = true;
        self
    }

    /// Tries `formula` on the goal and on its time-flipped, reflected, and time-flipped and
    /// reflected images; `build` turns a base solution into its word.
    fn all_symmetries(
        &mut self,
        (x, y, phi): (f64, f64, f64),
        formula: Formula,
        build: fn(f64, f64, f64) -> Word,
    ) {
        for (time_flip, reflect) in [(false, false), (true, false), (false, true), (true, true)] {
            let xs = if time_flip { -x } else { x };
            let ys = if reflect { -y } else { y };
            let phis = if time_flip != reflect { -phi } else { phi };
            let Some((t, u, v)) = formula(xs, ys, phis) else {
                continue;
            };
            let middle_weight = if self.double_middle { 2.0 } else { 1.0 };
            let cost = t.abs() + middle_weight * u.abs() + v.abs();
            if self.bound > cost {
                let mut word = build(t, u, v);
                if time_flip {
                    word = word.time_flipped();
                }
                if reflect {
                    word = word.reflected();
                }
                *self.best = word;
                self.bound = cost;
            }
        }
    }
}

/// The three free lengths `(t, u, v)` of a base word, in units of the turning radius.
type Lengths = (f64, f64, f64);

/// A closed-form solution for one base word: from the goal `(x, y, phi)` to the word's free
/// lengths, or `None` when the word cannot reach the goal.
type Formula = fn(f64, f64, f64) -> Option<Lengths>;

/// Wraps an angle into `[-pi, pi]` (OMPL's `mod2pi`).
fn mod2pi(angle: f64) -> f64 {
    let v = angle % TAU;
    if v < -PI {
        v + TAU
    } else if v > PI {
        v - TAU
    } else {
        v
    }
}

/// Polar coordinates `(r, theta)` of `(x, y)`.
fn polar(x: f64, y: f64) -> (f64, f64) {
    ((x * x + y * y).sqrt(), y.atan2(x))
}

/// The outer arc angles `(tau, omega)` of the CCCC words given the middle arcs `u`, `v`.
fn tau_omega(u: f64, v: f64, xi: f64, eta: f64, phi: f64) -> (f64, f64) {
    let delta = mod2pi(u - v);
    let a = u.sin() - delta.sin();
    let b = u.cos() - delta.cos() - 1.0;
    let t1 = (eta * a - xi * b).atan2(xi * a + eta * b);
    let t2 = 2.0 * (delta.cos() - v.cos() - u.cos()) + 3.0;
    let tau = if t2 < 0.0 {
        mod2pi(t1 + PI)
    } else {
        mod2pi(t1)
    };
    let omega = mod2pi(tau - u + v - phi);
    (tau, omega)
}

/// Formula 8.1, `L+ S+ L+`.
fn lp_sp_lp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let (u, t) = polar(x - phi.sin(), y - 1.0 + phi.cos());
    if t >= -ZERO {
        let v = mod2pi(phi - t);
        if v >= -ZERO {
            return Some((t, u, v));
        }
    }
    None
}

/// Formula 8.2, `L+ S+ R+`.
fn lp_sp_rp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let (u1, t1) = polar(x + phi.sin(), y - 1.0 - phi.cos());
    let u1_sq = u1 * u1;
    if u1_sq >= 4.0 {
        let u = (u1_sq - 4.0).sqrt();
        let theta = 2.0_f64.atan2(u);
        let t = mod2pi(t1 + theta);
        let v = mod2pi(t - phi);
        return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
    }
    None
}

/// Formulas 8.3/8.4 (with the paper's typo corrected), `L+ R- L`.
fn lp_rm_l(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x - phi.sin();
    let eta = y - 1.0 + phi.cos();
    let (u1, theta) = polar(xi, eta);
    if u1 <= 4.0 {
        let u = -2.0 * (0.25 * u1).asin();
        let t = mod2pi(theta + 0.5 * u + PI);
        let v = mod2pi(phi - t + u);
        return (t >= -ZERO && u <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.7, `L+ R+u L-u R-`.
fn lp_rup_lum_rm(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let rho = 0.25 * (2.0 + (xi * xi + eta * eta).sqrt());
    if rho <= 1.0 {
        let u = rho.acos();
        let (t, v) = tau_omega(u, -u, xi, eta, phi);
        return (t >= -ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.8, `L+ R-u L-u R+`.
fn lp_rum_lum_rp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let rho = (20.0 - xi * xi - eta * eta) / 16.0;
    if (0.0..=1.0).contains(&rho) {
        let u = -rho.acos();
        if u >= -0.5 * PI {
            let (t, v) = tau_omega(u, u, xi, eta, phi);
            return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
        }
    }
    None
}

/// Formula 8.9, `L+ R-(pi/2) S- L-`.
fn lp_rm_sm_lm(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x - phi.sin();
    let eta = y - 1.0 + phi.cos();
    let (rho, theta) = polar(xi, eta);
    if rho >= 2.0 {
        let r = (rho * rho - 4.0).sqrt();
        let u = 2.0 - r;
        let t = mod2pi(theta + r.atan2(-2.0));
        let v = mod2pi(phi - 0.5 * PI - t);
        return (t >= -ZERO && u <= ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.10, `L+ R-(pi/2) S- R-`.
fn lp_rm_sm_rm(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let (rho, theta) = polar(-eta, xi);
    if rho >= 2.0 {
        let t = theta;
        let u = 2.0 - rho;
        let v = mod2pi(t + 0.5 * PI - phi);
        return (t >= -ZERO && u <= ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.11 (with the paper's typo corrected), `L+ R-(pi/2) S- L-(pi/2) R+`.
fn lp_rm_s_lm_rp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let (rho, _theta) = polar(xi, eta);
    if rho >= 2.0 {
        let u = 4.0 - (rho * rho - 4.0).sqrt();
        if u <= ZERO {
            let t = mod2pi(((4.0 - u) * xi - 2.0 * eta).atan2(-2.0 * xi + (u - 4.0) * eta));
            let v = mod2pi(t - phi);
            return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::wrap_angle_rad;

    const TOLERANCE: f64 = 1e-9;

    fn assert_pose_close(actual: &Pose, expected: &Pose) {
        assert!(
            (actual.x_m - expected.x_m).abs() < TOLERANCE
                && (actual.y_m - expected.y_m).abs() < TOLERANCE
                && wrap_angle_rad(actual.heading_rad - expected.heading_rad).abs() < TOLERANCE,
            "{actual:?} != {expected:?}"
        );
    }

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
