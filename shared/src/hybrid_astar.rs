//! Hybrid A* for the formation centre: a curvature-bounded path from a start pose to a goal
//! pose among disk obstacles (Dolgov et al. 2008; Navigation2's Smac Hybrid-A* planner is
//! the production reference this follows).
//!
//! The search runs over cells of (x, y, heading bin) but keeps one *continuous* pose per
//! cell, the cheapest found so far. A node is expanded with arcs of curvature `-1/rho`, `0`
//! and `+1/rho` (and the same arcs driven backwards when reverse is allowed, penalised),
//! each long enough to leave its cell. The heuristic is the larger of two lower bounds on
//! the remaining length:
//!
//! - the Reeds-Shepp (or, forward only, Dubins) length to the goal, ignoring obstacles;
//! - the obstacle-aware length for a point that may turn on the spot, from a lazy 2-D
//!   Dijkstra over a grid of the field grown from the goal (`pathfinding::dijkstra_reach`),
//!   scaled by `cos(pi/8)` (the worst stretch of an 8-connected grid path over a straight
//!   line) less one cell diagonal, so that it does not overestimate.
//!
//! Before searching, a flood fill over a grid of the search cells marks the cells from
//! which the goal can be reached at all (a cell is closed only when the inflated obstacles
//! or the field's edges cover it whole): poses outside are never queued, and a start
//! outside gives [`PlanError::NoPath`] at once, not an exhausted search.
//!
//! As the search closes in on the goal it tries the analytic expansion (the Reeds-Shepp or
//! Dubins path straight to the goal) more and more often, as Smac does, and finishes with
//! the first one that is collision free.
//!
//! Collision checks are exact, not sampled: every arc and every chord of the returned
//! polyline keeps at least `clearance_m` from every obstacle's boundary (touching is
//! allowed) and stays in the field inset by `clearance_m`. The returned path is dense
//! (poses every [`HybridAStarSettings::sample_spacing_m`] at most), so the polyline through
//! its poses and the true curve differ by millimetres, and both are safe.
//!
//! The search is deterministic: no hash-map iteration, and the open list breaks ties on
//! cost then on insertion order.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::f64::consts::{FRAC_PI_2, PI, SQRT_2, TAU};
use std::hash::{BuildHasherDefault, Hasher};
use std::ops::ControlFlow;

use pathfinding::directed::dijkstra::{DijkstraReachable, dijkstra_reach};

use crate::curve::{CurvePath, Steer};
use crate::dubins;
use crate::geometry::{
    Disk, DiskGrid, Field, Point, Pose, Vector, distance_point_segment, wrap_angle_rad,
};
use crate::ordered::TotalF64;
use crate::reeds_shepp;

/// Settings of the Hybrid A* search. [`HybridAStarSettings::new`] gives sensible defaults
/// for a turning radius and a clearance; every field may then be tuned.
#[derive(Clone, Debug, PartialEq)]
pub struct HybridAStarSettings {
    /// Minimum turning radius of the path, in metres (the curvature never exceeds its
    /// inverse).
    pub turning_radius_m: f64,
    /// Whether the path may drive backwards (Reeds-Shepp) or only forwards (Dubins).
    pub allow_reverse: bool,
    /// Distance the path keeps from every obstacle's boundary and from the field's edges,
    /// in metres.
    pub clearance_m: f64,
    /// Number of heading bins of the search cells (72 = 5 degrees).
    pub heading_bins: usize,
    /// Side of the search cells in x and y, in metres (default: a quarter of the turning
    /// radius, within 0.1..=1 m). Motion primitives are one cell diagonal long (longer if
    /// needed to turn by one heading bin).
    pub cell_m: f64,
    /// The obstacle-aware heuristic's Dijkstra runs on cells of `heuristic_downsample`
    /// search cells a side (default 2, as Smac downsamples its costmap; 1..=64). Coarser
    /// is faster and a weaker bound. (Whether the goal can be reached at all is decided on
    /// the finer grid of `cell_m`.)
    pub heuristic_downsample: usize,
    /// Largest arc length between two consecutive poses of the returned path, in metres
    /// (default: the least of a quarter cell, a sixteenth of the turning radius and half
    /// the clearance).
    pub sample_spacing_m: f64,
    /// Cost multiplier of driving backwards (>= 1; Smac's default 2).
    pub reverse_penalty: f64,
    /// Cost multiplier of the turning primitives (>= 1; Smac's `non_straight_penalty`).
    pub turn_penalty: f64,
    /// Cost added at each change between forward and reverse, in metres (>= 0).
    pub direction_change_penalty_m: f64,
    /// Controls how often the analytic expansion is tried: every
    /// `max(d / ratio, ceil(ratio))` expansions, `d` being the smallest heuristic seen so far
    /// in cells (Smac's `analytic_expansion_ratio`, default 3.5). Smaller tries more often.
    pub analytic_expansion_ratio: f64,
    /// Node expansions after which the search gives up with
    /// [`PlanError::ExpansionLimit`].
    pub max_expansions: usize,
}

impl HybridAStarSettings {
    /// Defaults for a turning radius and a clearance, both in metres: 72 heading bins,
    /// cells of a quarter turning radius (0.1..=1 m), reverse costing twice forward,
    /// a direction change costing one turning radius, turns costing 5 % more than straight,
    /// 300 000 expansions at most.
    pub fn new(turning_radius_m: f64, clearance_m: f64, allow_reverse: bool) -> Self {
        let cell_m = if turning_radius_m.is_finite() {
            (0.25 * turning_radius_m).clamp(0.1, 1.0)
        } else {
            1.0
        };
        let mut sample_spacing_m = (0.25 * cell_m).min(turning_radius_m / 16.0);
        if clearance_m > 0.0 {
            sample_spacing_m = sample_spacing_m.min(0.5 * clearance_m);
        }
        Self {
            turning_radius_m,
            allow_reverse,
            clearance_m,
            heading_bins: 72,
            cell_m,
            heuristic_downsample: 2,
            sample_spacing_m,
            reverse_penalty: 2.0,
            turn_penalty: 1.05,
            direction_change_penalty_m: turning_radius_m,
            analytic_expansion_ratio: 3.5,
            max_expansions: 300_000,
        }
    }

    /// Check every field; the message names the first bad one.
    pub fn validate(&self) -> Result<(), PlanError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.turning_radius_m) {
            return Err(PlanError::InvalidSettings(
                "turning_radius_m must be positive and finite",
            ));
        }
        if !(self.clearance_m.is_finite() && self.clearance_m >= 0.0) {
            return Err(PlanError::InvalidSettings(
                "clearance_m must be finite and >= 0",
            ));
        }
        if !(4..=1 << 16).contains(&self.heading_bins) {
            return Err(PlanError::InvalidSettings(
                "heading_bins must be within 4..=65536",
            ));
        }
        if !positive(self.cell_m) {
            return Err(PlanError::InvalidSettings(
                "cell_m must be positive and finite",
            ));
        }
        if !(1..=64).contains(&self.heuristic_downsample) {
            return Err(PlanError::InvalidSettings(
                "heuristic_downsample must be within 1..=64",
            ));
        }
        if !positive(self.sample_spacing_m) {
            return Err(PlanError::InvalidSettings(
                "sample_spacing_m must be positive and finite",
            ));
        }
        if !(self.reverse_penalty.is_finite() && self.reverse_penalty >= 1.0) {
            return Err(PlanError::InvalidSettings(
                "reverse_penalty must be finite and >= 1",
            ));
        }
        if !(self.turn_penalty.is_finite() && self.turn_penalty >= 1.0) {
            return Err(PlanError::InvalidSettings(
                "turn_penalty must be finite and >= 1",
            ));
        }
        if !(self.direction_change_penalty_m.is_finite() && self.direction_change_penalty_m >= 0.0)
        {
            return Err(PlanError::InvalidSettings(
                "direction_change_penalty_m must be finite and >= 0",
            ));
        }
        if !positive(self.analytic_expansion_ratio) {
            return Err(PlanError::InvalidSettings(
                "analytic_expansion_ratio must be positive and finite",
            ));
        }
        if self.max_expansions == 0 {
            return Err(PlanError::InvalidSettings(
                "max_expansions must be at least 1",
            ));
        }
        Ok(())
    }

    /// Arc length of the motion primitives, in metres: one cell diagonal, or enough to turn
    /// by one heading bin if that is longer.
    pub fn primitive_length_m(&self) -> f64 {
        (SQRT_2 * self.cell_m).max(self.turning_radius_m * TAU / self.heading_bins as f64)
    }
}

/// Why [`plan`] found no path.
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
pub enum PlanError {
    /// The start pose is not finite, lies outside the field inset by the clearance, or
    /// within the clearance of an obstacle.
    #[error("the start pose is blocked (outside the field or too close to an obstacle)")]
    StartBlocked,
    /// The goal pose is not finite, lies outside the field inset by the clearance, or
    /// within the clearance of an obstacle.
    #[error("the goal pose is blocked (outside the field or too close to an obstacle)")]
    GoalBlocked,
    /// No collision-free path exists at the search's resolution: the goal is walled off
    /// from the start, or every way is too tight for the turning radius.
    #[error("no collision-free path from the start to the goal")]
    NoPath,
    /// The search expanded `max_expansions` nodes without reaching the goal.
    #[error("no path found within {expansions} expansions")]
    ExpansionLimit {
        /// Number of nodes expanded.
        expansions: usize,
    },
    /// A setting, the field or an obstacle is out of range (the message says which).
    #[error("invalid planner input: {0}")]
    InvalidSettings(&'static str),
}

/// Figures of one successful search.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanStats {
    /// Nodes expanded.
    pub expansions: usize,
    /// Analytic expansions tried (the last one succeeded).
    pub analytic_attempts: usize,
    /// Length of the returned path (sum of the distances between its poses), in metres.
    pub length_m: f64,
}

/// Plan a path for the formation centre from `start` to `goal`.
///
/// `obstacles` are the true obstacles (not inflated): the path keeps
/// `settings.clearance_m` from every obstacle's boundary and from the field's edges. The
/// result is dense (consecutive poses at most `settings.sample_spacing_m` apart along the
/// path), begins with `start` and ends with `goal`, both exactly as given; feed it to
/// [`resample`] for evenly spaced steps.
///
/// ```
/// use shared::geometry::{Disk, Field, Pose};
/// use shared::hybrid_astar::{HybridAStarSettings, plan, resample};
///
/// let field = Field::new(40.0, 30.0);
/// let obstacles = [Disk::new(20.0, 15.0, 2.0)];
/// let settings = HybridAStarSettings::new(2.0, 0.5, false);
/// let (start, goal) = (Pose::new(5.0, 15.0, 0.0), Pose::new(35.0, 15.0, 0.0));
/// let path = plan(&field, &obstacles, &start, &goal, &settings)?;
/// assert_eq!(path.last(), Some(&goal));
/// let steps = resample(&path, 0.25);
/// assert_eq!(steps[0], start);
/// # Ok::<(), shared::hybrid_astar::PlanError>(())
/// ```
pub fn plan(
    field: &Field,
    obstacles: &[Disk],
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
) -> Result<Vec<Pose>, PlanError> {
    plan_with_stats(field, obstacles, start, goal, settings).map(|(path, _)| path)
}

/// [`plan`], also returning the search's figures.
pub fn plan_with_stats(
    field: &Field,
    obstacles: &[Disk],
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
) -> Result<(Vec<Pose>, PlanStats), PlanError> {
    settings.validate()?;
    if !(field.width_m.is_finite()
        && field.height_m.is_finite()
        && field.width_m > 0.0
        && field.height_m > 0.0)
    {
        return Err(PlanError::InvalidSettings(
            "the field must have a positive finite size",
        ));
    }
    if obstacles.iter().any(|d| {
        !(d.center.x.is_finite()
            && d.center.y.is_finite()
            && d.radius_m.is_finite()
            && d.radius_m >= 0.0)
    }) {
        return Err(PlanError::InvalidSettings(
            "obstacles must be finite with a radius >= 0",
        ));
    }
    let grid_cells =
        (field.width_m / settings.cell_m).ceil() * (field.height_m / settings.cell_m).ceil();
    if grid_cells > MAX_GRID_CELLS {
        return Err(PlanError::InvalidSettings(
            "cell_m is too small for the field (over 2^24 cells)",
        ));
    }

    let mut checker = Checker::new(field, obstacles, settings);
    let finite = |p: &Pose| p.x_m.is_finite() && p.y_m.is_finite() && p.heading_rad.is_finite();
    if !finite(start) || !checker.point_free(&start.position()) {
        return Err(PlanError::StartBlocked);
    }
    if !finite(goal) || !checker.point_free(&goal.position()) {
        return Err(PlanError::GoalBlocked);
    }
    // The straight shot first, before paying for the heuristic grid.
    if let Some(tail) = analytic_expansion(&mut checker, settings, start, goal) {
        let path = dense_path(
            start,
            goal,
            tail.iter().map(|p| (*p, p.end())),
            settings.sample_spacing_m,
        );
        let length_m = path_length_m(&path);
        let stats = PlanStats {
            expansions: 0,
            analytic_attempts: 1,
            length_m,
        };
        return Ok((path, stats));
    }
    let holonomic = Holonomic::new(field, &checker, goal, settings);
    Search::new(field, checker, holonomic, start, goal, settings).run()
}

/// The curve path (Reeds-Shepp, or Dubins when forward only) from `from` to `goal` as
/// pieces, if it is free and ends at the goal.
fn analytic_expansion(
    checker: &mut Checker,
    settings: &HybridAStarSettings,
    from: &Pose,
    goal: &Pose,
) -> Option<Vec<Piece>> {
    let rho = settings.turning_radius_m;
    let curve: CurvePath = if settings.allow_reverse {
        reeds_shepp::shortest_path(from, goal, rho)
    } else {
        dubins::shortest_path(from, goal, rho)
    };
    let mut pieces = Vec::with_capacity(curve.segments.len());
    let mut pose = *from;
    for segment in &curve.segments {
        if !segment.length_m.is_finite() {
            return None;
        }
        if segment.length_m == 0.0 {
            continue;
        }
        let curvature_per_m = match segment.steer {
            Steer::Left => 1.0 / curve.turning_radius_m,
            Steer::Straight => 0.0,
            Steer::Right => -1.0 / curve.turning_radius_m,
        };
        let piece = Piece {
            start: pose,
            curvature_per_m,
            length_m: segment.length_m,
        };
        if !checker.piece_free(&piece) {
            return None;
        }
        pose = piece.end();
        pieces.push(piece);
    }
    // Guard against a curve path that does not end at the goal.
    let gap_m = (pose.position() - goal.position()).norm();
    let gap_rad = wrap_angle_rad(pose.heading_rad - goal.heading_rad).abs();
    (gap_m <= 1e-7 && gap_rad <= 1e-7).then_some(pieces)
}

/// The dense path through `pieces` (each with its exact end pose): `start`, poses at most
/// `spacing_m` apart, and `goal` exactly in place of the last end pose.
fn dense_path(
    start: &Pose,
    goal: &Pose,
    pieces: impl Iterator<Item = (Piece, Pose)>,
    spacing_m: f64,
) -> Vec<Pose> {
    let mut path = vec![*start];
    for (piece, end) in pieces {
        let n = ((piece.length_m.abs() / spacing_m).ceil() as usize).max(1);
        for i in 1..n {
            path.push(piece.pose_at(piece.length_m * i as f64 / n as f64));
        }
        path.push(end);
    }
    if path.len() > 1 {
        let last = path.len() - 1;
        path[last] = *goal;
    } else {
        path.push(*goal);
    }
    path
}

/// Poses every `step_m` of arc length along `path` (read as the polyline through its
/// poses): the first is `path[0]`, the last is the last pose of `path` exactly, the last
/// step may be shorter. Positions are interpolated linearly, headings along the shorter
/// way round. A `step_m` that is not positive and finite returns `path` unchanged.
pub fn resample(path: &[Pose], step_m: f64) -> Vec<Pose> {
    let (Some(first), Some(last)) = (path.first(), path.last()) else {
        return Vec::new();
    };
    if !(step_m.is_finite() && step_m > 0.0) || path.len() == 1 {
        return path.to_vec();
    }
    let total_m = path_length_m(path);
    let mut out = vec![*first];
    // Arc length of the next pose to emit, and of the start of the current segment.
    let mut k = 1usize;
    let mut travelled_m = 0.0;
    for pair in path.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let length_m = (b.position() - a.position()).norm();
        if length_m == 0.0 {
            continue;
        }
        loop {
            let target_m = k as f64 * step_m;
            // Stop before the end: the last pose is always `last` itself.
            if target_m > travelled_m + length_m || target_m >= total_m - 1e-9 {
                break;
            }
            let t = ((target_m - travelled_m) / length_m).clamp(0.0, 1.0);
            let dh = wrap_angle_rad(b.heading_rad - a.heading_rad);
            out.push(Pose::new(
                a.x_m + t * (b.x_m - a.x_m),
                a.y_m + t * (b.y_m - a.y_m),
                wrap_angle_rad(a.heading_rad + t * dh),
            ));
            k += 1;
        }
        travelled_m += length_m;
    }
    out.push(*last);
    out
}

/// Length of the polyline through the poses of `path`, in metres.
pub fn path_length_m(path: &[Pose]) -> f64 {
    path.windows(2)
        .map(|w| (w[1].position() - w[0].position()).norm())
        .sum()
}

// ---------------------------------------------------------------------------------------
// Geometry of constant-curvature pieces.

/// A piece of constant curvature: from `start`, drive `length_m` (negative = backwards)
/// with signed curvature `curvature_per_m` (positive turns left when driving forwards).
#[derive(Clone, Copy, Debug)]
struct Piece {
    start: Pose,
    curvature_per_m: f64,
    length_m: f64,
}

impl Piece {
    /// The pose after `s_m` of signed arc length (same sign convention as `length_m`).
    fn pose_at(&self, s_m: f64) -> Pose {
        let Pose {
            x_m,
            y_m,
            heading_rad: h,
        } = self.start;
        let k = self.curvature_per_m;
        if k == 0.0 {
            Pose::new(x_m + s_m * h.cos(), y_m + s_m * h.sin(), h)
        } else {
            let h1 = h + k * s_m;
            Pose::new(
                x_m + (h1.sin() - h.sin()) / k,
                y_m - (h1.cos() - h.cos()) / k,
                wrap_angle_rad(h1),
            )
        }
    }

    fn end(&self) -> Pose {
        self.pose_at(self.length_m)
    }

    /// Centre of the turning circle, the angle of the start point seen from it, and the
    /// signed angle swept (only for arcs).
    fn circle(&self) -> (Point, f64, f64) {
        let k = self.curvature_per_m;
        let h = self.start.heading_rad;
        let center = Point::new(self.start.x_m - h.sin() / k, self.start.y_m + h.cos() / k);
        let phi0 = (self.start.y_m - center.y).atan2(self.start.x_m - center.x);
        (center, phi0, k * self.length_m)
    }

    /// Whether the angle `angle_rad` (seen from the circle's centre) lies on the arc.
    fn sweeps(phi0: f64, sweep: f64, angle_rad: f64) -> bool {
        if sweep.abs() >= TAU {
            return true;
        }
        let rel = ((angle_rad - phi0) * sweep.signum()).rem_euclid(TAU);
        rel <= sweep.abs()
    }

    /// Axis-aligned bounding box of the piece.
    fn bounding_box(&self) -> (Point, Point) {
        let a = self.start.position();
        let b = self.end().position();
        let mut min = Point::new(a.x.min(b.x), a.y.min(b.y));
        let mut max = Point::new(a.x.max(b.x), a.y.max(b.y));
        if self.curvature_per_m != 0.0 {
            let (center, phi0, sweep) = self.circle();
            let r = 1.0 / self.curvature_per_m.abs();
            for (i, extreme) in [
                (0, center.x + r),
                (1, center.y + r),
                (2, center.x - r),
                (3, center.y - r),
            ] {
                if Self::sweeps(phi0, sweep, i as f64 * FRAC_PI_2) {
                    match i {
                        0 => max.x = max.x.max(extreme),
                        1 => max.y = max.y.max(extreme),
                        2 => min.x = min.x.min(extreme),
                        _ => min.y = min.y.min(extreme),
                    }
                }
            }
        }
        (min, max)
    }

    /// Smallest distance from `p` to the piece (exact).
    fn distance_m(&self, p: &Point) -> f64 {
        let a = self.start.position();
        let b = self.end().position();
        if self.curvature_per_m == 0.0 {
            return distance_point_segment(p, &a, &b);
        }
        let (center, phi0, sweep) = self.circle();
        let r = 1.0 / self.curvature_per_m.abs();
        let d = p - center;
        let dn = d.norm();
        if dn == 0.0 {
            return r;
        }
        if Self::sweeps(phi0, sweep, d.y.atan2(d.x)) {
            (dn - r).abs()
        } else {
            (p - a).norm().min((p - b).norm())
        }
    }

    /// Number of chords the piece is drawn with at `spacing_m`.
    fn chords(&self, spacing_m: f64) -> usize {
        if self.curvature_per_m == 0.0 {
            1
        } else {
            ((self.length_m.abs() / spacing_m).ceil() as usize).max(1)
        }
    }
}

// ---------------------------------------------------------------------------------------
// Collision checking.

/// Exact collision checks against the obstacles inflated by the clearance and the field
/// inset by it.
struct Checker {
    grid: DiskGrid,
    min: Point,
    max: Point,
    spacing_m: f64,
    candidates: Vec<Disk>,
}

impl Checker {
    fn new(field: &Field, obstacles: &[Disk], settings: &HybridAStarSettings) -> Self {
        let c = settings.clearance_m;
        Self {
            grid: DiskGrid::new(obstacles.iter().map(|d| d.inflated(c)).collect()),
            min: Point::new(c, c),
            max: Point::new(field.width_m - c, field.height_m - c),
            spacing_m: settings.sample_spacing_m,
            candidates: Vec::new(),
        }
    }

    fn in_field(&self, p: &Point) -> bool {
        p.x >= self.min.x && p.y >= self.min.y && p.x <= self.max.x && p.y <= self.max.y
    }

    fn point_free(&self, p: &Point) -> bool {
        self.in_field(p)
            && self
                .grid
                .visit_near(p, 0.0, |_, d| {
                    if (p - d.center).norm() < d.radius_m {
                        ControlFlow::Break(())
                    } else {
                        ControlFlow::Continue(())
                    }
                })
                .is_continue()
    }

    /// Whether the piece and every chord it is drawn with are free.
    fn piece_free(&mut self, piece: &Piece) -> bool {
        let (min, max) = piece.bounding_box();
        if !(self.in_field(&min) && self.in_field(&max)) {
            return false;
        }
        self.candidates.clear();
        let candidates = &mut self.candidates;
        let _ = self.grid.visit_box(&min, &max, |_, d| {
            candidates.push(*d);
            ControlFlow::<()>::Continue(())
        });
        if self.candidates.is_empty() {
            return true;
        }
        if self
            .candidates
            .iter()
            .any(|d| piece.distance_m(&d.center) < d.radius_m)
        {
            return false;
        }
        if piece.curvature_per_m == 0.0 {
            return true;
        }
        // The chords of the returned polyline cut inside the arc: check them too.
        let n = piece.chords(self.spacing_m);
        let mut a = piece.start.position();
        for i in 1..=n {
            let b = if i == n {
                piece.end().position()
            } else {
                piece
                    .pose_at(piece.length_m * i as f64 / n as f64)
                    .position()
            };
            if self
                .candidates
                .iter()
                .any(|d| distance_point_segment(&d.center, &a, &b) < d.radius_m)
            {
                return false;
            }
            a = b;
        }
        true
    }
}

// ---------------------------------------------------------------------------------------
// The holonomic-with-obstacles heuristic.

/// Up to eight grid neighbours with their step costs.
struct Neighbours {
    items: [(u32, u32); 8],
    len: usize,
    next: usize,
}

impl Iterator for Neighbours {
    type Item = (u32, u32);
    fn next(&mut self) -> Option<(u32, u32)> {
        (self.next < self.len).then(|| {
            self.next += 1;
            self.items[self.next - 1]
        })
    }
}

/// Grid step costs: 1000 per straight step, 1414 per diagonal (rounded down, so never an
/// overestimate).
const STRAIGHT_COST: u32 = 1000;
const DIAGONAL_COST: u32 = 1414;

/// A fine cell is blocked when each of its `COVER_SPLIT x COVER_SPLIT` sub-squares lies
/// inside one obstacle.
const COVER_SPLIT: usize = 4;

/// Largest number of cells of the connectivity grid.
const MAX_GRID_CELLS: f64 = (1u64 << 24) as f64;

/// Square cells of side `cell_m` tiling the field from the origin, row by row.
#[derive(Clone, Copy, Debug)]
struct Grid {
    columns: usize,
    rows: usize,
    cell_m: f64,
}

impl Grid {
    fn column_row(&self, cell: usize) -> (usize, usize) {
        (cell % self.columns, cell / self.columns)
    }

    fn cell_of(&self, p: &Point) -> usize {
        let to_cell = |v: f64, n: usize| ((v / self.cell_m).floor().max(0.0) as usize).min(n - 1);
        to_cell(p.y, self.rows) * self.columns + to_cell(p.x, self.columns)
    }

    /// The 8-neighbours of `cell` that are not blocked, with their step costs. A diagonal
    /// step between two blocked cells is refused: their shared corner is not free.
    fn neighbours(&self, cell: usize, blocked: &[bool]) -> Neighbours {
        let (c, r) = self.column_row(cell);
        let mut out = Neighbours {
            items: [(0, 0); 8],
            len: 0,
            next: 0,
        };
        for (dc, dr) in [
            (-1i64, -1i64),
            (0, -1),
            (1, -1),
            (-1, 0),
            (1, 0),
            (-1, 1),
            (0, 1),
            (1, 1),
        ] {
            let (nc, nr) = (c as i64 + dc, r as i64 + dr);
            if nc < 0 || nr < 0 || nc >= self.columns as i64 || nr >= self.rows as i64 {
                continue;
            }
            let (nc, nr) = (nc as usize, nr as usize);
            let n = nr * self.columns + nc;
            let diagonal = dc != 0 && dr != 0;
            if blocked[n]
                || (diagonal && blocked[r * self.columns + nc] && blocked[nr * self.columns + c])
            {
                continue;
            }
            let step = if diagonal {
                DIAGONAL_COST
            } else {
                STRAIGHT_COST
            };
            out.items[out.len] = (n as u32, step);
            out.len += 1;
        }
        out
    }
}

type Successors = Box<dyn FnMut(&u32) -> Neighbours>;

/// The obstacle-aware lower bound, on two grids.
///
/// The fine grid (cells of `cell_m`) blocks only the cells no free point can occupy: wholly
/// outside the inset field, or covered by the inflated obstacles. Every free path therefore
/// crosses free cells only, from each to an 8-neighbour, so the flood fill of the free cells
/// from the goal's cell holds every point from which the goal can be reached: a pose
/// outside it has no path (`NoPath` at once, rather than an exhausted search).
///
/// The coarse grid (`heuristic_downsample` fine cells a side, as Smac downsamples its
/// costmap) opens the cells holding a reachable fine cell, and a lazy Dijkstra
/// (`pathfinding::dijkstra_reach`) grows from the goal's cell as far as the queries need.
struct Holonomic {
    fine: Grid,
    coarse: Grid,
    downsample: usize,
    /// Fine cells from which the goal's cell can be reached.
    reachable: Vec<bool>,
    /// Coarse grid cost from the goal cell, `u32::MAX` while not yet reached.
    cost: Vec<u32>,
    reach: DijkstraReachable<u32, u32, Successors>,
    exhausted: bool,
}

impl Holonomic {
    fn new(field: &Field, checker: &Checker, goal: &Pose, settings: &HybridAStarSettings) -> Self {
        let cell_m = settings.cell_m;
        let fine = Grid {
            columns: ((field.width_m / cell_m).ceil() as usize).max(1),
            rows: ((field.height_m / cell_m).ceil() as usize).max(1),
            cell_m,
        };
        let blocked = Self::blocked_cells(field, checker, &fine);

        let goal_cell = fine.cell_of(&goal.position());
        let reachable = Self::flood_fill(&fine, &blocked, goal_cell);

        let downsample = settings.heuristic_downsample;
        let coarse = Grid {
            columns: fine.columns.div_ceil(downsample),
            rows: fine.rows.div_ceil(downsample),
            cell_m: cell_m * downsample as f64,
        };
        let mut coarse_blocked = vec![true; coarse.columns * coarse.rows];
        for (cell, _) in reachable.iter().enumerate().filter(|(_, r)| **r) {
            let (c, r) = fine.column_row(cell);
            coarse_blocked[(r / downsample) * coarse.columns + c / downsample] = false;
        }
        let coarse_goal = Self::coarse_cell(&fine, &coarse, downsample, goal_cell) as u32;
        let successors: Successors =
            Box::new(move |&cell: &u32| coarse.neighbours(cell as usize, &coarse_blocked));
        Self {
            fine,
            coarse,
            downsample,
            reachable,
            cost: vec![u32::MAX; coarse.columns * coarse.rows],
            reach: dijkstra_reach(&coarse_goal, successors),
            exhausted: false,
        }
    }

    fn coarse_cell(fine: &Grid, coarse: &Grid, downsample: usize, fine_cell: usize) -> usize {
        let (c, r) = fine.column_row(fine_cell);
        (r / downsample) * coarse.columns + c / downsample
    }

    /// The cells reachable from `from` through free cells (8-connected, no corner cutting,
    /// the same moves as [`Grid::neighbours`]).
    fn flood_fill(grid: &Grid, blocked: &[bool], from: usize) -> Vec<bool> {
        // A copy with a blocked border, so that the loop needs no bounds checks.
        let w = grid.columns + 2;
        let mut free = vec![false; w * (grid.rows + 2)];
        for r in 0..grid.rows {
            for c in 0..grid.columns {
                free[(r + 1) * w + c + 1] = !blocked[r * grid.columns + c];
            }
        }
        let mut reached = vec![false; free.len()];
        let (c, r) = grid.column_row(from);
        let first = (r + 1) * w + c + 1;
        let mut stack = Vec::new();
        if free[first] {
            reached[first] = true;
            stack.push(first);
        }
        while let Some(i) = stack.pop() {
            for n in [i - 1, i + 1, i - w, i + w] {
                if free[n] && !reached[n] {
                    reached[n] = true;
                    stack.push(n);
                }
            }
            for (x, y) in [
                (i - 1, i - w),
                (i + 1, i - w),
                (i - 1, i + w),
                (i + 1, i + w),
            ] {
                let n = x + y - i;
                if free[n] && !reached[n] && (free[x] || free[y]) {
                    reached[n] = true;
                    stack.push(n);
                }
            }
        }
        let mut reachable = vec![false; blocked.len()];
        for r in 0..grid.rows {
            for c in 0..grid.columns {
                reachable[r * grid.columns + c] = reached[(r + 1) * w + c + 1];
            }
        }
        reachable
    }

    /// The fine cells no free point can occupy.
    fn blocked_cells(field: &Field, checker: &Checker, fine: &Grid) -> Vec<bool> {
        let cell_m = fine.cell_m;
        let bounds = |cell: usize| {
            let (c, r) = fine.column_row(cell);
            (
                Point::new(c as f64 * cell_m, r as f64 * cell_m),
                Point::new(
                    ((c + 1) as f64 * cell_m).min(field.width_m),
                    ((r + 1) as f64 * cell_m).min(field.height_m),
                ),
            )
        };
        // Columns and rows wholly outside the inset field.
        let outside = |i: usize, max_v: f64, lo_v: f64, hi_v: f64| {
            let (a, b) = (i as f64 * cell_m, ((i + 1) as f64 * cell_m).min(max_v));
            b < lo_v || a > hi_v
        };
        let column_out: Vec<bool> = (0..fine.columns)
            .map(|c| outside(c, field.width_m, checker.min.x, checker.max.x))
            .collect();
        let row_out: Vec<bool> = (0..fine.rows)
            .map(|r| outside(r, field.height_m, checker.min.y, checker.max.y))
            .collect();
        let mut blocked = vec![false; fine.columns * fine.rows];
        for (r, row) in blocked.chunks_mut(fine.columns).enumerate() {
            for (c, b) in row.iter_mut().enumerate() {
                *b = row_out[r] || column_out[c];
            }
        }
        // Cells that some obstacle touches, visited in index order (deterministic).
        let mut touched = vec![false; blocked.len()];
        for d in checker.grid.disks() {
            let r = Vector::new(d.radius_m, d.radius_m);
            let (c0, r0) = fine.column_row(fine.cell_of(&(d.center - r)));
            let (c1, r1) = fine.column_row(fine.cell_of(&(d.center + r)));
            for row in r0..=r1 {
                touched[row * fine.columns + c0..=row * fine.columns + c1].fill(true);
            }
        }
        // A touched cell is blocked when each of its sub-squares lies wholly inside one
        // obstacle, so that the union of the obstacles covers it.
        let mut candidates = Vec::new();
        for cell in 0..blocked.len() {
            if !touched[cell] || blocked[cell] {
                continue;
            }
            let (lo, hi) = bounds(cell);
            candidates.clear();
            let _ = checker.grid.visit_box(&lo, &hi, |_, d| {
                candidates.push(*d);
                ControlFlow::<()>::Continue(())
            });
            let step = (hi - lo) / COVER_SPLIT as f64;
            blocked[cell] = (0..COVER_SPLIT * COVER_SPLIT).all(|k| {
                let a = lo
                    + Vector::new(
                        (k % COVER_SPLIT) as f64 * step.x,
                        (k / COVER_SPLIT) as f64 * step.y,
                    );
                let corners = [
                    a,
                    a + step,
                    a + Vector::new(step.x, 0.0),
                    a + Vector::new(0.0, step.y),
                ];
                candidates
                    .iter()
                    .any(|d| corners.iter().all(|p| (p - d.center).norm() < d.radius_m))
            });
        }
        blocked
    }

    /// A lower bound on the length of a free path from `p` to the goal, in metres;
    /// infinite when the grid shows none exists.
    fn lower_bound_m(&mut self, p: &Point) -> f64 {
        let fine_cell = self.fine.cell_of(p);
        if !self.reachable[fine_cell] {
            return f64::INFINITY;
        }
        let cell = Self::coarse_cell(&self.fine, &self.coarse, self.downsample, fine_cell);
        while self.cost[cell] == u32::MAX && !self.exhausted {
            match self.reach.next() {
                Some(item) => self.cost[item.node as usize] = item.total_cost,
                None => self.exhausted = true,
            }
        }
        match self.cost[cell] {
            u32::MAX => f64::INFINITY,
            cost => {
                // An 8-connected grid path is at most sec(pi/8) times a straight line, plus a
                // cell diagonal for where the point lies in its cell.
                let cell_m = self.coarse.cell_m;
                let grid_m = cost as f64 / STRAIGHT_COST as f64 * cell_m;
                (grid_m * (PI / 8.0).cos() - SQRT_2 * cell_m).max(0.0)
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// The search.

/// Hashes the u64 cell keys (a multiplicative mix; no iteration order is ever used).
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 29)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (v ^ (v >> 31)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

#[derive(Clone, Copy, Debug)]
struct Primitive {
    curvature_per_m: f64,
    length_m: f64,
    cost_m: f64,
}

const NO_PARENT: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Node {
    pose: Pose,
    g_m: f64,
    parent: u32,
    /// Index of the primitive that led here (unused for the start).
    primitive: u8,
    /// +1 forwards, -1 backwards, 0 for the start.
    direction: i8,
    closed: bool,
}

/// An entry of the open list: lowest `f` first, then highest `g` (deeper), then oldest.
/// `BinaryHeap` pops the greatest, so `f` and the node index are reversed; the fields
/// compare in this order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Entry {
    f_m: Reverse<TotalF64>,
    g_m: TotalF64,
    node: Reverse<u32>,
}

impl Entry {
    fn new(f_m: f64, g_m: f64, node: u32) -> Self {
        Self {
            f_m: Reverse(TotalF64(f_m)),
            g_m: TotalF64(g_m),
            node: Reverse(node),
        }
    }
}

struct Search<'a> {
    checker: Checker,
    holonomic: Holonomic,
    start: Pose,
    goal: Pose,
    settings: &'a HybridAStarSettings,
    primitives: Vec<Primitive>,
    rows: u64,
    nodes: Vec<Node>,
    cells: HashMap<u64, u32, BuildHasherDefault<KeyHasher>>,
    open: BinaryHeap<Entry>,
}

impl<'a> Search<'a> {
    fn new(
        field: &Field,
        checker: Checker,
        holonomic: Holonomic,
        start: &Pose,
        goal: &Pose,
        settings: &'a HybridAStarSettings,
    ) -> Self {
        let length_m = settings.primitive_length_m();
        let k = 1.0 / settings.turning_radius_m;
        let mut primitives = Vec::new();
        let directions: &[f64] = if settings.allow_reverse {
            &[1.0, -1.0]
        } else {
            &[1.0]
        };
        for &direction in directions {
            for curvature_per_m in [0.0, k, -k] {
                let mut cost_m = length_m;
                if curvature_per_m != 0.0 {
                    cost_m *= settings.turn_penalty;
                }
                if direction < 0.0 {
                    cost_m *= settings.reverse_penalty;
                }
                primitives.push(Primitive {
                    curvature_per_m,
                    length_m: direction * length_m,
                    cost_m,
                });
            }
        }
        Self {
            checker,
            holonomic,
            start: *start,
            goal: *goal,
            settings,
            primitives,
            rows: (field.height_m / settings.cell_m).ceil() as u64 + 1,
            nodes: Vec::new(),
            cells: HashMap::default(),
            open: BinaryHeap::new(),
        }
    }

    fn cell_key(&self, pose: &Pose) -> u64 {
        let bins = self.settings.heading_bins;
        let bin_rad = TAU / bins as f64;
        let bin = ((pose.heading_rad.rem_euclid(TAU) / bin_rad + 0.5).floor() as usize) % bins;
        // Poses reaching here are inside the field, so the cell coordinates are >= 0.
        let ix = (pose.x_m / self.settings.cell_m).floor().max(0.0) as u64;
        let iy = (pose.y_m / self.settings.cell_m).floor().max(0.0) as u64;
        (ix * self.rows + iy) * bins as u64 + bin as u64
    }

    fn shortest_length_m(&self, from: &Pose) -> f64 {
        if self.settings.allow_reverse {
            reeds_shepp::shortest_length_m(from, &self.goal, self.settings.turning_radius_m)
        } else {
            dubins::shortest_length_m(from, &self.goal, self.settings.turning_radius_m)
        }
    }

    fn heuristic_m(&mut self, pose: &Pose) -> f64 {
        let holonomic_m = self.holonomic.lower_bound_m(&pose.position());
        if holonomic_m.is_infinite() {
            return holonomic_m;
        }
        self.shortest_length_m(pose).max(holonomic_m)
    }

    fn run(mut self) -> Result<(Vec<Pose>, PlanStats), PlanError> {
        let start = self.start;
        let h_m = self.heuristic_m(&start);
        if h_m.is_infinite() {
            return Err(PlanError::NoPath);
        }
        self.nodes.push(Node {
            pose: self.start,
            g_m: 0.0,
            parent: NO_PARENT,
            primitive: 0,
            direction: 0,
            closed: false,
        });
        let start_key = self.cell_key(&self.start);
        self.cells.insert(start_key, 0);
        self.open.push(Entry::new(h_m, 0.0, 0));

        let cell_m = self.settings.cell_m;
        let ratio = self.settings.analytic_expansion_ratio;
        let mut closest_cells = f64::INFINITY;
        // The start's shot was tried in `plan_with_stats`.
        let mut countdown = i64::MAX;
        let mut expansions = 0usize;
        let mut analytic_attempts = 1usize;

        while let Some(Entry {
            f_m: Reverse(TotalF64(entry_f_m)),
            g_m: TotalF64(entry_g_m),
            node: Reverse(index),
        }) = self.open.pop()
        {
            let index = index as usize;
            let node = self.nodes[index];
            if node.closed || node.g_m != entry_g_m {
                continue; // stale entry
            }
            if expansions >= self.settings.max_expansions {
                return Err(PlanError::ExpansionLimit { expansions });
            }
            self.nodes[index].closed = true;
            expansions += 1;

            // Analytic expansion, more often as the search closes in (Smac's schedule).
            let h_m = entry_f_m - entry_g_m;
            closest_cells = closest_cells.min(h_m / cell_m);
            let desired = (closest_cells / ratio).floor().max(ratio.ceil()) as i64;
            countdown = countdown.min(desired);
            if countdown <= 0 {
                countdown = desired;
                analytic_attempts += 1;
                if let Some(tail) =
                    analytic_expansion(&mut self.checker, self.settings, &node.pose, &self.goal)
                {
                    let path = self.reconstruct(index, tail);
                    let length_m = path_length_m(&path);
                    return Ok((
                        path,
                        PlanStats {
                            expansions,
                            analytic_attempts,
                            length_m,
                        },
                    ));
                }
            }
            countdown -= 1;

            for p in 0..self.primitives.len() {
                let primitive = self.primitives[p];
                let piece = Piece {
                    start: node.pose,
                    curvature_per_m: primitive.curvature_per_m,
                    length_m: primitive.length_m,
                };
                let child = piece.end();
                if !self.checker.in_field(&child.position()) {
                    continue;
                }
                let direction: i8 = if primitive.length_m < 0.0 { -1 } else { 1 };
                let mut g_m = node.g_m + primitive.cost_m;
                if node.direction != 0 && node.direction != direction {
                    g_m += self.settings.direction_change_penalty_m;
                }
                let key = self.cell_key(&child);
                let existing = self.cells.get(&key).copied();
                if let Some(other) = existing {
                    let other = &self.nodes[other as usize];
                    if other.closed || other.g_m <= g_m {
                        continue;
                    }
                }
                if !self.checker.piece_free(&piece) {
                    continue;
                }
                let h_m = self.heuristic_m(&child);
                if h_m.is_infinite() {
                    continue;
                }
                let new_node = Node {
                    pose: child,
                    g_m,
                    parent: index as u32,
                    primitive: p as u8,
                    direction,
                    closed: false,
                };
                let slot = match existing {
                    Some(other) => {
                        self.nodes[other as usize] = new_node;
                        other
                    }
                    None => {
                        let slot = self.nodes.len() as u32;
                        self.nodes.push(new_node);
                        self.cells.insert(key, slot);
                        slot
                    }
                };
                self.open.push(Entry::new(g_m + h_m, g_m, slot));
            }
        }
        Err(PlanError::NoPath)
    }

    /// The dense path: the primitives from the start to node `last`, then `tail`.
    fn reconstruct(&self, last: usize, tail: Vec<Piece>) -> Vec<Pose> {
        let mut chain = Vec::new();
        let mut index = last;
        while self.nodes[index].parent != NO_PARENT {
            chain.push(index);
            index = self.nodes[index].parent as usize;
        }
        chain.reverse();
        let primitives = chain.iter().map(|&i| {
            let node = &self.nodes[i];
            let primitive = &self.primitives[node.primitive as usize];
            let piece = Piece {
                start: self.nodes[node.parent as usize].pose,
                curvature_per_m: primitive.curvature_per_m,
                length_m: primitive.length_m,
            };
            (piece, node.pose)
        });
        let tail = tail.into_iter().map(|p| (p, p.end()));
        dense_path(
            &self.start,
            &self.goal,
            primitives.chain(tail),
            self.settings.sample_spacing_m,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_distance_and_bounding_box_are_exact() {
        // Quarter circle of radius 2 centred at the origin, from (2, 0) heading north.
        let piece = Piece {
            start: Pose::new(2.0, 0.0, FRAC_PI_2),
            curvature_per_m: 0.5,
            length_m: PI,
        };
        let end = piece.end();
        assert!((end.x_m).abs() < 1e-12 && (end.y_m - 2.0).abs() < 1e-12);
        assert!((piece.distance_m(&Point::new(3.0, 3.0)) - (18f64.sqrt() - 2.0)).abs() < 1e-12);
        assert!((piece.distance_m(&Point::new(0.0, 0.0)) - 2.0).abs() < 1e-12);
        // Beyond the arc's end: nearest is the endpoint (0, 2).
        assert!((piece.distance_m(&Point::new(-1.0, 1.0)) - 2f64.sqrt()).abs() < 1e-12);
        let (min, max) = piece.bounding_box();
        assert!((min.x).abs() < 1e-12 && (min.y).abs() < 1e-12);
        assert!((max.x - 2.0).abs() < 1e-12 && (max.y - 2.0).abs() < 1e-12);
        // Driven backwards: the arc below, from (2, 0) to (0, -2).
        let back = Piece {
            length_m: -PI,
            ..piece
        };
        let end = back.end();
        assert!((end.x_m).abs() < 1e-12 && (end.y_m + 2.0).abs() < 1e-12);
        let (min, _) = back.bounding_box();
        assert!((min.y + 2.0).abs() < 1e-12);
    }

    #[test]
    fn resample_keeps_endpoints_and_spacing() {
        let path: Vec<Pose> = (0..=10).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
        let out = resample(&path, 3.0);
        let xs: Vec<f64> = out.iter().map(|p| p.x_m).collect();
        assert_eq!(xs, vec![0.0, 3.0, 6.0, 9.0, 10.0]);
        let out = resample(&path, 2.5);
        let xs: Vec<f64> = out.iter().map(|p| p.x_m).collect();
        assert_eq!(xs, vec![0.0, 2.5, 5.0, 7.5, 10.0]);
    }
}
