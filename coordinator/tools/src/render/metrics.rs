//! Per-step figures derived from a run's recorded positions: the formation's mean
//! deviation, and the smallest agent-agent and agent-obstacle clearances (distance minus
//! both radii), computed afresh from positions and the scenario's radii.

use std::ops::ControlFlow;

use shared::geometry::{Disk, DiskGrid, Point};

use super::data::RunData;

/// The derived figures of one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepMetrics {
    /// The step.
    pub step: usize,
    /// Mean deviation of the live agents, in metres (`None` when none is alive).
    pub mean_deviation_m: Option<f64>,
    /// Smallest clearance between two agents (dead ones included: they stay as
    /// obstacles), in metres (`None` with fewer than two agents).
    pub agent_clearance_m: Option<f64>,
    /// Smallest clearance between an agent and an obstacle, in metres (`None` without
    /// obstacles).
    pub obstacle_clearance_m: Option<f64>,
}

/// The derived figures of every step of `data`.
pub fn per_step(data: &RunData) -> Vec<StepMetrics> {
    let radii: Vec<f64> = data.scenario.agents.iter().map(|a| a.radius_m).collect();
    let obstacles = DiskGrid::new(data.scenario.obstacles.clone());
    let diagonal = data
        .scenario
        .field
        .width_m
        .hypot(data.scenario.field.height_m);
    data.steps
        .iter()
        .map(|s| {
            let live: Vec<f64> = s
                .agents
                .iter()
                .filter(|a| a.alive)
                .map(|a| a.deviation_m)
                .collect();
            let mean_deviation_m =
                (!live.is_empty()).then(|| live.iter().sum::<f64>() / live.len() as f64);
            let mut agent_clearance_m: Option<f64> = None;
            for (i, a) in s.agents.iter().enumerate() {
                for (j, b) in s.agents.iter().enumerate().skip(i + 1) {
                    let c = (a.position - b.position).norm() - radii[i] - radii[j];
                    agent_clearance_m = Some(agent_clearance_m.map_or(c, |m| m.min(c)));
                }
            }
            let obstacle_clearance_m = s
                .agents
                .iter()
                .zip(&radii)
                .filter_map(|(a, &r)| {
                    nearest_obstacle_clearance(&obstacles, &a.position, r, diagonal)
                })
                .reduce(f64::min);
            StepMetrics {
                step: s.step,
                mean_deviation_m,
                agent_clearance_m,
                obstacle_clearance_m,
            }
        })
        .collect()
}

/// Exact clearance from a disk of radius `r` at `p` to the nearest obstacle: search a
/// growing box until the best found cannot be beaten by a disk outside it.
fn nearest_obstacle_clearance(grid: &DiskGrid, p: &Point, r: f64, diagonal: f64) -> Option<f64> {
    if grid.disks().is_empty() {
        return None;
    }
    let max_r = grid.max_radius_m();
    let mut reach = 2.0 * (max_r + r) + 1.0;
    loop {
        let mut best = f64::INFINITY;
        let _ = grid.visit_near(p, reach, |_, o: &Disk| {
            best = best.min((p - o.centre).norm() - o.radius_m - r);
            ControlFlow::<()>::Continue(())
        });
        // A disk not visited has its centre farther than `reach` from `p`.
        if best <= reach - max_r - r || reach > 2.0 * diagonal + max_r {
            return best.is_finite().then_some(best);
        }
        reach *= 2.0;
    }
}

/// The smallest value of `f` over `metrics` and its step.
pub fn lowest(
    metrics: &[StepMetrics],
    f: impl Fn(&StepMetrics) -> Option<f64>,
) -> Option<(usize, f64)> {
    metrics
        .iter()
        .filter_map(|m| f(m).map(|v| (m.step, v)))
        .reduce(|a, b| if b.1 < a.1 { b } else { a })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_obstacle_is_exact_far_away() {
        let grid = DiskGrid::new(vec![Disk::new(1.0, 1.0, 0.5), Disk::new(90.0, 90.0, 2.0)]);
        let c = nearest_obstacle_clearance(&grid, &Point::new(80.0, 80.0), 0.3, 200.0);
        let want = (10.0f64 * 10.0 * 2.0).sqrt() - 2.0 - 0.3;
        assert!((c.unwrap_or(f64::NAN) - want).abs() < 1e-12);
        let empty = DiskGrid::new(Vec::new());
        assert_eq!(
            nearest_obstacle_clearance(&empty, &Point::new(0.0, 0.0), 0.3, 10.0),
            None
        );
    }
}
