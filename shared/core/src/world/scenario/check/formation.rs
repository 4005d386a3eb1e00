//! The formation and its controller checked: every slot with its agent's radius, top
//! speed and sensing, and the controller with its `[cbf]` settings.

use super::{Checker, Checks, num};
use crate::control::formation::Slot;
use crate::control::tracking::{DEFAULT_HORIZON_STEPS, MAX_HORIZON_STEPS};
use crate::control::vocabulary::{
    AgentSpec, ControllerKind, ControllerSpec, Kinematics, MAX_AGENTS, MAX_CBF_SUBSTEPS,
};
use crate::geometry::{Field, Pose};
use crate::world::scenario::ScenarioError;
use crate::world::scenario::file::{CbfFile, FormationFile, OrcaFile};

impl Checker<'_> {
    pub(super) fn controller(
        &self,
        kind: ControllerKind,
        raw: Option<&CbfFile>,
        orca: Option<&OrcaFile>,
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
            if let Some(n) = c.substeps {
                if !(1..=MAX_CBF_SUBSTEPS).contains(&n) {
                    return Err(self.invalid(
                        "cbf.substeps",
                        format!("must be 1 to {MAX_CBF_SUBSTEPS}, got {n}"),
                    ));
                }
                spec.cbf.substeps = n;
            }
            if let Some(escape) = c.deadlock_escape {
                spec.cbf.deadlock_escape = escape;
            }
        }
        spec.check(agents)
            .map_err(|e| self.invalid("cbf", e.to_string()))?;
        if let Some(o) = orca {
            if let Some(v) = o.time_horizon_steps {
                spec.orca.time_horizon_steps = self.positive("orca.time_horizon_steps", v, 1e3)?;
            }
            match o.max_neighbours {
                Some(n) if n == 0 || n > MAX_AGENTS => {
                    return Err(self.invalid(
                        "orca.max_neighbours",
                        format!("{n}: from 1 to {MAX_AGENTS}"),
                    ));
                }
                Some(n) => spec.orca.max_neighbours = n,
                None => {}
            }
        }
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
        let horizon_steps = match raw.horizon_steps {
            Some(h) if h > MAX_HORIZON_STEPS => {
                return Err(self.invalid(
                    "formation.horizon_steps",
                    format!("{h} steps exceed the largest look-ahead, {MAX_HORIZON_STEPS}"),
                ));
            }
            Some(h) => h,
            None => DEFAULT_HORIZON_STEPS,
        };
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
            let kinematics = self.kinematics(raw, i, max_step_m, radius_m, field)?;
            let heading_offset_rad = match s.heading_deg {
                Some(_) if !kinematics.has_heading() => {
                    return Err(self.invalid(
                        format!("{name}.heading_deg"),
                        "a heading belongs to agents with one (kinematics = \"unicycle\" or \"car\"); this agent is holonomic",
                    ));
                }
                Some(h) => self
                    .angle_deg(&format!("{name}.heading_deg"), h)?
                    .to_radians(),
                None => 0.0,
            };
            agents.push(AgentSpec {
                slot: Slot::new(r_m, theta_deg.to_radians()),
                radius_m,
                max_step_m,
                sensing_radius_m,
                kinematics,
                heading_offset_rad,
                align_heading: raw.align_heading.unwrap_or(false) && kinematics.has_heading(),
                horizon_steps,
            });
        }
        // A formation-wide key of a model no agent has would be silently unused.
        let any = |model: &str| agents.iter().any(|a| a.kinematics.name() == model);
        for (key, given, model) in [
            ("max_turn_rad", raw.max_turn_rad.is_some(), "unicycle"),
            ("turning_radius_m", raw.turning_radius_m.is_some(), "car"),
        ] {
            if given && !any(model) {
                return Err(self.invalid(
                    format!("formation.{key}"),
                    format!("belongs to kinematics = \"{model}\"; no agent here is one"),
                ));
            }
        }
        if !agents.iter().any(|a| a.kinematics.has_heading()) {
            for (key, given) in [
                ("max_turn_rad", raw.max_turn_rad.is_some()),
                ("reverse", raw.reverse.is_some()),
                ("align_heading", raw.align_heading.is_some()),
            ] {
                if given {
                    return Err(self.invalid(
                        format!("formation.{key}"),
                        "belongs to agents with a heading (kinematics = \"unicycle\" or \"car\"); every agent here is holonomic",
                    ));
                }
            }
        }
        // The paper's Assumption 2: the nominal formation is itself collision-free. Each
        // slot placed once; O(n^2) all the same, so a file validated before skips it.
        if self.checks == Checks::Values {
            return Ok(agents);
        }
        let origin = Pose::new(0.0, 0.0, 0.0);
        let placed: Vec<_> = agents
            .iter()
            .map(|a| a.slot.ideal_position(&origin))
            .collect();
        for i in 0..agents.len() {
            for j in 0..i {
                let d = (placed[i] - placed[j]).norm();
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

    /// Slot `i`'s kinematic model: its own keys over the formation's, checked; its top
    /// speed is `max_step_m`, its radius `radius_m`, in `field`.
    fn kinematics(
        &self,
        raw: &FormationFile,
        i: usize,
        max_step_m: Option<f64>,
        radius_m: f64,
        field: &Field,
    ) -> Result<Kinematics, ScenarioError> {
        let slot = &raw.slots[i];
        let (kinematics_field, name) = match (&slot.kinematics, &raw.kinematics) {
            (Some(k), _) => (format!("formation.slots[{i}].kinematics"), k.as_str()),
            (None, Some(k)) => ("formation.kinematics".to_string(), k.as_str()),
            (None, None) => ("formation.kinematics".to_string(), "holonomic"),
        };
        let at_slot = |key: &str, given: bool| given.then(|| format!("formation.slots[{i}].{key}"));
        match name {
            "holonomic" => {
                let stray = at_slot("max_turn_rad", slot.max_turn_rad.is_some())
                    .or_else(|| at_slot("reverse", slot.reverse.is_some()))
                    .or_else(|| at_slot("turning_radius_m", slot.turning_radius_m.is_some()));
                if let Some(key) = stray {
                    return Err(self.invalid(
                        key,
                        format!("belongs to another kinematic model; agent {i} is holonomic"),
                    ));
                }
                Ok(Kinematics::Holonomic)
            }
            "unicycle" => {
                if let Some(key) = at_slot("turning_radius_m", slot.turning_radius_m.is_some()) {
                    return Err(self.invalid(
                        key,
                        "belongs to kinematics = \"car\"; a unicycle turns in place (max_turn_rad)",
                    ));
                }
                if max_step_m.is_none() {
                    return Err(self.invalid(
                        kinematics_field,
                        format!(
                            "a unicycle needs a top speed (formation.max_step_m or formation.slots[{i}].max_step_m): its turning and driving share one step"
                        ),
                    ));
                }
                let (turn_field, max_turn_rad) = match (slot.max_turn_rad, raw.max_turn_rad) {
                    (Some(v), _) => (format!("formation.slots[{i}].max_turn_rad"), v),
                    (None, Some(v)) => ("formation.max_turn_rad".to_string(), v),
                    (None, None) => {
                        let missing = match slot.kinematics {
                            Some(_) => format!("formation.slots[{i}].max_turn_rad"),
                            None => "formation.max_turn_rad".to_string(),
                        };
                        return Err(self.invalid(
                            missing,
                            format!(
                                "a unicycle needs max_turn_rad (formation.max_turn_rad or formation.slots[{i}].max_turn_rad): its largest heading change per step"
                            ),
                        ));
                    }
                };
                let max_turn_rad =
                    self.positive(&turn_field, max_turn_rad, std::f64::consts::TAU)?;
                Ok(Kinematics::Unicycle {
                    max_turn_rad,
                    reverse: slot.reverse.or(raw.reverse).unwrap_or(false),
                })
            }
            "car" => {
                if let Some(key) = at_slot("max_turn_rad", slot.max_turn_rad.is_some()) {
                    return Err(self.invalid(
                        key,
                        "belongs to kinematics = \"unicycle\"; a car cannot turn in place (turning_radius_m)",
                    ));
                }
                if max_step_m.is_none() {
                    return Err(self.invalid(
                        kinematics_field,
                        format!(
                            "a car needs a top speed (formation.max_step_m or formation.slots[{i}].max_step_m): its moves are cut at it"
                        ),
                    ));
                }
                let (radius_field, turning_radius_m) = match (
                    slot.turning_radius_m,
                    raw.turning_radius_m,
                ) {
                    (Some(v), _) => (format!("formation.slots[{i}].turning_radius_m"), v),
                    (None, Some(v)) => ("formation.turning_radius_m".to_string(), v),
                    (None, None) => {
                        return Err(self.invalid(
                                "formation.turning_radius_m",
                                format!(
                                    "a car needs turning_radius_m (formation.turning_radius_m or formation.slots[{i}].turning_radius_m): the tightest it bends"
                                ),
                            ));
                    }
                };
                let turning_radius_m = self.positive(&radius_field, turning_radius_m, f64::MAX)?;
                // Its turning circle, with its body, must fit in the field.
                let across_m = 2.0 * (turning_radius_m + radius_m);
                let room_m = field.width_m.min(field.height_m);
                if across_m > room_m {
                    return Err(self.invalid(
                        radius_field,
                        format!(
                            "a turning circle {} m across (with the body) does not fit in a field {} m across",
                            num(across_m),
                            num(room_m)
                        ),
                    ));
                }
                Ok(Kinematics::Car {
                    turning_radius_m,
                    reverse: slot.reverse.or(raw.reverse).unwrap_or(false),
                })
            }
            other => Err(self.invalid(
                kinematics_field,
                format!("unknown kinematic model {other:?} (holonomic, unicycle, car)"),
            )),
        }
    }
}
