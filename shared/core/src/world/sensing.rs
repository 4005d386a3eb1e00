//! Limited sensing: which agents an agent senses, found with a spatial index so the
//! world sent to an agent grows with what it can see, not with the formation.

use std::ops::ControlFlow;

use crate::control::vocabulary::{AgentSpec, Body};
use crate::geometry::DiskGrid;

/// The agents' bodies at one moment, indexed for sensing queries.
#[derive(Clone, Debug)]
pub struct SensedAgents {
    grid: DiskGrid,
}

impl SensedAgents {
    /// Index `bodies` (every agent, in agent order).
    pub fn new(bodies: &[Body]) -> Self {
        Self {
            grid: crate::control::safety::bodies_grid(bodies),
        }
    }

    /// The grid over the bodies (a disk each, in agent order).
    pub fn grid(&self) -> &DiskGrid {
        &self.grid
    }

    /// The agents agent `agent` (of spec `spec`) senses, itself included, in increasing
    /// order: every agent without a sensing radius. The test is
    /// [`AgentSpec::senses`], the one the controller applies, so the controller finds in this
    /// list exactly the bodies it would pick from all of them.
    ///
    /// ```
    /// use shared::control::formation::Slot;
    /// use shared::geometry::Point;
    /// use shared::world::sensing::SensedAgents;
    /// use shared::control::vocabulary::{AgentSpec, Body};
    /// let mut spec = AgentSpec::new(Slot::new(0.0, 0.0), 0.5);
    /// spec.sensing_radius_m = Some(3.0);
    /// let at = |x: f64| Body { position: Point::new(x, 0.0), radius_m: 0.5 };
    /// let bodies = [at(0.0), at(3.4), at(3.6), at(-1.0)];
    /// // Agent 2's disk starts 3.1 m away: beyond 3 m.
    /// assert_eq!(SensedAgents::new(&bodies).sensed_by(0, &spec), vec![0, 1, 3]);
    /// ```
    pub fn sensed_by(&self, agent: usize, spec: &AgentSpec) -> Vec<usize> {
        let disks = self.grid.disks();
        let Some(sensing_m) = spec.sensing_radius_m else {
            return (0..disks.len()).collect();
        };
        let Some(me) = disks.get(agent).map(|d| d.centre) else {
            return Vec::new();
        };
        let mut seen = vec![agent];
        let _ = self
            .grid
            .visit_near(&me, sensing_m + self.grid.max_radius_m(), |j, d| {
                if j != agent && spec.senses(&me, &d.centre, d.radius_m) {
                    seen.push(j);
                }
                ControlFlow::<()>::Continue(())
            });
        seen.sort_unstable();
        seen
    }
}
