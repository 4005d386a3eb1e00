//! The heading figures of a run whose agents have a heading: how far they face from the
//! centre's heading, and the most one of them turned in one step (`summary.json`).

use serde::Serialize;

use super::Run;
use crate::control::kinematics::{car_piece, driving_headings};
use crate::control::vocabulary::Kinematics;
use crate::geometry::wrap_angle_rad;
use crate::world::scenario::Scenario;

/// The heading figures of a run, for runs in which some agent has a heading.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HeadingSummary {
    /// Mean, over steps 1 to the last, of the mean heading error of the live agents with a
    /// heading, radians. An agent's heading error is its heading minus the centre's,
    /// wrapped to `(-pi, pi]`; its magnitude is averaged.
    pub mean_heading_error_rad: f64,
    /// Largest heading error (in magnitude) of a live agent with a heading over the run,
    /// radians.
    pub max_heading_error_rad: f64,
    /// The most one agent turned in one step, radians: the least total turning that
    /// drives its move from the heading it had to the one it ended with (turns at the
    /// vertices and at the end, each segment driven forward or, where the agent may
    /// reverse, backward), the turning the monitor checks against `max_turn_rad`; for a
    /// car, the turning along its arcs.
    pub max_turn_rad: f64,
}

impl Run {
    /// The heading figures of this run of `scenario`, or `None` when no agent has a
    /// heading (a holonomic run).
    ///
    /// ```
    /// use shared::world::scenario::Scenario;
    /// use shared::run::simulate::simulate;
    ///
    /// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/paper-unicycle.toml");
    /// let scenario = Scenario::load(std::path::Path::new(path)).unwrap();
    /// let run = simulate(&scenario).unwrap();
    /// let figures = run.heading_summary(&scenario).unwrap();
    /// // No agent turns more in one step than its limit, 3 rad.
    /// assert!(figures.max_turn_rad <= 3.0 + 1e-9);
    /// assert!(figures.mean_heading_error_rad <= figures.max_heading_error_rad);
    /// ```
    pub fn heading_summary(&self, scenario: &Scenario) -> Option<HeadingSummary> {
        if !scenario.agents.iter().any(|a| a.kinematics.has_heading()) {
            return None;
        }
        let moving = &self.steps[self.steps.len().min(1)..];
        let mut mean_sum = 0.0;
        let mut max_error: f64 = 0.0;
        for step in moving {
            let errors: Vec<f64> = step
                .agents
                .iter()
                .filter(|a| a.alive)
                .filter_map(|a| a.heading_rad)
                .map(|h| wrap_angle_rad(h - step.centre.heading_rad).abs())
                .collect();
            if !errors.is_empty() {
                mean_sum += errors.iter().sum::<f64>() / errors.len() as f64;
            }
            max_error = errors.iter().copied().fold(max_error, f64::max);
        }
        let mut max_turn: f64 = 0.0;
        for pair in self.steps.windows(2) {
            for ((before, after), spec) in pair[0]
                .agents
                .iter()
                .zip(&pair[1].agents)
                .zip(&scenario.agents)
            {
                let (Some(from_rad), Some(to_rad)) = (before.heading_rad, after.heading_rad) else {
                    continue;
                };
                let turning_rad = match spec.kinematics {
                    Kinematics::Unicycle { reverse, .. } => {
                        driving_headings(from_rad, &after.waypoints, Some(to_rad), reverse).1
                    }
                    // A car turns along its arcs: each chord's arc, read back.
                    Kinematics::Car { .. } => {
                        let mut heading_rad = from_rad;
                        let mut turned_rad = 0.0;
                        for w in after.waypoints.windows(2) {
                            let piece = car_piece(heading_rad, &w[0], &w[1]);
                            heading_rad += piece.turn_rad;
                            turned_rad += piece.turn_rad.abs();
                        }
                        turned_rad
                    }
                    Kinematics::Holonomic => continue,
                };
                max_turn = max_turn.max(turning_rad);
            }
        }
        Some(HeadingSummary {
            mean_heading_error_rad: if moving.is_empty() {
                0.0
            } else {
                mean_sum / moving.len() as f64
            },
            max_heading_error_rad: max_error,
            max_turn_rad: max_turn,
        })
    }
}
