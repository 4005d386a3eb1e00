//! The best point of the paper's Theorem 1: the point of the field nearest to an agent's
//! ideal slot `x*` that lies outside every (inflated) disk, found exactly.
//!
//! # Method
//!
//! The free set `F` is the closed field rectangle minus the open disks (a point on a
//! circle is free). If `x*` is free it is the answer. Otherwise the nearest point `p` of
//! `F` lies on the boundary of `F`, and the constraints active at `p` make it one of:
//!
//! - the radial projection of `x*` onto one circle (one circle active);
//! - the clamp of `x*` into the field, or its perpendicular projection onto an edge (one
//!   edge active);
//! - a crossing of two circles, of a circle and an edge line, or a field corner (two
//!   constraints active).
//!
//! A grown polygon ([`InflatedPolygon`](crate::geometry::InflatedPolygon)) adds two
//! kinds of boundary piece: circles round its convex corners, treated as disks above, and
//! its offset sides, which add the projection of `x*` onto each side (clamped to it) and
//! the crossings of each side with the edge lines, the circles and the other sides.
//!
//! The same holds for the nearest point of any one connected component of `F` (a
//! component is closed, and near its nearest point it coincides with `F`), which is what
//! [`nearest_reachable_free_point`] relies on.
//!
//! If `x*` sits exactly at a centre every point of that circle ties; one deterministic
//! point is offered, and if it is blocked, the ends of the free arcs of that circle (which
//! are crossings, at the same distance) are offered by the other candidate kinds.
//!
//! # Cost
//!
//! Candidates are enumerated from the disks near `x*` only, by rings of growing radius
//! `rho`: every candidate within `rho` of `x*` lies on a circle that meets the ball of
//! radius `rho` around `x*` and on a disk whose bounding box meets the bounding box of
//! that ball clipped to the field, so one grid box query per ring finds every disk that
//! can contribute. Candidates are then tried nearest first, and only those within `rho`:
//! the first free one is optimal. When none is free, `rho` grows (the margin beyond the
//! lower bound doubles) and the new disks add their candidates. Each feasibility test is
//! one grid point query. The cost depends on the disks near `x*`, not on the field.
//!
//! # Files
//!
//! - `nearest.rs`: [`nearest_free_point`] and [`nearest_reachable_free_point`], the entry
//!   points, and [`BestPointError`];
//! - `candidates.rs`: the candidates and their enumeration by rings nearest first, and
//!   [`FEASIBILITY_TOLERANCE_M`].

mod candidates;
mod nearest;

pub use candidates::FEASIBILITY_TOLERANCE_M;
pub use nearest::{BestPointError, nearest_free_point, nearest_reachable_free_point};
