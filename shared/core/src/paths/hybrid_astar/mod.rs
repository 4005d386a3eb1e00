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
//!   Dijkstra over a grid of the field grown from the goal,
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
//!
//! # Files
//!
//! - `plan.rs`: [`plan()`] and [`plan_with_stats`], the entry points;
//! - `replan.rs`: [`Replanner`], which plans to one goal from start after start as
//!   obstacles are added, reusing the heuristic, and [`first_blocked_pose`];
//! - `settings.rs` and `error.rs`: [`HybridAStarSettings`] and [`PlanError`];
//! - `primitive.rs`: motion primitives, pieces of constant curvature and their geometry;
//! - `collision.rs`: the exact collision checks;
//! - `heuristic.rs`: the holonomic-with-obstacles lower bound and the reachable cells,
//!   updatable in place when obstacles are added;
//! - `grid.rs`: the square grids of the heuristic, their 8-neighbours and step costs;
//! - `dijkstra.rs`: the lazy grid Dijkstra under the heuristic, repairable in place when
//!   cells become blocked;
//! - `analytic.rs`: the analytic expansion (Reeds-Shepp or Dubins shot to the goal);
//! - `search.rs`: the search itself, and [`PlanStats`];
//! - `resample.rs`: [`resample()`] and [`path_length_m`].

mod analytic;
mod collision;
mod dijkstra;
mod error;
mod grid;
mod heuristic;
mod plan;
mod primitive;
mod replan;
mod resample;
mod search;
mod settings;

pub use error::PlanError;
pub use plan::{plan, plan_among_polygons, plan_with_stats};
pub use replan::{Replanner, first_blocked_pose};
pub use resample::{path_length_m, resample};
pub use search::PlanStats;
pub use settings::HybridAStarSettings;
