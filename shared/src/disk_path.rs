//! Shortest collision-free path for a point agent among stationary disks, inside the
//! rectangular field.
//!
//! The disks are already inflated (agent radius plus whatever planning margin the caller
//! chose), so the agent is a point. The exact shortest path is a chain of common tangent
//! segments and boundary arcs (the *tangent visibility graph*):
//! `start -> tangent -> arc -> bitangent -> arc -> ... -> tangent -> goal`. The field is
//! convex, so the path never bends at a wall, but every segment and every arc must stay
//! inside it.
//!
//! # Method
//!
//! - **Fast path.** If the straight segment is free, it is the answer.
//! - **Lazy tangent graph, A\*.** A node is an *arrival* on a circle: the end point of a
//!   directed tangent segment, with the sense (counter-clockwise or clockwise) in which the
//!   path goes on around that circle. Its identity is a tuple of integers (source circle,
//!   source sense, target circle, target sense), never a float; its point is a pure
//!   function of that tuple. An edge leaves an arrival node, follows the arc in its sense up
//!   to a departure tangent point, then the tangent segment to the next arrival (or the
//!   goal). Successors are generated on demand and searched with [`pathfinding`]'s A\* and
//!   the Euclidean heuristic (consistent: every edge is at least as long as its chord).
//! - **Ellipse bound.** A path of length `<= L` from `s` to `t` lies in the ellipse
//!   `|x - s| + |x - t| <= L`. Each round keeps only the disks that meet that ellipse and
//!   the field; a path found with length `<= L` is then globally free and optimal. If none
//!   is found, `L` doubles, until the ellipse covers the whole field (then every disk that
//!   meets the field takes part and the answer is final).
//! - **Exact checks.** Segments are checked against every disk through the grid index
//!   ([`FreeSpace::is_segment_free`]). Arcs are checked exactly: the part of a circle that
//!   lies strictly inside another disk, or outside a field edge, is an open angular
//!   interval (from the circle-circle or circle-line intersection angles), and an arc is
//!   allowed only if it enters none of them.
//! - **Quick proof of unreachability.** When a round finds nothing, a barrier test runs on
//!   that round's disks: overlapping disks (and disks crossing a field edge, joined through
//!   the outside of the field) form closed curves of obstacle; if one of them crosses the
//!   segment `s`-`t` an odd number of times, `s` and `t` are in different free components
//!   and the answer is [`PathError::Unreachable`] without searching the whole field.
//!
//! # Tolerance
//!
//! Start and goal are accepted within [`FREE_TOLERANCE_M`] of free space (they may lie
//! exactly on a disk boundary, or where two boundaries cross). Every returned path keeps a
//! signed clearance of at least `-FREE_TOLERANCE_M` from every disk and stays within that
//! distance of the field. Touching a disk is allowed.
//!
//! # Determinism
//!
//! No randomness, no iteration over hash maps: the same inputs give the same path, bit for
//! bit, in every process.

use std::cmp::Ordering;
use std::f64::consts::TAU;
use std::ops::ControlFlow;

use pathfinding::directed::astar::astar;

use crate::geometry::{Disk, Field, FreeSpace, Point, Vector};
use crate::ordered::TotalF64;

/// How far inside a disk (or outside the field) a start, a goal or any point of a path may
/// be, in metres.
pub const FREE_TOLERANCE_M: f64 = 1e-9;

/// Overlap (or wall crossing) a barrier needs before the unreachability test trusts it, in
/// metres: far above [`FREE_TOLERANCE_M`], so no path within tolerance slips through.
const BARRIER_MARGIN_M: f64 = 1e-6;

/// An arc this close to a full turn is a rounding artefact of an exactly collinear pair of
/// tangents: it is treated as no arc at all (radians).
const FULL_TURN_SNAP_RAD: f64 = 1e-9;

/// Arcs shorter than this are not emitted as pieces (metres).
const MIN_ARC_LENGTH_M: f64 = 1e-12;

/// Slack when comparing an arc's sweep with the free extent around its circle (radians).
const SWEEP_SLACK_RAD: f64 = 1e-12;

/// One piece of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathPiece {
    /// Straight segment.
    Segment {
        /// First point.
        from: Point,
        /// Last point.
        to: Point,
    },
    /// Arc of the circle (`center`, `radius_m`) starting at angle `start_rad`, sweeping
    /// `sweep_rad` (positive = counter-clockwise).
    Arc {
        /// Centre of the circle.
        center: Point,
        /// Radius of the circle, in metres.
        radius_m: f64,
        /// Angle of the first point, counter-clockwise from +x, in radians.
        start_rad: f64,
        /// Signed swept angle, in radians (positive = counter-clockwise).
        sweep_rad: f64,
    },
}

/// The point of the circle (`center`, `radius_m`) at angle `angle_rad`.
fn circle_point(center: &Point, radius_m: f64, angle_rad: f64) -> Point {
    let (sin, cos) = angle_rad.sin_cos();
    center + radius_m * Vector::new(cos, sin)
}

impl PathPiece {
    /// First point of the piece.
    pub fn start(&self) -> Point {
        match self {
            Self::Segment { from, .. } => *from,
            Self::Arc {
                center,
                radius_m,
                start_rad,
                ..
            } => circle_point(center, *radius_m, *start_rad),
        }
    }

    /// Last point of the piece.
    pub fn end(&self) -> Point {
        match self {
            Self::Segment { to, .. } => *to,
            Self::Arc {
                center,
                radius_m,
                start_rad,
                sweep_rad,
            } => circle_point(center, *radius_m, start_rad + sweep_rad),
        }
    }

    /// Length of the piece, in metres.
    pub fn length_m(&self) -> f64 {
        match self {
            Self::Segment { from, to } => (to - from).norm(),
            Self::Arc {
                radius_m,
                sweep_rad,
                ..
            } => radius_m * sweep_rad.abs(),
        }
    }

    /// The point at fraction `t` of the piece's length (`0` = start, `1` = end; clamped).
    pub fn point_at_fraction(&self, t: f64) -> Point {
        let t = t.clamp(0.0, 1.0);
        match self {
            Self::Segment { from, to } => from + t * (to - from),
            Self::Arc {
                center,
                radius_m,
                start_rad,
                sweep_rad,
            } => circle_point(center, *radius_m, start_rad + t * sweep_rad),
        }
    }
}

/// A path made of segments and arcs, continuous from start to goal.
///
/// Paths returned by [`shortest_path`] are exactly continuous (each piece starts at the
/// previous piece's [`PathPiece::end`], bit for bit), start exactly at the requested start
/// and end exactly at the requested goal. They are never empty: a path from a point to
/// itself is a single zero-length segment.
#[derive(Clone, Debug, PartialEq)]
pub struct DiskPath {
    /// The pieces, in travel order.
    pub pieces: Vec<PathPiece>,
    /// Where the path starts when `pieces` is empty.
    origin: Point,
}

impl DiskPath {
    /// A path made of `pieces`, starting at `origin` when `pieces` is empty (otherwise the
    /// first piece's start is the path's start).
    pub fn new(origin: Point, pieces: Vec<PathPiece>) -> Self {
        Self { pieces, origin }
    }

    /// The straight path from `from` to `to` (a single segment, possibly of zero length).
    pub fn straight(from: Point, to: Point) -> Self {
        Self::new(from, vec![PathPiece::Segment { from, to }])
    }

    /// Total length, in metres.
    pub fn length_m(&self) -> f64 {
        self.pieces.iter().map(PathPiece::length_m).sum()
    }

    /// First point of the path.
    pub fn start(&self) -> Point {
        self.pieces.first().map_or(self.origin, PathPiece::start)
    }

    /// Last point of the path.
    pub fn end(&self) -> Point {
        self.pieces.last().map_or(self.origin, PathPiece::end)
    }

    /// Polyline vertices following the path, start and end included, such that every chord
    /// stays within `max_chord_error_m` of the true arc (inscribed chords: vertices exactly
    /// on the arcs, so a chord cuts at most `max_chord_error_m` into an arc's disk).
    ///
    /// Segments contribute their end points only. `max_chord_error_m` below `1e-9` m (or
    /// NaN) is treated as `1e-9` m.
    pub fn polyline(&self, max_chord_error_m: f64) -> Vec<Point> {
        let error_m = max_chord_error_m.max(1e-9);
        let mut out = vec![self.start()];
        for piece in &self.pieces {
            match piece {
                PathPiece::Segment { to, .. } => out.push(*to),
                PathPiece::Arc {
                    radius_m,
                    sweep_rad,
                    ..
                } => {
                    // Sagitta of a chord spanning `step`: r (1 - cos(step / 2)).
                    let max_step_rad = if error_m >= *radius_m {
                        std::f64::consts::PI
                    } else {
                        (2.0 * (1.0 - error_m / radius_m).acos()).min(std::f64::consts::PI)
                    };
                    let n = chord_count(sweep_rad.abs(), max_step_rad);
                    for i in 1..=n {
                        out.push(piece.point_at_fraction(i as f64 / n as f64));
                    }
                }
            }
        }
        out
    }

    /// Points along the path at most `spacing_m` apart along the path (so also in
    /// straight-line distance), start and end included, every one exactly on the path.
    ///
    /// `spacing_m` below `1e-9` m (or NaN) is treated as `1e-9` m.
    pub fn sample(&self, spacing_m: f64) -> Vec<Point> {
        let spacing_m = spacing_m.max(1e-9);
        let mut out = vec![self.start()];
        for piece in &self.pieces {
            let n = chord_count(piece.length_m(), spacing_m);
            for i in 1..=n {
                out.push(piece.point_at_fraction(i as f64 / n as f64));
            }
        }
        out
    }
}

/// Number of equal steps, at least one, so that `total / steps <= max_step`.
fn chord_count(total: f64, max_step: f64) -> usize {
    let n = (total / max_step).ceil();
    if n.is_finite() && n >= 1.0 {
        n as usize
    } else {
        1
    }
}

/// Why no path was returned.
#[derive(Debug, thiserror::Error, Clone, Copy, PartialEq, Eq)]
pub enum PathError {
    /// The start is inside a disk or outside the field (beyond [`FREE_TOLERANCE_M`]).
    #[error("the start is not in free space")]
    StartNotFree,
    /// The goal is inside a disk or outside the field (beyond [`FREE_TOLERANCE_M`]).
    #[error("the goal is not in free space")]
    GoalNotFree,
    /// Start and goal are both free but lie in different components of free space.
    #[error("the goal cannot be reached from the start")]
    Unreachable,
}

/// Shortest free path from `from` to `to` in `space`.
///
/// `space`'s disks are the already inflated obstacles; the path keeps a signed clearance of
/// at least `-`[`FREE_TOLERANCE_M`] from each of them and stays inside the field. Start and
/// goal may lie on disk boundaries. `from == to` gives a single zero-length segment.
pub fn shortest_path(space: &FreeSpace, from: &Point, to: &Point) -> Result<DiskPath, PathError> {
    if !space.is_free(from, FREE_TOLERANCE_M) {
        return Err(PathError::StartNotFree);
    }
    if !space.is_free(to, FREE_TOLERANCE_M) {
        return Err(PathError::GoalNotFree);
    }
    if from == to || space.is_segment_free(from, to, FREE_TOLERANCE_M) {
        return Ok(DiskPath::straight(*from, *to));
    }
    search_path(space, from, to)
}

/// The search part of [`shortest_path`], for free end points whose straight segment is
/// blocked.
fn search_path(space: &FreeSpace, from: &Point, to: &Point) -> Result<DiskPath, PathError> {
    let direct_m = (to - from).norm();
    // The ellipse covers the field once it holds the four corners (the field is convex).
    let cover_m = space
        .field
        .corners()
        .iter()
        .map(|c| (c - from).norm() + (c - to).norm())
        .fold(0.0, f64::max);
    let mut bound_m = direct_m + direct_m.max(3.0 * space.max_radius_m()).max(1.0);
    loop {
        let last_round = bound_m.partial_cmp(&cover_m) != Some(Ordering::Less);
        let limit_m = if last_round { f64::INFINITY } else { bound_m };
        let circles = candidate_disks(space, from, to, limit_m);
        let mut planner = Planner::new(space, *from, *to, &circles, limit_m);
        match planner.search() {
            Some((nodes, cost)) if last_round || cost.0 <= bound_m + FREE_TOLERANCE_M => {
                return Ok(planner.build_path(&nodes));
            }
            // A path exists but is longer than the bound: widen.
            Some(_) => {}
            None => {
                if last_round || separated(&space.field, from, to, &circles) {
                    return Err(PathError::Unreachable);
                }
            }
        }
        bound_m = (2.0 * bound_m).min(cover_m);
    }
}

/// Shortest paths from one start to many goals in the same free space: the reachability
/// test of one agent's turn, where the candidate best points are tried one after another.
///
/// [`PathsFrom::shortest_path`] answers exactly what [`shortest_path`] answers (the same
/// path, bit for bit, or the same error). It is faster when the goal lies in another free
/// component than the start, as when the agent stands in a pocket closed by overlapping
/// disks and its slot lies outside: [`shortest_path`] has to exhaust the pocket before it
/// may give up, while here a barrier graph of the disks around the start, built once and
/// shared by every goal, shows most such goals unreachable in one pass over its edges.
/// The barrier test is sound (a goal it rejects is unreachable, so no answer changes); a
/// goal it does not reject goes to the search.
#[derive(Debug)]
pub struct PathsFrom<'a, 's> {
    space: &'a FreeSpace<'s>,
    from: Point,
    from_is_free: bool,
    /// Built on the first goal that needs it; rebuilt larger for a goal it does not cover.
    barriers: Option<BarrierGraph>,
}

impl<'a, 's> PathsFrom<'a, 's> {
    /// Paths from `from` in `space` (already inflated disks, as for [`shortest_path`]).
    pub fn new(space: &'a FreeSpace<'s>, from: &Point) -> Self {
        Self {
            space,
            from: *from,
            from_is_free: space.is_free(from, FREE_TOLERANCE_M),
            barriers: None,
        }
    }

    /// The common start of every path.
    pub fn start(&self) -> Point {
        self.from
    }

    /// `shortest_path(space, from, to)`, the same answer bit for bit.
    pub fn shortest_path(&mut self, to: &Point) -> Result<DiskPath, PathError> {
        if !self.from_is_free {
            return Err(PathError::StartNotFree);
        }
        if !self.space.is_free(to, FREE_TOLERANCE_M) {
            return Err(PathError::GoalNotFree);
        }
        let from = self.from;
        if from == *to || self.space.is_segment_free(&from, to, FREE_TOLERANCE_M) {
            return Ok(DiskPath::straight(from, *to));
        }
        if self.barriers_for(to).separates(&from, to) {
            return Err(PathError::Unreachable);
        }
        search_path(self.space, &from, to)
    }

    /// The barrier graph, covering the disks near the start and near `to`.
    fn barriers_for(&mut self, to: &Point) -> &mut BarrierGraph {
        // Pockets are small: a few of the largest disks around the start or the goal.
        let pad_m = BARRIER_PAD_RADII * self.space.max_radius_m();
        let needed_m = (to - self.from).norm() + pad_m;
        let reach_m = match &self.barriers {
            Some(graph) if graph.reach_m >= needed_m => None,
            Some(graph) => Some(needed_m.max(2.0 * graph.reach_m)),
            None => Some(needed_m),
        };
        if let Some(reach_m) = reach_m {
            self.barriers = Some(BarrierGraph::new(self.space, &self.from, reach_m));
        }
        self.barriers.as_mut().expect("built above")
    }
}

/// How far around the start a [`PathsFrom`] barrier graph reaches beyond its farthest goal,
/// in largest disk radii.
const BARRIER_PAD_RADII: f64 = 4.0;

/// One barrier edge: a segment through obstacle from vertex `u` to vertex `v`, with its
/// bounding box.
#[derive(Clone, Copy, Debug)]
struct BarrierEdge {
    u: u32,
    v: u32,
    p: Point,
    q: Point,
    min: Point,
    max: Point,
}

impl BarrierEdge {
    fn new(u: usize, v: usize, p: &Point, q: &Point) -> Self {
        Self {
            u: u as u32,
            v: v as u32,
            p: *p,
            q: *q,
            min: Point::new(p.x.min(q.x), p.y.min(q.y)),
            max: Point::new(p.x.max(q.x), p.y.max(q.y)),
        }
    }

    /// [`crosses`] `s`-`t`, with `[min, max]` the box of `s`-`t` grown by a slack far
    /// above rounding (an edge whose box misses it cannot cross).
    fn crosses(&self, s: &Point, t: &Point, min: &Point, max: &Point) -> bool {
        self.max.x >= min.x
            && self.min.x <= max.x
            && self.max.y >= min.y
            && self.min.y <= max.y
            && crosses(s, t, &self.p, &self.q)
    }
}

/// The barrier edges ([`visit_barrier_edges`]) of the disks that meet a ball around a start,
/// reduced to what can close a curve, for the test of [`separated`] against many goals.
///
/// A goal is separated from the start iff some cycle of the graph is crossed an odd number
/// of times by the segment between them. Only the 2-core of the graph (what is left after
/// repeatedly removing vertices of degree at most one) holds cycles, and the cycle space is
/// spanned by the fundamental cycles of a spanning forest: with `parity(v)` the parity of
/// the crossings along the forest path from its root to `v`, some cycle is odd iff some edge
/// off the forest has `parity(u) ^ parity(v) ^ crosses(edge)` set. One pass, no sorting.
#[derive(Debug)]
struct BarrierGraph {
    /// Radius of the ball around the start: the graph holds every disk that meets it.
    reach_m: f64,
    /// Forest edges, parent `u` to child `v`, each parent reached before its children.
    forest: Vec<BarrierEdge>,
    /// The other edges of the 2-core, each closing one fundamental cycle.
    chords: Vec<BarrierEdge>,
    /// Scratch: crossing parity of the forest path from the root to each vertex.
    parity: Vec<bool>,
}

impl BarrierGraph {
    fn new(space: &FreeSpace, from: &Point, reach_m: f64) -> Self {
        let field = &space.field;
        let r_max = space.max_radius_m();
        let grow = Vector::new(reach_m + r_max, reach_m + r_max);
        let mut disks = Vec::new();
        let _ = space.visit_box(&(from - grow), &(from + grow), |_, d| {
            let usable = d.radius_m > 0.0 && d.radius_m.is_finite();
            if usable
                && (field.clamp(&d.center) - d.center).norm() <= d.radius_m
                && (d.center - from).norm() <= reach_m + d.radius_m
            {
                disks.push(*d);
            }
            ControlFlow::<()>::Continue(())
        });
        let vertices = disks.len() + 1;
        let mut edges = Vec::new();
        let _ = visit_barrier_edges(field, &disks, |u, v, p, q| {
            edges.push(BarrierEdge::new(u, v, p, q));
            ControlFlow::Continue(())
        });

        // Adjacency (edge indices per vertex, in edge order).
        let mut degree = vec![0usize; vertices];
        for e in &edges {
            degree[e.u as usize] += 1;
            degree[e.v as usize] += 1;
        }
        let mut first = Vec::with_capacity(vertices + 1);
        let mut total = 0;
        for d in &degree {
            first.push(total);
            total += d;
        }
        first.push(total);
        let mut fill = first.clone();
        let mut incident = vec![0usize; total];
        for (k, e) in edges.iter().enumerate() {
            for w in [e.u as usize, e.v as usize] {
                incident[fill[w]] = k;
                fill[w] += 1;
            }
        }
        let other = |k: usize, w: usize| {
            let e = &edges[k];
            if e.u as usize == w {
                e.v as usize
            } else {
                e.u as usize
            }
        };

        // 2-core: peel vertices of degree <= 1.
        let mut removed = vec![false; vertices];
        let mut peel: Vec<usize> = (0..vertices).filter(|&w| degree[w] <= 1).collect();
        while let Some(w) = peel.pop() {
            if removed[w] {
                continue;
            }
            removed[w] = true;
            for &k in &incident[first[w]..first[w + 1]] {
                let x = other(k, w);
                if !removed[x] {
                    degree[x] -= 1;
                    if degree[x] <= 1 {
                        peel.push(x);
                    }
                }
            }
        }

        // Spanning forest of the 2-core, breadth first, roots in vertex order.
        let mut used = vec![false; edges.len()];
        let mut seen = removed.clone();
        let mut forest = Vec::new();
        let mut queue = std::collections::VecDeque::new();
        for root in 0..vertices {
            if seen[root] {
                continue;
            }
            seen[root] = true;
            queue.push_back(root);
            while let Some(w) = queue.pop_front() {
                for &k in &incident[first[w]..first[w + 1]] {
                    let x = other(k, w);
                    if seen[x] {
                        continue;
                    }
                    seen[x] = true;
                    used[k] = true;
                    let e = &edges[k];
                    forest.push(BarrierEdge {
                        u: w as u32,
                        v: x as u32,
                        ..*e
                    });
                    queue.push_back(x);
                }
            }
        }
        let chords = edges
            .iter()
            .zip(&used)
            .filter(|&(e, &in_forest)| {
                !in_forest && !removed[e.u as usize] && !removed[e.v as usize]
            })
            .map(|(e, _)| *e)
            .collect();
        Self {
            reach_m,
            forest,
            chords,
            parity: vec![false; vertices],
        }
    }

    /// Whether a cycle of the graph separates `s` from `t` (sound, as [`separated`]).
    fn separates(&mut self, s: &Point, t: &Point) -> bool {
        if self.chords.is_empty() {
            return false;
        }
        let slack_m = FREE_TOLERANCE_M * (1.0 + s.x.abs() + s.y.abs() + t.x.abs() + t.y.abs());
        let min = Point::new(s.x.min(t.x) - slack_m, s.y.min(t.y) - slack_m);
        let max = Point::new(s.x.max(t.x) + slack_m, s.y.max(t.y) + slack_m);
        // Roots keep `false`; every other vertex is set after its parent.
        for e in &self.forest {
            self.parity[e.v as usize] = self.parity[e.u as usize] ^ e.crosses(s, t, &min, &max);
        }
        let parity = &self.parity;
        self.chords
            .iter()
            .any(|e| parity[e.u as usize] ^ parity[e.v as usize] ^ e.crosses(s, t, &min, &max))
    }
}

/// Disks that meet the field and may meet the ellipse `|x - s| + |x - t| <= limit_m`
/// (a superset: `|c - s| + |c - t| <= limit_m + 2 r`), in the grid's deterministic order.
fn candidate_disks(space: &FreeSpace, s: &Point, t: &Point, limit_m: f64) -> Vec<Disk> {
    let r_max = space.max_radius_m();
    let field = &space.field;
    // The ellipse lies in the disk of radius limit/2 around the midpoint of s and t.
    let mid = nalgebra::center(s, t);
    let half_m = 0.5 * limit_m + r_max;
    let min = Point::new((mid.x - half_m).max(-r_max), (mid.y - half_m).max(-r_max));
    let max = Point::new(
        (mid.x + half_m).min(field.width_m + r_max),
        (mid.y + half_m).min(field.height_m + r_max),
    );
    let mut out = Vec::new();
    let _ = space.visit_box(&min, &max, |_, d| {
        let usable = d.radius_m > 0.0 && d.radius_m.is_finite();
        let meets_field = usable && (field.clamp(&d.center) - d.center).norm() <= d.radius_m;
        if meets_field
            && (d.center - s).norm() + (d.center - t).norm() <= limit_m + 2.0 * d.radius_m
        {
            out.push(*d);
        }
        ControlFlow::<()>::Continue(())
    });
    out
}

/// Circle id of the start point in a [`NodeKey`].
const START: u32 = u32::MAX - 1;
/// Circle id of the goal point in a [`NodeKey`].
const GOAL: u32 = u32::MAX;

/// Integer identity of a search node: the directed tangent from (`from`, `from_sense`) to
/// (`to`, `to_sense`), senses `+1` counter-clockwise, `-1` clockwise, `0` for the start and
/// goal points. The start node is `(START, 0, START, 0)`, the goal `(GOAL, 0, GOAL, 0)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct NodeKey {
    from: u32,
    from_sense: i8,
    to: u32,
    to_sense: i8,
}

/// A search node: its key plus its geometry, a pure function of the key (so equality and
/// hashing look at the key only).
#[derive(Clone, Copy, Debug)]
struct Node {
    key: NodeKey,
    /// Arrival point.
    point: Point,
    /// Angle of the arrival point on its circle (unused for start and goal).
    angle_rad: f64,
}

impl PartialEq for Node {
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key
    }
}

impl Eq for Node {}

impl std::hash::Hash for Node {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.key.hash(state);
    }
}

/// Where an edge goes.
#[derive(Clone, Copy, Debug)]
enum Target {
    /// Arrive on candidate circle `.0` with sense `.1`.
    Circle(u32, i8),
    /// Reach the goal.
    Goal,
}

/// Geometry of one edge: the arc around the source circle, then the tangent segment.
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// Unsigned arc sweep on the source circle (0 from the start point).
    sweep_rad: f64,
    /// Departure point (end of the arc, start of the segment).
    depart: Point,
    /// Arrival point (end of the segment).
    arrive: Point,
    /// Angle of the arrival point on the target circle.
    arrive_angle_rad: f64,
    /// The segment is degenerate (a start or goal on the circle itself): no segment check.
    degenerate: bool,
}

/// Non-negative remainder of `x` modulo a full turn, in `[0, 2 pi)`.
fn turn_rem(x: f64) -> f64 {
    let r = x.rem_euclid(TAU);
    if r >= TAU { 0.0 } else { r }
}

/// The directed common tangent leaving circle 1 and arriving at circle 2, with signed radii
/// (`> 0` the path goes counter-clockwise around the circle, `< 0` clockwise, `0` a point).
/// Returns the (departure, arrival) points, or `None` when that tangent does not exist.
///
/// With `n` the unit normal on the left of the travel direction, a counter-clockwise
/// circle lies on the left, so its tangent point is `c - rho n`; the segment is parallel to
/// the travel direction iff `n . (c2 - c1) = rho2 - rho1`, and going forward picks the
/// normal rotated from `c2 - c1` by `+acos((rho2 - rho1) / |c2 - c1|)`.
fn directed_tangent(c1: &Point, rho1: f64, c2: &Point, rho2: f64) -> Option<(Point, Point)> {
    let d = c2 - c1;
    let dist = d.norm();
    if dist.is_nan() || dist <= 0.0 {
        return None;
    }
    let mut cos = (rho2 - rho1) / dist;
    if cos.abs() > 1.0 {
        // Circles touching within tolerance: the tangent degenerates to the touching point.
        if (rho2 - rho1).abs() - dist <= FREE_TOLERANCE_M {
            cos = cos.signum();
        } else {
            return None;
        }
    }
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let u = d / dist;
    let n = Vector::new(u.x * cos - u.y * sin, u.x * sin + u.y * cos);
    Some((c1 - rho1 * n, c2 - rho2 * n))
}

/// Open angular intervals `(start, width)` of a circle that lie strictly inside other disks
/// or outside the field (beyond tolerance). A width of a full turn blocks the whole circle.
fn blocked_intervals(k: usize, circles: &[Disk], field: &Field) -> Vec<(f64, f64)> {
    let ck = circles[k].center;
    let rk = circles[k].radius_m;
    let mut out = Vec::new();
    // The circle point at angle phi is blocked iff cos(phi - alpha) > c.
    let mut push = |alpha: f64, c: f64| {
        if c >= 1.0 || c.is_nan() {
            return;
        }
        if c <= -1.0 {
            out.push((0.0, TAU));
            return;
        }
        let half = c.acos();
        out.push((turn_rem(alpha - half), 2.0 * half));
    };
    for (j, dj) in circles.iter().enumerate() {
        if j == k {
            continue;
        }
        let reach = dj.radius_m - FREE_TOLERANCE_M;
        if reach <= 0.0 {
            continue;
        }
        let v = dj.center - ck;
        let d = v.norm();
        if d >= rk + reach || d + reach <= rk {
            continue;
        }
        if d == 0.0 {
            // Concentric: reached here only when the circle is inside the larger disk.
            push(0.0, -1.0);
            continue;
        }
        // |ck + rk u(phi) - cj|^2 < reach^2  <=>  cos(phi - alpha) > (d^2 + rk^2 - reach^2) / (2 d rk).
        push(
            v.y.atan2(v.x),
            (d * d + rk * rk - reach * reach) / (2.0 * d * rk),
        );
    }
    // Field edges, as outward normal m and offset h (inside: m . p <= h); the circle point is
    // outside iff m . ck + rk cos(phi - alpha_m) > h + tol.
    let edges = [
        (Vector::new(-1.0, 0.0), 0.0),
        (Vector::new(1.0, 0.0), field.width_m),
        (Vector::new(0.0, -1.0), 0.0),
        (Vector::new(0.0, 1.0), field.height_m),
    ];
    for (m, h) in edges {
        push(
            m.y.atan2(m.x),
            (h + FREE_TOLERANCE_M - m.dot(&ck.coords)) / rk,
        );
    }
    out
}

/// How far (unsigned angle) one can travel around a circle from `angle_rad` in `sense`
/// without entering any blocked interval; a full turn when nothing blocks.
fn free_extent_rad(intervals: &[(f64, f64)], angle_rad: f64, sense: i8) -> f64 {
    let mut extent = TAU;
    for &(start, width) in intervals {
        if width >= TAU {
            return 0.0;
        }
        let (inside_at, distance) = if sense > 0 {
            (turn_rem(angle_rad - start), turn_rem(start - angle_rad))
        } else {
            let end = start + width;
            (turn_rem(end - angle_rad), turn_rem(angle_rad - end))
        };
        if inside_at > 0.0 && inside_at < width {
            return 0.0;
        }
        extent = extent.min(distance);
    }
    extent
}

/// One round of the search: the candidate circles, the ellipse bound and the caches.
struct Planner<'a, 's> {
    space: &'a FreeSpace<'s>,
    from: Point,
    to: Point,
    circles: &'a [Disk],
    /// Ellipse bound (`INFINITY` in the last round).
    limit_m: f64,
    /// Blocked intervals per circle, computed on first use.
    blocked: Vec<Option<Vec<(f64, f64)>>>,
}

impl<'a, 's> Planner<'a, 's> {
    fn new(
        space: &'a FreeSpace<'s>,
        from: Point,
        to: Point,
        circles: &'a [Disk],
        limit_m: f64,
    ) -> Self {
        Self {
            space,
            from,
            to,
            circles,
            limit_m,
            blocked: vec![None; circles.len()],
        }
    }

    fn start_node(&self) -> Node {
        Node {
            key: NodeKey {
                from: START,
                from_sense: 0,
                to: START,
                to_sense: 0,
            },
            point: self.from,
            angle_rad: 0.0,
        }
    }

    fn search(&mut self) -> Option<(Vec<Node>, TotalF64)> {
        let start = self.start_node();
        let goal = self.to;
        astar(
            &start,
            |node| self.successors(node),
            |node| TotalF64((goal - node.point).norm()),
            |node| node.key.to == GOAL,
        )
    }

    fn within_limit(&self, p: &Point) -> bool {
        (p - self.from).norm() + (p - self.to).norm() <= self.limit_m + FREE_TOLERANCE_M
    }

    fn intervals(&mut self, k: usize) -> &[(f64, f64)] {
        let circles = self.circles;
        let field = self.space.field;
        self.blocked[k].get_or_insert_with(|| blocked_intervals(k, circles, &field))
    }

    /// The edge from `node` to `target`, if the tangent exists (not checked for freedom).
    fn edge(&self, node: &Node, target: Target) -> Option<Edge> {
        let (dst_center, dst_rho) = match target {
            Target::Circle(j, sense) => {
                let d = &self.circles[j as usize];
                (d.center, f64::from(sense) * d.radius_m)
            }
            Target::Goal => (self.to, 0.0),
        };
        if node.key.to == START {
            // Straight from the start to an arrival on a circle.
            let Target::Circle(..) = target else {
                return None;
            };
            let v = self.from - dst_center;
            if (v.norm() - dst_rho.abs()).abs() <= FREE_TOLERANCE_M {
                // The start is on this circle: go on around it from the start itself.
                return Some(Edge {
                    sweep_rad: 0.0,
                    depart: self.from,
                    arrive: self.from,
                    arrive_angle_rad: v.y.atan2(v.x),
                    degenerate: true,
                });
            }
            let (depart, arrive) = directed_tangent(&self.from, 0.0, &dst_center, dst_rho)?;
            let w = arrive - dst_center;
            return Some(Edge {
                sweep_rad: 0.0,
                depart,
                arrive,
                arrive_angle_rad: w.y.atan2(w.x),
                degenerate: false,
            });
        }
        let k = node.key.to as usize;
        let sense = node.key.to_sense;
        let src = &self.circles[k];
        let src_rho = f64::from(sense) * src.radius_m;
        let (depart, arrive, arrive_angle_rad, degenerate) = match target {
            Target::Goal => {
                let v = self.to - src.center;
                if (v.norm() - src.radius_m).abs() <= FREE_TOLERANCE_M {
                    // The goal is on this circle: the arc ends at the goal's angle.
                    (self.to, self.to, 0.0, true)
                } else {
                    let (d, a) = directed_tangent(&src.center, src_rho, &self.to, 0.0)?;
                    (d, a, 0.0, false)
                }
            }
            Target::Circle(..) => {
                let (d, a) = directed_tangent(&src.center, src_rho, &dst_center, dst_rho)?;
                let w = a - dst_center;
                (d, a, w.y.atan2(w.x), false)
            }
        };
        let v = depart - src.center;
        let depart_angle = v.y.atan2(v.x);
        let mut sweep_rad = turn_rem(f64::from(sense) * (depart_angle - node.angle_rad));
        if sweep_rad > TAU - FULL_TURN_SNAP_RAD {
            sweep_rad = 0.0;
        }
        Some(Edge {
            sweep_rad,
            depart,
            arrive,
            arrive_angle_rad,
            degenerate,
        })
    }

    fn successors(&mut self, node: &Node) -> Vec<(Node, TotalF64)> {
        let mut out = Vec::new();
        let on_circle = node.key.to != START;
        let (extent_rad, radius_m) = if on_circle {
            let k = node.key.to as usize;
            let extent = free_extent_rad(self.intervals(k), node.angle_rad, node.key.to_sense);
            (extent, self.circles[k].radius_m)
        } else {
            (0.0, 0.0)
        };
        let (from, from_sense) = (node.key.to, node.key.to_sense);
        for j in 0..self.circles.len() as u32 {
            if j == node.key.to {
                continue;
            }
            for sense in [1i8, -1] {
                let Some(edge) = self.edge(node, Target::Circle(j, sense)) else {
                    continue;
                };
                if edge.sweep_rad > extent_rad + SWEEP_SLACK_RAD
                    || !self.within_limit(&edge.arrive)
                    || !(edge.degenerate
                        || self
                            .space
                            .is_segment_free(&edge.depart, &edge.arrive, FREE_TOLERANCE_M))
                {
                    continue;
                }
                let cost = radius_m * edge.sweep_rad + (edge.arrive - edge.depart).norm();
                let key = NodeKey {
                    from,
                    from_sense,
                    to: j,
                    to_sense: sense,
                };
                out.push((
                    Node {
                        key,
                        point: edge.arrive,
                        angle_rad: edge.arrive_angle_rad,
                    },
                    TotalF64(cost),
                ));
            }
        }
        if on_circle && let Some(edge) = self.edge(node, Target::Goal) {
            let free = edge.degenerate
                || self
                    .space
                    .is_segment_free(&edge.depart, &edge.arrive, FREE_TOLERANCE_M);
            if edge.sweep_rad <= extent_rad + SWEEP_SLACK_RAD && free {
                let cost = radius_m * edge.sweep_rad + (edge.arrive - edge.depart).norm();
                let key = NodeKey {
                    from: GOAL,
                    from_sense: 0,
                    to: GOAL,
                    to_sense: 0,
                };
                out.push((
                    Node {
                        key,
                        point: self.to,
                        angle_rad: 0.0,
                    },
                    TotalF64(cost),
                ));
            }
        }
        out
    }

    /// Turn the node chain found by the search into pieces, exactly continuous, from the
    /// exact start to the exact goal.
    fn build_path(&self, nodes: &[Node]) -> DiskPath {
        let mut pieces: Vec<PathPiece> = Vec::new();
        let mut cur = self.from;
        for pair in nodes.windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            let target = if b.key.to == GOAL {
                Target::Goal
            } else {
                Target::Circle(b.key.to, b.key.to_sense)
            };
            // The search accepted this edge; recomputing it gives the same bits.
            let Some(edge) = self.edge(a, target) else {
                debug_assert!(false, "an accepted edge must recompute");
                continue;
            };
            if a.key.to != START {
                let circle = &self.circles[a.key.to as usize];
                if circle.radius_m * edge.sweep_rad > MIN_ARC_LENGTH_M {
                    let arc = PathPiece::Arc {
                        center: circle.center,
                        radius_m: circle.radius_m,
                        start_rad: a.angle_rad,
                        sweep_rad: f64::from(a.key.to_sense) * edge.sweep_rad,
                    };
                    join(&mut pieces, &mut cur, arc.start());
                    cur = arc.end();
                    pieces.push(arc);
                }
            }
            join(&mut pieces, &mut cur, edge.arrive);
        }
        join(&mut pieces, &mut cur, self.to);
        if pieces.is_empty() {
            pieces.push(PathPiece::Segment {
                from: self.from,
                to: self.to,
            });
        }
        DiskPath::new(self.from, pieces)
    }
}

/// Continue the pieces from `cur` to `next`: a point within tolerance of the last
/// segment's end replaces that end (rounding between two formulas for one tangent point);
/// otherwise a segment joins them.
fn join(pieces: &mut Vec<PathPiece>, cur: &mut Point, next: Point) {
    if *cur == next {
        return;
    }
    if let Some(PathPiece::Segment { from, to }) = pieces.last_mut()
        && (next - *to).norm() <= FREE_TOLERANCE_M
        && *from != next
    {
        *to = next;
    } else {
        pieces.push(PathPiece::Segment {
            from: *cur,
            to: next,
        });
    }
    *cur = next;
}

/// Union-find over barrier nodes, each with the parity of its path to its root.
struct ParityUnionFind {
    parent: Vec<usize>,
    parity: Vec<bool>,
}

impl ParityUnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
            parity: vec![false; n],
        }
    }

    /// Root of `x` and the parity of `x` relative to it (with path compression).
    fn find(&mut self, x: usize) -> (usize, bool) {
        let (mut root, mut parity) = (x, false);
        while self.parent[root] != root {
            parity ^= self.parity[root];
            root = self.parent[root];
        }
        let (mut cur, mut cur_parity) = (x, parity);
        while self.parent[cur] != root && cur != root {
            let next = self.parent[cur];
            let next_parity = cur_parity ^ self.parity[cur];
            self.parent[cur] = root;
            self.parity[cur] = cur_parity;
            cur = next;
            cur_parity = next_parity;
        }
        (root, parity)
    }

    /// Join `a` and `b` with an edge of parity `p`; `false` when that closes a cycle of odd
    /// parity.
    fn union(&mut self, a: usize, b: usize, p: bool) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return pa ^ pb == p;
        }
        self.parent[ra] = rb;
        self.parity[ra] = pa ^ pb ^ p;
        true
    }
}

/// `(b - a) x (c - a)`.
fn orient(a: &Point, b: &Point, c: &Point) -> f64 {
    let (u, v) = (b - a, c - a);
    u.x * v.y - u.y * v.x
}

/// Whether segment `p`-`q` crosses segment `s`-`t`, counting a vertex on the line `s`-`t`
/// as lying on its non-positive side (so crossings of a closed polygon have the right
/// parity). Assumes `s` and `t` are not on `p`-`q`.
fn crosses(s: &Point, t: &Point, p: &Point, q: &Point) -> bool {
    let (dp, dq) = (orient(s, t, p), orient(s, t, q));
    if (dp > 0.0) == (dq > 0.0) {
        return false;
    }
    let x = p + (dp / (dp - dq)) * (q - p);
    let st = t - s;
    let mu = (x - s).dot(&st) / st.norm_squared();
    mu > 0.0 && mu < 1.0
}

/// Every barrier edge among `disks`: a pair of disks `i < j` that overlap by more than
/// [`BARRIER_MARGIN_M`], with the segment between their centres, and a disk crossing a field
/// edge by more than that margin, joined to vertex `disks.len()` (the outside of the field)
/// by the segment from its centre to a point beyond that edge. Every such segment lies in
/// the obstacle (the union of the disks and the outside of the field) with a depth far above
/// [`FREE_TOLERANCE_M`]. Stops when `visit` breaks.
fn visit_barrier_edges(
    field: &Field,
    disks: &[Disk],
    mut visit: impl FnMut(usize, usize, &Point, &Point) -> ControlFlow<()>,
) -> ControlFlow<()> {
    let outside = disks.len();
    let r_max = disks.iter().map(|d| d.radius_m).fold(0.0, f64::max);
    let mut order: Vec<usize> = (0..disks.len()).collect();
    order.sort_by(|&a, &b| disks[a].center.x.total_cmp(&disks[b].center.x));
    for (pos, &i) in order.iter().enumerate() {
        let di = &disks[i];
        for &j in &order[pos + 1..] {
            let dj = &disks[j];
            if dj.center.x - di.center.x >= di.radius_m + r_max {
                break;
            }
            let reach = di.radius_m + dj.radius_m - BARRIER_MARGIN_M;
            if (dj.center - di.center).norm() < reach {
                visit(i, j, &di.center, &dj.center)?;
            }
        }
        let (c, r, m) = (di.center, di.radius_m, BARRIER_MARGIN_M);
        let (w, h) = (field.width_m, field.height_m);
        let exits = [
            (c.x < r - m, Point::new(c.x.min(0.0) - 1.0, c.y)),
            (c.x > w - r + m, Point::new(c.x.max(w) + 1.0, c.y)),
            (c.y < r - m, Point::new(c.x, c.y.min(0.0) - 1.0)),
            (c.y > h - r + m, Point::new(c.x, c.y.max(h) + 1.0)),
        ];
        for (crosses_edge, beyond) in exits {
            if crosses_edge {
                visit(i, outside, &c, &beyond)?;
            }
        }
    }
    ControlFlow::Continue(())
}

/// Whether some closed chain of overlapping `disks` (the outside of the field counting as
/// one more obstacle) separates `s` from `t`.
///
/// The segment between the centres of two disks that overlap lies inside their union, and
/// so does the segment from the centre of a disk crossing a field edge to a point beyond
/// that edge; joining such segments gives closed curves made of obstacle
/// ([`visit_barrier_edges`]). A curve crossed an odd number of times by the segment `s`-`t`
/// separates them, which shows as a cycle of odd parity in a union-find with parities.
/// Overlaps must exceed [`BARRIER_MARGIN_M`], so `s` and `t` (free within
/// [`FREE_TOLERANCE_M`]) never lie on these curves and no path within tolerance passes.
/// Sound, not complete: `false` means "not shown".
fn separated(field: &Field, s: &Point, t: &Point, disks: &[Disk]) -> bool {
    let mut uf = ParityUnionFind::new(disks.len() + 1);
    visit_barrier_edges(field, disks, |i, j, p, q| {
        if uf.union(i, j, crosses(s, t, p, q)) {
            ControlFlow::Continue(())
        } else {
            ControlFlow::Break(())
        }
    })
    .is_break()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DiskGrid;

    fn plan(field: Field, disks: Vec<Disk>, from: Point, to: Point) -> Result<DiskPath, PathError> {
        let grid = DiskGrid::new(disks);
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        shortest_path(&space, &from, &to)
    }

    /// Brute-force minimum clearance of dense samples against every disk, and the
    /// smallest inset into the field.
    fn min_clearance_and_inset(path: &DiskPath, disks: &[Disk], field: &Field) -> (f64, f64) {
        let mut clearance = f64::INFINITY;
        let mut inset = f64::INFINITY;
        for p in path.sample(1e-3) {
            for d in disks {
                clearance = clearance.min((p - d.center).norm() - d.radius_m);
            }
            inset = inset.min(field.signed_inset_m(&p));
        }
        (clearance, inset)
    }

    fn assert_continuous(path: &DiskPath, from: &Point, to: &Point) {
        assert_eq!(path.start(), *from);
        assert_eq!(path.end(), *to);
        for w in path.pieces.windows(2) {
            assert!(
                (w[0].end() - w[1].start()).norm() <= 1e-9,
                "gap between {:?} and {:?}",
                w[0],
                w[1]
            );
        }
    }

    #[test]
    fn straight_line_when_visible() {
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(5.0, 8.0, 1.0)];
        let (a, b) = (Point::new(1.0, 1.0), Point::new(9.0, 2.0));
        let path = plan(field, disks, a, b).expect("path");
        assert_eq!(path.pieces, vec![PathPiece::Segment { from: a, to: b }]);
        assert!((path.length_m() - (b - a).norm()).abs() < 1e-12);
    }

    #[test]
    fn same_point_is_a_zero_length_segment() {
        let field = Field::new(10.0, 10.0);
        let a = Point::new(3.0, 3.0);
        let path = plan(field, vec![], a, a).expect("path");
        assert_eq!(path.pieces.len(), 1);
        assert_eq!(path.length_m(), 0.0);
        assert_eq!((path.start(), path.end()), (a, a));
        assert_eq!(path.sample(0.1), vec![a, a]);
    }

    #[test]
    fn one_disk_in_the_way_matches_the_analytic_length() {
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(5.0, 5.0, 1.0)];
        let (a, b) = (Point::new(2.0, 5.0), Point::new(8.0, 5.0));
        let path = plan(field, disks.clone(), a, b).expect("path");
        // Two tangents of length sqrt(3^2 - 1^2), and the arc between the tangent points.
        let expected = 2.0 * 8f64.sqrt() + (std::f64::consts::PI - 2.0 * (1.0f64 / 3.0).acos());
        assert!(
            (path.length_m() - expected).abs() < 1e-9,
            "{} vs {}",
            path.length_m(),
            expected
        );
        assert_eq!(path.pieces.len(), 3);
        assert!(matches!(path.pieces[1], PathPiece::Arc { .. }));
        assert_continuous(&path, &a, &b);
        let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9 && inset >= -1e-9);
    }

    #[test]
    fn start_and_goal_on_the_boundary() {
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(5.0, 5.0, 1.0)];
        let (a, b) = (Point::new(4.0, 5.0), Point::new(6.0, 5.0));
        let path = plan(field, disks.clone(), a, b).expect("path");
        assert!((path.length_m() - std::f64::consts::PI).abs() < 1e-9);
        assert_continuous(&path, &a, &b);
        // Start on the boundary, goal far: tangent from the goal, arc from the start.
        let c = Point::new(9.0, 5.0);
        let path = plan(field, disks.clone(), a, c).expect("path");
        let expected = 15f64.sqrt() + (std::f64::consts::PI - (0.25f64).acos());
        assert!(
            (path.length_m() - expected).abs() < 1e-9,
            "{} vs {}",
            path.length_m(),
            expected
        );
        assert_continuous(&path, &a, &c);
        let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9);
    }

    #[test]
    fn goal_where_two_circles_cross() {
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(4.0, 5.0, 1.0), Disk::new(5.5, 5.0, 1.0)];
        // Upper intersection point of the two circles.
        let y = 5.0 + (1.0f64 - 0.75f64 * 0.75).sqrt();
        let goal = Point::new(4.75, y);
        let start = Point::new(4.75, 3.0);
        let path = plan(field, disks.clone(), start, goal).expect("path");
        assert_continuous(&path, &start, &goal);
        let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9, "{clearance}");
        let back = plan(field, disks.clone(), goal, start).expect("path back");
        assert!((back.length_m() - path.length_m()).abs() < 1e-9);
    }

    #[test]
    fn enclosed_goal_is_unreachable() {
        let field = Field::new(20.0, 20.0);
        let mut disks = Vec::new();
        for i in 0..12 {
            let a = i as f64 * TAU / 12.0;
            disks.push(Disk::new(10.0 + 3.0 * a.cos(), 10.0 + 3.0 * a.sin(), 1.0));
        }
        let inside = Point::new(10.0, 10.0);
        let outside = Point::new(1.0, 2.0);
        assert_eq!(
            plan(field, disks.clone(), outside, inside),
            Err(PathError::Unreachable)
        );
        assert_eq!(
            plan(field, disks.clone(), inside, outside),
            Err(PathError::Unreachable)
        );
        assert_eq!(
            plan(
                field,
                disks.clone(),
                Point::new(10.0, 10.0),
                Point::new(10.0, 14.5)
            ),
            Err(PathError::Unreachable)
        );
        // Remove one disk of the ring: a path exists and goes through the gap.
        disks.remove(3);
        let path = plan(field, disks.clone(), outside, inside).expect("path through the gap");
        let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9);
    }

    #[test]
    fn wall_and_disk_enclose_a_corner() {
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(0.0, 0.0, 3.0)];
        let r = plan(field, disks, Point::new(0.5, 0.5), Point::new(8.0, 8.0));
        assert_eq!(r, Err(PathError::StartNotFree));
        // A disk across the corner region: x + y < 2 is cut off by a barrier of three disks.
        let disks = vec![
            Disk::new(0.0, 3.0, 1.0),
            Disk::new(1.5, 1.5, 1.3),
            Disk::new(3.0, 0.0, 1.0),
        ];
        let r = plan(field, disks, Point::new(0.3, 0.3), Point::new(8.0, 8.0));
        assert_eq!(r, Err(PathError::Unreachable));
    }

    #[test]
    fn disk_sticking_out_of_the_field_forces_the_other_side() {
        let field = Field::new(10.0, 10.0);
        // Centre above the line s-t, so going below would be shorter, but the disk reaches
        // below y = 0: the lower arc would leave the field.
        let disks = vec![Disk::new(5.0, 1.5, 2.0)];
        let (a, b) = (Point::new(1.0, 1.0), Point::new(9.0, 1.0));
        let path = plan(field, disks.clone(), a, b).expect("path");
        let c = disks[0].center;
        let (va, vb) = (a - c, b - c);
        let d = va.norm();
        let (angle_a, angle_b) = (va.y.atan2(va.x), vb.y.atan2(vb.x));
        let over_top = turn_rem(angle_a - angle_b);
        let expected = 2.0 * (d * d - 4.0).sqrt() + 2.0 * (over_top - 2.0 * (2.0 / d).acos());
        assert!(
            (path.length_m() - expected).abs() < 1e-9,
            "{} vs {}",
            path.length_m(),
            expected
        );
        let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9 && inset >= -1e-9);
        assert!(
            path.sample(0.01).iter().any(|p| p.y > 3.0),
            "goes over the top"
        );
    }

    #[test]
    fn an_arc_may_not_dip_out_of_the_field() {
        // Start and goal on the circle, both in the field; the short arc between them passes
        // below y = 0, so the path goes the long way round (three quarters of the circle).
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(5.0, 2.0, 2.5)];
        let a = disks[0].boundary_point(-0.75 * std::f64::consts::PI);
        let b = disks[0].boundary_point(-0.25 * std::f64::consts::PI);
        assert!(field.contains(&a, 0.0) && field.contains(&b, 0.0));
        let path = plan(field, disks.clone(), a, b).expect("path");
        let expected = 2.5 * 1.5 * std::f64::consts::PI;
        assert!(
            (path.length_m() - expected).abs() < 1e-9,
            "{} vs {}",
            path.length_m(),
            expected
        );
        let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9 && inset >= -1e-9);
    }

    #[test]
    fn long_wall_needs_several_ellipse_rounds() {
        // A wall of overlapping disks between start and goal; its free end lies far outside
        // the first ellipses, whose candidate disks stop part-way up the wall.
        let field = Field::new(60.0, 20.0);
        let disks: Vec<Disk> = (0..28)
            .map(|i| Disk::new(30.0, 0.6 * i as f64, 0.5))
            .collect();
        let (a, b) = (Point::new(29.0, 5.0), Point::new(31.0, 5.0));
        let path = plan(field, disks.clone(), a, b).expect("path");
        assert_continuous(&path, &a, &b);
        let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9 && inset >= -1e-9, "{clearance} {inset}");
        // Around the top disk (30, 16.2): symmetric tangents plus the arc over it.
        let top = disks[27];
        let d = (top.center - a).norm();
        // a and b seen from the top centre are 2 atan(1 / 11.2) apart below it; the arc
        // covers the rest of the turn minus the two tangent angles.
        let below = 2.0 * (1.0f64 / 11.2).atan();
        let over = TAU - below - 2.0 * (0.5 / d).acos();
        let expected = 2.0 * (d * d - 0.25).sqrt() + 0.5 * over;
        assert!(
            (path.length_m() - expected).abs() < 1e-9,
            "{} vs {}",
            path.length_m(),
            expected
        );
    }

    #[test]
    fn a_path_longer_than_the_ellipse_bound_is_not_trusted() {
        // Wall of small disks with one large disk k in it. In the round with bound 16 the
        // tangent points on k lie in the ellipse but the arc over k's top runs into the next
        // wall disk, which is not a candidate yet: that (invalid) path is longer than the
        // bound, so it must be rejected and the search widened.
        let field = Field::new(60.0, 60.0);
        let mut disks: Vec<Disk> = (0..=27)
            .map(|i| Disk::new(30.0, 0.6 * i as f64, 0.5))
            .collect();
        disks.push(Disk::new(30.0, 18.2, 2.0));
        disks.extend((0..=33).map(|i| Disk::new(30.0, 20.0 + 0.6 * i as f64, 0.5)));
        let (a, b) = (Point::new(29.0, 11.0), Point::new(31.0, 11.0));
        let path = plan(field, disks.clone(), a, b).expect("path");
        let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9 && inset >= -1e-9, "{clearance} {inset}");
        // Up the left side: tangent to k, arc on k, outer tangent from k to the top wall
        // disk (30, 39.8), over its top, and the mirror image down to b.
        let (ck, rk, r_top, rise) = (Point::new(30.0, 18.2), 2.0, 0.5, 39.8 - 18.2);
        let d1 = (ck - a).norm();
        let theta1 = (a - ck).y.atan2((a - ck).x) + TAU - (rk / d1).acos();
        let alpha = ((rk - r_top) / rise).asin();
        let theta2 = std::f64::consts::PI - alpha;
        let side = (d1 * d1 - rk * rk).sqrt()
            + rk * (theta1 - theta2)
            + (rise * rise - (rk - r_top).powi(2)).sqrt();
        let expected = 2.0 * side + r_top * (std::f64::consts::PI - 2.0 * alpha);
        assert!(
            (path.length_m() - expected).abs() < 1e-9,
            "{} vs {}",
            path.length_m(),
            expected
        );
    }

    #[test]
    fn start_and_goal_within_tolerance_inside_a_disk() {
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(5.0, 5.0, 1.0)];
        let a = Point::new(4.0 + 5e-10, 5.0);
        let b = Point::new(6.0 - 5e-10, 5.0);
        let path = plan(field, disks.clone(), a, b).expect("path");
        assert_continuous(&path, &a, &b);
        assert!((path.length_m() - std::f64::consts::PI).abs() < 1e-8);
        let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
        assert!(clearance >= -1e-9, "{clearance}");
        let deep = Point::new(4.0 + 2e-9, 5.0);
        assert_eq!(plan(field, disks, deep, b), Err(PathError::StartNotFree));
    }

    #[test]
    fn every_layer_blocks() {
        let field = Field::new(10.0, 10.0);
        let obstacles = DiskGrid::new(vec![Disk::new(5.0, 5.0, 1.0)]);
        let agents = DiskGrid::new(vec![Disk::new(5.0, 6.5, 0.6), Disk::new(5.0, 3.5, 0.6)]);
        let layers = [&obstacles, &agents];
        let space = FreeSpace::new(field, &layers);
        let (a, b) = (Point::new(2.0, 5.0), Point::new(8.0, 5.0));
        let path = shortest_path(&space, &a, &b).expect("path");
        let mut all = obstacles.disks().to_vec();
        all.extend_from_slice(agents.disks());
        let (clearance, _) = min_clearance_and_inset(&path, &all, &field);
        assert!(clearance >= -1e-9, "{clearance}");
        let one_disk = 2.0 * 8f64.sqrt() + (std::f64::consts::PI - 2.0 * (1.0f64 / 3.0).acos());
        assert!(
            path.length_m() > one_disk + 0.1,
            "the agents' layer must lengthen the path"
        );
    }

    #[test]
    fn barrier_test_finds_closed_rings_only() {
        let field = Field::new(20.0, 20.0);
        let ring: Vec<Disk> = (0..12)
            .map(|i| {
                let a = i as f64 * TAU / 12.0;
                Disk::new(10.0 + 3.0 * a.cos(), 10.0 + 3.0 * a.sin(), 1.0)
            })
            .collect();
        let (inside, outside) = (Point::new(10.0, 10.0), Point::new(1.0, 2.0));
        assert!(separated(&field, &inside, &outside, &ring));
        assert!(separated(&field, &outside, &inside, &ring));
        assert!(!separated(&field, &outside, &Point::new(18.0, 3.0), &ring));
        assert!(!separated(&field, &inside, &Point::new(10.5, 9.0), &ring));
        let open: Vec<Disk> = ring.iter().copied().skip(1).collect();
        assert!(!separated(&field, &inside, &outside, &open));
        // A barrier closed through the outside of the field (two wall crossings).
        let corner = vec![
            Disk::new(0.0, 3.0, 1.0),
            Disk::new(1.5, 1.5, 1.3),
            Disk::new(3.0, 0.0, 1.0),
        ];
        assert!(separated(
            &field,
            &Point::new(0.3, 0.3),
            &Point::new(8.0, 8.0),
            &corner
        ));
        assert!(!separated(
            &field,
            &Point::new(8.0, 0.3),
            &Point::new(8.0, 8.0),
            &corner
        ));
        // A wall across the whole field.
        let wall: Vec<Disk> = (0..12)
            .map(|i| Disk::new(10.0, 1.8 * i as f64, 1.0))
            .collect();
        assert!(separated(
            &field,
            &Point::new(2.0, 5.0),
            &Point::new(18.0, 15.0),
            &wall
        ));
        assert!(!separated(
            &field,
            &Point::new(2.0, 5.0),
            &Point::new(2.0, 15.0),
            &wall
        ));
    }

    /// A packed block of agents at 1 m spacing, each inflated to 0.601 m (radius 0.3 m
    /// twice plus a margin): orthogonal neighbours overlap, so every agent's position is a
    /// pocket closed by its eight neighbours.
    fn packed_block() -> (Field, Vec<Disk>) {
        let mut disks = Vec::new();
        for i in 0..9 {
            for j in 0..7 {
                disks.push(Disk::new(2.0 + i as f64, 2.0 + j as f64, 0.601));
            }
        }
        (Field::new(14.0, 12.0), disks)
    }

    #[test]
    fn barrier_graph_agrees_with_the_barrier_test() {
        let (field, mut disks) = packed_block();
        // An open pocket, and disks crossing the field edges (barriers through the outside).
        disks.remove(30);
        disks.push(Disk::new(0.2, 6.0, 0.8));
        disks.push(Disk::new(13.5, 11.5, 1.0));
        let grid = DiskGrid::new(disks.clone());
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        let s = Point::new(5.5, 4.5);
        let mut graph = BarrierGraph::new(&space, &s, 100.0);
        let (mut separated_count, mut free_count) = (0, 0);
        for i in 0..=56 {
            for j in 0..=48 {
                let t = Point::new(0.25 * i as f64, 0.25 * j as f64);
                if !space.is_free(&t, 0.0) {
                    continue;
                }
                free_count += 1;
                let expected = separated(&field, &s, &t, &disks);
                assert_eq!(graph.separates(&s, &t), expected, "{t:?}");
                separated_count += usize::from(expected);
            }
        }
        assert!(separated_count > 0 && separated_count < free_count);
    }

    #[test]
    fn paths_from_a_pocket_match_shortest_path() {
        let (field, disks) = packed_block();
        let grid = DiskGrid::new(disks.clone());
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        // An agent's position in the block: a pocket.
        let me = Point::new(5.5, 4.5);
        let mut paths = PathsFrom::new(&space, &me);
        let goals = [
            Point::new(5.6, 4.3),   // same pocket, straight
            Point::new(6.5, 4.5),   // a neighbouring pocket
            Point::new(1.0, 1.0),   // outside the block
            Point::new(20.0, 1.0),  // outside the field
            Point::new(5.0, 6.0),   // inside a disk
            Point::new(13.0, 11.0), // far outside the block
        ];
        let mut unreachable = 0;
        for goal in &goals {
            let fast = paths.shortest_path(goal);
            let slow = shortest_path(&space, &me, goal);
            assert_eq!(format!("{fast:?}"), format!("{slow:?}"), "{goal:?}");
            unreachable += usize::from(fast == Err(PathError::Unreachable));
        }
        assert_eq!(unreachable, 3);
        // The barrier graph alone shows the pocket closed.
        let graph = paths
            .barriers
            .as_mut()
            .expect("built for the blocked goals");
        assert!(graph.separates(&me, &Point::new(1.0, 1.0)));
        assert!(!graph.separates(&me, &Point::new(5.4, 4.6)));
        // From outside the block, a path around it.
        let mut outside = PathsFrom::new(&space, &Point::new(1.0, 1.0));
        let around = outside.shortest_path(&Point::new(13.0, 11.0));
        assert_eq!(
            around,
            shortest_path(&space, &Point::new(1.0, 1.0), &Point::new(13.0, 11.0))
        );
        assert!(around.is_ok());
    }

    #[test]
    fn start_and_goal_outside_free_space_are_rejected() {
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(5.0, 5.0, 1.0)];
        let inside = Point::new(5.2, 5.0);
        let free = Point::new(1.0, 1.0);
        assert_eq!(
            plan(field, disks.clone(), inside, free),
            Err(PathError::StartNotFree)
        );
        assert_eq!(
            plan(field, disks.clone(), free, inside),
            Err(PathError::GoalNotFree)
        );
        assert_eq!(
            plan(field, disks.clone(), Point::new(-1.0, 1.0), free),
            Err(PathError::StartNotFree)
        );
        let nan = Point::new(f64::NAN, 1.0);
        assert_eq!(plan(field, disks, nan, free), Err(PathError::StartNotFree));
    }

    #[test]
    fn polyline_vertices_lie_on_arcs_and_respect_the_chord_error() {
        let arc = PathPiece::Arc {
            center: Point::new(1.0, 2.0),
            radius_m: 2.0,
            start_rad: 0.3,
            sweep_rad: -2.5,
        };
        let path = DiskPath::new(arc.start(), vec![arc]);
        for e in [1e-1, 1e-3, 1e-6] {
            let poly = path.polyline(e);
            assert_eq!(poly[0], path.start());
            assert_eq!(*poly.last().expect("vertices"), path.end());
            for w in poly.windows(2) {
                assert!(((w[0] - Point::new(1.0, 2.0)).norm() - 2.0).abs() < 1e-12);
                let mid = nalgebra::center(&w[0], &w[1]);
                assert!(2.0 - (mid - Point::new(1.0, 2.0)).norm() <= e + 1e-12);
            }
        }
    }

    #[test]
    fn barrier_parity_handles_vertices_on_the_segment_line() {
        // s on the horizontal line through a disk centre crossing the left wall.
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(0.5, 5.0, 1.0)];
        assert!(!separated(
            &field,
            &Point::new(3.0, 5.0),
            &Point::new(3.0, 8.0),
            &disks
        ));
        assert!(!separated(
            &field,
            &Point::new(3.0, 5.0),
            &Point::new(8.0, 5.0),
            &disks
        ));
    }

    #[test]
    fn determinism() {
        let field = Field::new(20.0, 20.0);
        let disks: Vec<Disk> = (0..30)
            .map(|i| {
                let f = i as f64;
                Disk::new(
                    (f * 7.3) % 20.0,
                    (f * 3.7 + 1.0) % 20.0,
                    0.8 + (f * 0.37) % 0.9,
                )
            })
            .collect();
        let (a, b) = (Point::new(0.2, 0.2), Point::new(19.5, 19.7));
        let p1 = plan(field, disks.clone(), a, b);
        let p2 = plan(field, disks, a, b);
        assert_eq!(format!("{p1:?}"), format!("{p2:?}"));
    }
}
