//! The planner's settings, with defaults derived from the turning radius and the clearance.

use std::f64::consts::{SQRT_2, TAU};

use super::error::PlanError;

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
