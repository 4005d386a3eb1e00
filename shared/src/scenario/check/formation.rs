//! The formation and its controller checked: every slot with its agent's radius, top
//! speed and sensing, and the controller with its `[cbf]` settings.

use super::{Checker, num};
use crate::formation::Slot;
use crate::geometry::{Field, Pose};
use crate::scenario::ScenarioError;
use crate::scenario::file::{CbfFile, FormationFile};
use crate::vocabulary::{AgentSpec, ControllerKind, ControllerSpec, MAX_AGENTS};

impl Checker<'_> {
    pub(super) fn controller(
        &self,
        kind: ControllerKind,
        raw: Option<&CbfFile>,
        agents: &[AgentSpec],
        side_m: f64,
    ) -> Result<ControllerSpec, ScenarioError> {
        let mut spec = ControllerSpec {
            kind,
            ..ControllerSpec::default()
        };
        if let Some(c) = raw {
            let set = |name: &str, v: Option<f64>, slot: &mut f64| -> Result<(), ScenarioError> {
                if let Some(v) = v {
                    *slot = self.positive(&format!("cbf.{name}"), v, side_m.max(1e3))?;
                }
                Ok(())
            };
            set("gamma_per_s", c.gamma_per_s, &mut spec.cbf.gamma_per_s)?;
            set("dt_s", c.dt_s, &mut spec.cbf.dt_s)?;
            set("gain_per_s", c.gain_per_s, &mut spec.cbf.gain_per_s)?;
            set(
                "max_speed_m_per_s",
                c.max_speed_m_per_s,
                &mut spec.cbf.max_speed_m_per_s,
            )?;
            set(
                "sensing_radius_m",
                c.sensing_radius_m,
                &mut spec.cbf.sensing_radius_m,
            )?;
            set(
                "lse_sharpness_per_m",
                c.lse_sharpness_per_m,
                &mut spec.lse_sharpness_per_m,
            )?;
        }
        spec.check(agents)
            .map_err(|e| self.invalid("cbf", e.to_string()))?;
        Ok(spec)
    }

    pub(super) fn agents(
        &self,
        raw: &FormationFile,
        field: &Field,
    ) -> Result<Vec<AgentSpec>, ScenarioError> {
        let hold_m = 0.5 * field.width_m.min(field.height_m);
        let default_radius_m =
            self.positive("formation.agent_radius_m", raw.agent_radius_m, hold_m)?;
        if raw.slots.is_empty() {
            return Err(self.invalid("formation.slots", "the formation has no agents"));
        }
        if raw.slots.len() > MAX_AGENTS {
            return Err(self.invalid(
                "formation.slots",
                format!(
                    "{} agents exceed the capacity of {MAX_AGENTS}",
                    raw.slots.len()
                ),
            ));
        }
        let diagonal_m = field.width_m.hypot(field.height_m);
        let default_max_step_m = raw
            .max_step_m
            .map(|v| self.positive("formation.max_step_m", v, diagonal_m))
            .transpose()?;
        let sensing_radius_m = raw
            .sensing_radius_m
            .map(|v| self.positive("formation.sensing_radius_m", v, diagonal_m))
            .transpose()?;
        let mut agents = Vec::with_capacity(raw.slots.len());
        for (i, s) in raw.slots.iter().enumerate() {
            let name = format!("formation.slots[{i}]");
            let r_m = self.non_negative(
                &format!("{name}.r_m"),
                s.r_m,
                field.width_m.hypot(field.height_m),
            )?;
            let theta_deg = self.angle_deg(&format!("{name}.theta_deg"), s.theta_deg)?;
            let radius_m = match s.radius_m {
                Some(r) => self.positive(&format!("{name}.radius_m"), r, hold_m)?,
                None => default_radius_m,
            };
            let max_step_m = match s.max_step_m {
                Some(v) => Some(self.positive(&format!("{name}.max_step_m"), v, diagonal_m)?),
                None => default_max_step_m,
            };
            // A move must never reach a body the agent cannot see: every point of a move
            // lies within max_step_m of the start, so an unseen disk (farther than the
            // sensing radius from the centre) stays clear iff the sensing radius covers
            // the move plus the agent's own radius.
            if let Some(sensing_m) = sensing_radius_m {
                let Some(step_m) = max_step_m else {
                    return Err(self.invalid(
                        "formation.sensing_radius_m",
                        format!(
                            "limited sensing needs a top speed (formation.max_step_m or {name}.max_step_m): without one a move could reach a body the agent cannot see"
                        ),
                    ));
                };
                if sensing_m < step_m + radius_m {
                    return Err(self.invalid(
                        "formation.sensing_radius_m",
                        format!(
                            "{} m does not cover the move of agent {i} plus its radius ({} + {} m): a move could reach a body it cannot see",
                            num(sensing_m),
                            num(step_m),
                            num(radius_m)
                        ),
                    ));
                }
            }
            agents.push(AgentSpec {
                slot: Slot::new(r_m, theta_deg.to_radians()),
                radius_m,
                max_step_m,
                sensing_radius_m,
            });
        }
        // The paper's Assumption 2: the nominal formation is itself collision-free.
        let origin = Pose::new(0.0, 0.0, 0.0);
        for i in 0..agents.len() {
            for j in 0..i {
                let d = (agents[i].slot.ideal_position(&origin)
                    - agents[j].slot.ideal_position(&origin))
                .norm();
                let need = agents[i].radius_m + agents[j].radius_m;
                if d < need {
                    return Err(self.invalid(
                        format!("formation.slots[{i}]"),
                        format!(
                            "slot is {d:.4} m from slot {j}, closer than their radii sum {need:.4} m (Assumption 2)"
                        ),
                    ));
                }
            }
        }
        Ok(agents)
    }
}
