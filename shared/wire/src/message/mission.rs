//! The static scenario, published once for every agent.

use iceoryx2::prelude::*;
use iceoryx2_bb_container::vector::{StaticVec, Vector};
use shared::formation::Slot;
use shared::geometry::{Disk, Field};
use shared::scenario::Scenario;
use shared::vocabulary::{
    AgentSpec, CbfSettings, MAX_AGENTS, MAX_OBSTACLES, PlannerKind, PlannerSpec,
};

use crate::CapacityError;

/// An obstacle on the wire (true radius).
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WireDisk")]
pub struct WireDisk {
    /// Centre x, in metres.
    pub x_m: f64,
    /// Centre y, in metres.
    pub y_m: f64,
    /// Radius, in metres.
    pub radius_m: f64,
}

/// An agent's formation slot and radius on the wire.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WireAgent")]
pub struct WireAgent {
    /// Slot distance from the centre, in metres.
    pub slot_r_m: f64,
    /// Slot angle from the heading, in radians.
    pub slot_theta_rad: f64,
    /// Body radius, in metres.
    pub radius_m: f64,
    /// Top speed, metres per step; infinite for none.
    pub max_step_m: f64,
    /// Sensing radius, in metres; infinite when the agent knows every body.
    pub sensing_radius_m: f64,
}

/// The static scenario, published once (history 1) for every agent.
#[repr(C)]
#[derive(Debug, Default, ZeroCopySend, PlacementDefault)]
#[type_name("formation::Mission")]
pub struct Mission {
    /// Field width, in metres.
    pub field_width_m: f64,
    /// Field height, in metres.
    pub field_height_m: f64,
    /// Every obstacle, true radii.
    pub obstacles: StaticVec<WireDisk, MAX_OBSTACLES>,
    /// Every agent, in agent order.
    pub agents: StaticVec<WireAgent, MAX_AGENTS>,
    /// The controller: a [`PlannerKind`] code.
    pub planner: u32,
    /// Padding, always 0.
    pub reserved: u32,
    /// Barrier-function settings (see [`CbfSettings`]).
    pub cbf_gamma_per_s: f64,
    /// Duration of one barrier-function move, in seconds.
    pub cbf_dt_s: f64,
    /// Gain of the nominal control, in 1/s.
    pub cbf_gain_per_s: f64,
    /// Speed limit, in m/s.
    pub cbf_max_speed_m_per_s: f64,
    /// Sensing radius, in metres.
    pub cbf_sensing_radius_m: f64,
    /// LogSumExp sharpness, in 1/m.
    pub lse_sharpness_per_m: f64,
}

impl Mission {
    /// Fill the mission in place from `scenario`.
    pub fn fill(&mut self, scenario: &Scenario) -> Result<(), CapacityError> {
        let (field, obstacles, agents) = (&scenario.field, &scenario.obstacles, &scenario.agents);
        let p = &scenario.planner;
        self.planner = p.kind.code();
        self.cbf_gamma_per_s = p.cbf.gamma_per_s;
        self.cbf_dt_s = p.cbf.dt_s;
        self.cbf_gain_per_s = p.cbf.gain_per_s;
        self.cbf_max_speed_m_per_s = p.cbf.max_speed_m_per_s;
        self.cbf_sensing_radius_m = p.cbf.sensing_radius_m;
        self.lse_sharpness_per_m = p.lse_sharpness_per_m;
        self.field_width_m = field.width_m;
        self.field_height_m = field.height_m;
        self.obstacles.clear();
        self.agents.clear();
        for o in obstacles {
            self.obstacles
                .push(WireDisk {
                    x_m: o.centre.x,
                    y_m: o.centre.y,
                    radius_m: o.radius_m,
                })
                .map_err(|_| CapacityError::Obstacles(obstacles.len()))?;
        }
        for a in agents {
            self.agents
                .push(WireAgent {
                    slot_r_m: a.slot.r_m,
                    slot_theta_rad: a.slot.theta_rad,
                    radius_m: a.radius_m,
                    max_step_m: a.max_step_m.unwrap_or(f64::INFINITY),
                    sensing_radius_m: a.sensing_radius_m.unwrap_or(f64::INFINITY),
                })
                .map_err(|_| CapacityError::Agents(agents.len()))?;
        }
        Ok(())
    }

    /// The controller and its settings (`None` for an unknown planner code).
    pub fn planner(&self) -> Option<PlannerSpec> {
        Some(PlannerSpec {
            kind: PlannerKind::from_code(self.planner)?,
            cbf: CbfSettings {
                gamma_per_s: self.cbf_gamma_per_s,
                dt_s: self.cbf_dt_s,
                gain_per_s: self.cbf_gain_per_s,
                max_speed_m_per_s: self.cbf_max_speed_m_per_s,
                sensing_radius_m: self.cbf_sensing_radius_m,
            },
            lse_sharpness_per_m: self.lse_sharpness_per_m,
        })
    }

    /// The field.
    pub fn field(&self) -> Field {
        Field::new(self.field_width_m, self.field_height_m)
    }

    /// The obstacles, true radii.
    pub fn obstacles(&self) -> Vec<Disk> {
        self.obstacles
            .iter()
            .map(|o| Disk::new(o.x_m, o.y_m, o.radius_m))
            .collect()
    }

    /// The agents, in agent order.
    pub fn agents(&self) -> Vec<AgentSpec> {
        self.agents
            .iter()
            .map(|a| AgentSpec {
                slot: Slot::new(a.slot_r_m, a.slot_theta_rad),
                radius_m: a.radius_m,
                max_step_m: a.max_step_m.is_finite().then_some(a.max_step_m),
                sensing_radius_m: a.sensing_radius_m.is_finite().then_some(a.sensing_radius_m),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mission_round_trips_the_scenario_exactly() {
        let mut s = Scenario::paper();
        s.agents[1].max_step_m = Some(0.25);
        s.agents[2].sensing_radius_m = Some(3.5);
        let mut m = Mission::default();
        m.fill(&s).unwrap();
        assert_eq!(m.planner(), Some(s.planner));
        assert_eq!(m.field(), s.field);
        assert_eq!(m.obstacles(), s.obstacles);
        assert_eq!(m.agents(), s.agents);
    }
}
