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
//! Polygons grown by the agent's radius
//! ([`InflatedPolygon`](crate::geometry::InflatedPolygon)) take part too: a path bends
//! round one only on the circles of its convex corners, so those circles join the tangent
//! graph, segments are checked against the polygons, and an arc is checked against the
//! angles where its circle crosses a polygon's offset sides and corner circles.
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
//!   ([`FreeSpace::is_segment_free`](crate::geometry::FreeSpace::is_segment_free)). Arcs
//!   are checked exactly: the part of a circle that lies strictly inside another disk, or
//!   outside a field edge, is an open angular interval (from the circle-circle or
//!   circle-line intersection angles), and an arc is allowed only if it enters none of them.
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
//!
//! # Files
//!
//! - `path.rs`: [`DiskPath`] and its [`PathPiece`]s;
//! - `shortest_path.rs`: [`shortest_path()`], the ellipse-bound rounds;
//! - `tangent_graph.rs`: one round's lazy tangent graph and its A\*;
//! - `free_arcs.rs`: the exact check of arcs (blocked angular intervals of a circle);
//! - `barrier.rs` and `parity_union_find.rs`: the barrier test of unreachability;
//! - `barrier_graph.rs`: the same test prepared once for many goals;
//! - `paths_from.rs`: [`PathsFrom`], many goals from one start;
//! - `tolerance.rs` and `error.rs`: [`FREE_TOLERANCE_M`] and [`PathError`].

mod barrier;
mod barrier_graph;
mod error;
mod free_arcs;
mod parity_union_find;
mod path;
mod paths_from;
mod shortest_path;
mod tangent_graph;
#[cfg(test)]
mod tests;
mod tolerance;

pub use error::PathError;
pub use path::{DiskPath, PathPiece};
pub use paths_from::PathsFrom;
pub use shortest_path::shortest_path;
pub use tolerance::FREE_TOLERANCE_M;
