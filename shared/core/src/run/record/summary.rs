//! The figures of a run: the `summary.json` keys that do not depend on timing.

use serde::Serialize;

use super::{Fault, Run, Step};
use crate::control::safety::SAFETY_TOLERANCE_M;

/// The figures of a run (the `summary.json` keys that do not depend on timing).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Number of agents.
    pub agents: usize,
    /// Number of steps recorded after step 0.
    pub steps: usize,
    /// Whether the run went through the whole centre path.
    pub completed: bool,
    /// Number of (step, agent) records in which the agent overlaps another body (an
    /// obstacle or an agent) at the end of the step, plus the number of times a moving
    /// obstacle's motion came within an agent's reach: 0 in a safe run.
    pub collisions: usize,
    /// Smallest clearance between two bodies over the run, in metres.
    pub min_clearance_m: f64,
    /// Mean of the per-step mean deviation of the live agents, in metres.
    pub mean_deviation_m: f64,
    /// Largest deviation of a live agent over the run, in metres.
    pub max_deviation_m: f64,
    /// Mean deviation at the last step, in metres.
    pub final_mean_deviation_m: f64,
    /// The longest single move of an agent in one step over the run, in metres.
    pub max_move_m: f64,
    /// Mean number of turn groups per step (steps 1 to the last): the number of live
    /// agents in sequential mode, fewer with parallel turns.
    pub mean_groups_per_step: f64,
    /// Every fault.
    pub faults: Vec<Fault>,
    /// Every replanning of the centre's path (a changing world), found or not.
    pub replans: Vec<ReplanNote>,
    /// Every step the centre held its pose, and why.
    pub waits: Vec<WaitNote>,
    /// For each `[[obstacles.unknown]]` obstacle, the step it became known (`null`: never).
    pub unknown_found_at_step: Vec<Option<usize>>,
    /// Whether the run ended because the centre found no way through for too long.
    pub gave_up: bool,
}

/// One replanning, as `summary.json` lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReplanNote {
    /// The step at whose start it was planned.
    pub step: usize,
    /// `found-obstacle` or `moving-obstacle`.
    pub reason: &'static str,
    /// Wall time of the planning, in milliseconds.
    pub planning_ms: f64,
    /// Whether a path was found and taken (false: the centre waited).
    pub found: bool,
}

/// One step the centre held, as `summary.json` lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WaitNote {
    /// The step.
    pub step: usize,
    /// `lag` (an agent too far behind) or `blocked` (no way through yet).
    pub reason: &'static str,
}

impl Run {
    /// The run's figures.
    pub fn summary(&self) -> Summary {
        let moving = &self.steps[self.steps.len().min(1)..];
        let mean_deviation_m = if moving.is_empty() {
            0.0
        } else {
            moving.iter().map(Step::mean_deviation_m).sum::<f64>() / moving.len() as f64
        };
        let collisions = self
            .steps
            .iter()
            .map(|s| {
                s.agents
                    .iter()
                    .filter(|a| a.clearance_m < -SAFETY_TOLERANCE_M)
                    .count()
                    + s.struck.len()
            })
            .sum();
        Summary {
            scenario: self.scenario.clone(),
            agents: self.steps.first().map_or(0, |s| s.agents.len()),
            steps: self.steps.len().saturating_sub(1),
            completed: self.completed,
            collisions,
            min_clearance_m: self
                .steps
                .iter()
                .map(Step::min_clearance_m)
                .fold(f64::INFINITY, f64::min),
            mean_deviation_m,
            max_deviation_m: self
                .steps
                .iter()
                .flat_map(|s| s.agents.iter().filter(|a| a.alive).map(|a| a.deviation_m))
                .fold(0.0, f64::max),
            final_mean_deviation_m: self.steps.last().map_or(0.0, Step::mean_deviation_m),
            max_move_m: self.steps.iter().map(Step::max_move_m).fold(0.0, f64::max),
            mean_groups_per_step: if moving.is_empty() {
                0.0
            } else {
                moving.iter().map(|s| s.groups as f64).sum::<f64>() / moving.len() as f64
            },
            faults: self.faults.clone(),
            replans: self
                .course
                .replans
                .iter()
                .map(|r| ReplanNote {
                    step: r.step,
                    reason: r.reason.name(),
                    planning_ms: r.planning_ms,
                    found: r.found,
                })
                .collect(),
            waits: self
                .course
                .waits
                .iter()
                .map(|w| WaitNote {
                    step: w.step,
                    reason: w.reason.name(),
                })
                .collect(),
            unknown_found_at_step: self.course.found_at.clone(),
            gave_up: self.course.gave_up,
        }
    }
}
