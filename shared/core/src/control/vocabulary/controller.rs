//! Which controller moves the agents, and its settings.

use serde::{Deserialize, Serialize};

use crate::control::vocabulary::{
    AgentSpec, CbfSettings, CbfSettingsError, DEFAULT_LSE_SHARPNESS_PER_M, Named,
};

/// Which controller moves the agents.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControllerKind {
    /// The paper's method: exact best point, then a shortest collision-free path to it.
    #[default]
    BestPoint,
    /// A control-barrier-function QP with one constraint per neighbour
    /// ([`crate::control::cbf`]): safe by construction, may deadlock.
    Cbf,
    /// The paper's failed zeroing barrier with a LogSumExp-smoothed max: kept to show its
    /// violations (the safety monitor refuses them).
    ZcbfLogsumexp,
    /// The reactive baseline: optimal reciprocal collision avoidance (RVO2) towards the
    /// slot, one step at the top speed ([`crate::control::orca`]).
    Orca,
}

impl ControllerKind {
    /// Every controller, in code order.
    pub const ALL: [ControllerKind; 4] =
        [Self::BestPoint, Self::Cbf, Self::ZcbfLogsumexp, Self::Orca];

    /// The name used in files and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::BestPoint => "best-point",
            Self::Cbf => "cbf",
            Self::ZcbfLogsumexp => "zcbf-logsumexp",
            Self::Orca => "orca",
        }
    }

    /// The controller called `name`, if any.
    ///
    /// ```
    /// use shared::control::vocabulary::ControllerKind;
    /// assert_eq!(ControllerKind::from_name("cbf"), Some(ControllerKind::Cbf));
    /// assert_eq!(ControllerKind::from_name(ControllerKind::ZcbfLogsumexp.name()), Some(ControllerKind::ZcbfLogsumexp));
    /// assert_eq!(ControllerKind::from_name("best_point"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        <Self as Named>::from_name(name)
    }

    /// The wire code.
    pub fn code(&self) -> u32 {
        *self as u32
    }

    /// The controller with wire code `code`, if any.
    pub fn from_code(code: u32) -> Option<Self> {
        Self::ALL.get(code as usize).copied()
    }
}

impl Named for ControllerKind {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "controller";

    fn name(&self) -> &'static str {
        ControllerKind::name(self)
    }
}

/// The controller and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllerSpec {
    /// Which controller.
    pub kind: ControllerKind,
    /// Settings of the barrier-function controllers (unused by the best-point controller).
    pub cbf: CbfSettings,
    /// Sharpness of the LogSumExp smooth max, in 1/m (`zcbf-logsumexp` only).
    pub lse_sharpness_per_m: f64,
    /// Settings of ORCA in its own model (`orca` in simultaneous turns).
    pub orca: OrcaSettings,
}

/// RVO2's settings of ORCA in its own model (`[orca]` in a scenario; used by the `orca`
/// controller in simultaneous turns).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrcaSettings {
    /// How far ahead, in steps, velocities are kept from leading into a body (RVO2's
    /// `timeHorizon`, and `timeHorizonObst` for the obstacles, which ORCA sees as agents
    /// standing still).
    pub time_horizon_steps: f64,
    /// The most neighbouring agents weighed, nearest first (RVO2's `maxNeighbors`).
    pub max_neighbours: usize,
}

impl Default for OrcaSettings {
    /// 5 steps and 20 neighbours: measured on the paper, dense, narrow and large
    /// scenarios capped at twice the centre's step against the reference RVO2 (time
    /// horizon 1.0 s, obstacle horizon 0.5 s, 20 neighbours, 0.1 s a step), 5 steps came
    /// within 25 % of its mean deviation on all four; 10, RVO2's own, was 46 % worse on
    /// large, where our obstacles are disks seen as static agents, not polygons.
    fn default() -> Self {
        Self {
            time_horizon_steps: 5.0,
            max_neighbours: 20,
        }
    }
}

impl Default for ControllerSpec {
    fn default() -> Self {
        Self {
            kind: ControllerKind::BestPoint,
            cbf: CbfSettings::default(),
            lse_sharpness_per_m: DEFAULT_LSE_SHARPNESS_PER_M,
            orca: OrcaSettings::default(),
        }
    }
}

impl ControllerSpec {
    /// Check the barrier settings for every agent (unused settings are still checked, so
    /// switching controllers on the command line cannot meet an invalid file).
    pub fn check(&self, agents: &[AgentSpec]) -> Result<(), CbfSettingsError> {
        for a in agents {
            self.cbf.validate_for_agent(a.radius_m)?;
        }
        Ok(())
    }
}
