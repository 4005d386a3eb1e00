//! Feasibility: whether the checked parts fit together at the start (the start and goal
//! clear of every obstacle, every agent in the field and clear of the obstacles), as
//! against the field-by-field checks.

use super::Checker;
use crate::control::vocabulary::AgentSpec;
use crate::geometry::{Disk, Field};
use crate::world::scenario::{PathSpec, ScenarioError};

impl Checker<'_> {
    pub(super) fn start_and_goal_clear(
        &self,
        obstacles: &[Disk],
        field: &Field,
        path: &PathSpec,
    ) -> Result<(), ScenarioError> {
        for (name, pose) in [("path.start", &path.start), ("path.goal", &path.goal)] {
            let p = pose.position();
            if field.signed_inset_m(&p) < path.centre_clearance_m {
                return Err(self.invalid(
                    name,
                    format!(
                        "({}, {}) is closer to the field's edge than the centre clearance {} m",
                        p.x, p.y, path.centre_clearance_m
                    ),
                ));
            }
            if let Some((k, o)) = obstacles
                .iter()
                .enumerate()
                .find(|(_, o)| o.signed_distance_m(&p) < path.centre_clearance_m)
            {
                return Err(self.invalid(
                    name,
                    format!(
                        "({}, {}) is within the centre clearance {} m of obstacle {k} at ({}, {}) radius {} m",
                        p.x, p.y, path.centre_clearance_m, o.centre.x, o.centre.y, o.radius_m
                    ),
                ));
            }
        }
        Ok(())
    }

    pub(super) fn formation_fits_at_start(
        &self,
        agents: &[AgentSpec],
        obstacles: &[Disk],
        field: &Field,
        path: &PathSpec,
    ) -> Result<(), ScenarioError> {
        for (i, a) in agents.iter().enumerate() {
            let name = format!("formation.slots[{i}]");
            let p = a.slot.ideal_position(&path.start);
            if field.signed_inset_m(&p) < a.radius_m {
                return Err(self.invalid(
                    name,
                    format!(
                        "at the start pose the agent at ({:.3}, {:.3}) does not fit inside the field",
                        p.x, p.y
                    ),
                ));
            }
            if let Some((k, o)) = obstacles
                .iter()
                .enumerate()
                .find(|(_, o)| o.signed_distance_m(&p) < a.radius_m)
            {
                return Err(self.invalid(
                    name,
                    format!(
                        "at the start pose the agent at ({:.3}, {:.3}) overlaps obstacle {k} at ({}, {})",
                        p.x, p.y, o.centre.x, o.centre.y
                    ),
                ));
            }
        }
        Ok(())
    }
}
