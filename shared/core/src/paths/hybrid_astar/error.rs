//! Why no path was planned.

/// Why [`plan`](super::plan()) found no path.
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
