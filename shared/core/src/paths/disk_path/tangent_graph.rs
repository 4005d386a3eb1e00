//! The lazy tangent visibility graph and its A* search, for one round of
//! [`shortest_path`](super::shortest_path()).
//!
//! A node is an *arrival* on a circle: the end point of a directed tangent segment, with the
//! sense in which the path goes on around that circle; its identity is a tuple of integers,
//! its point a pure function of them. An edge follows the arc from an arrival to a departure
//! tangent point, then the tangent segment to the next arrival (or the goal). Successors are
//! generated on demand.

use std::f64::consts::TAU;

use pathfinding::directed::astar::astar;

use super::free_arcs::{blocked_intervals, free_extent_rad, turn_rem};
use super::path::{DiskPath, PathPiece};
use super::tolerance::FREE_TOLERANCE_M;
use crate::geometry::{Disk, FreeSpace, Point, Vector};
use crate::ordered::TotalF64;

/// An arc this close to a full turn is a rounding artefact of an exactly collinear pair of
/// tangents: it is treated as no arc at all (radians).
const FULL_TURN_SNAP_RAD: f64 = 1e-9;

/// Arcs shorter than this are not emitted as pieces (metres).
const MIN_ARC_LENGTH_M: f64 = 1e-12;

/// Slack when comparing an arc's sweep with the free extent around its circle (radians).
const SWEEP_SLACK_RAD: f64 = 1e-12;

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
pub(super) struct Node {
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

/// One round of the search: the candidate circles, the ellipse bound and the caches.
pub(super) struct Planner<'a, 's> {
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
    pub(super) fn new(
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

    pub(super) fn search(&mut self) -> Option<(Vec<Node>, TotalF64)> {
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
        let polygons = self.space.polygons;
        self.blocked[k].get_or_insert_with(|| blocked_intervals(k, circles, polygons, &field))
    }

    /// The edge from `node` to `target`, if the tangent exists (not checked for freedom).
    fn edge(&self, node: &Node, target: Target) -> Option<Edge> {
        let (dst_center, dst_rho) = match target {
            Target::Circle(j, sense) => {
                let d = &self.circles[j as usize];
                (d.centre, f64::from(sense) * d.radius_m)
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
                let v = self.to - src.centre;
                if (v.norm() - src.radius_m).abs() <= FREE_TOLERANCE_M {
                    // The goal is on this circle: the arc ends at the goal's angle.
                    (self.to, self.to, 0.0, true)
                } else {
                    let (d, a) = directed_tangent(&src.centre, src_rho, &self.to, 0.0)?;
                    (d, a, 0.0, false)
                }
            }
            Target::Circle(..) => {
                let (d, a) = directed_tangent(&src.centre, src_rho, &dst_center, dst_rho)?;
                let w = a - dst_center;
                (d, a, w.y.atan2(w.x), false)
            }
        };
        let v = depart - src.centre;
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
    pub(super) fn build_path(&self, nodes: &[Node]) -> DiskPath {
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
                        centre: circle.centre,
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
