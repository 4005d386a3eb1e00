//! Which controller moves the agents, and its settings.

use serde::{Deserialize, Serialize};

use crate::vocabulary::{
    AgentSpec, CbfSettings, CbfSettingsError, DEFAULT_LSE_SHARPNESS_PER_M, Named,
};

/// Which controller moves the agents.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlannerKind {
    /// The paper's method: exact best point, then a shortest collision-free path to it.
    #[default]
    BestPoint,
    /// A control-barrier-function QP with one constraint per neighbour
    /// ([`crate::cbf`]): safe by construction, may deadlock.
    Cbf,
    /// The paper's failed zeroing barrier with a LogSumExp-smoothed max: kept to show its
    /// violations (the safety monitor refuses them).
    ZcbfLogsumexp,
    /// The reactive baseline: optimal reciprocal collision avoidance (RVO2) towards the
    /// slot, one step at the top speed ([`crate::orca`]).
    Orca,
}

impl PlannerKind {
    /// Every planner, in code order.
    pub const ALL: [PlannerKind; 4] = [Self::BestPoint, Self::Cbf, Self::ZcbfLogsumexp, Self::Orca];

    /// The name used in files and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::BestPoint => "best-point",
            Self::Cbf => "cbf",
            Self::ZcbfLogsumexp => "zcbf-logsumexp",
            Self::Orca => "orca",
        }
    }

    /// The planner called `name`, if any.
    ///
    /// ```
    /// use shared::vocabulary::PlannerKind;
    /// assert_eq!(PlannerKind::from_name("cbf"), Some(PlannerKind::Cbf));
    /// assert_eq!(PlannerKind::from_name(PlannerKind::ZcbfLogsumexp.name()), Some(PlannerKind::ZcbfLogsumexp));
    /// assert_eq!(PlannerKind::from_name("best_point"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        <Self as Named>::from_name(name)
    }

    /// The wire code.
    pub fn code(&self) -> u32 {
        *self as u32
    }

    /// The planner with wire code `code`, if any.
    pub fn from_code(code: u32) -> Option<Self> {
        Self::ALL.get(code as usize).copied()
    }
}

impl Named for PlannerKind {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "planner";

    fn name(&self) -> &'static str {
        PlannerKind::name(self)
    }
}

/// The controller and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlannerSpec {
    /// Which controller.
    pub kind: PlannerKind,
    /// Settings of the barrier-function planners (unused by the best-point planner).
    pub cbf: CbfSettings,
    /// Sharpness of the LogSumExp smooth max, in 1/m (`zcbf-logsumexp` only).
    pub lse_sharpness_per_m: f64,
}

impl Default for PlannerSpec {
    fn default() -> Self {
        Self {
            kind: PlannerKind::BestPoint,
            cbf: CbfSettings::default(),
            lse_sharpness_per_m: DEFAULT_LSE_SHARPNESS_PER_M,
        }
    }
}

impl PlannerSpec {
    /// Check the barrier settings for every agent (unused settings are still checked, so
    /// switching planners on the command line cannot meet an invalid file).
    pub fn check(&self, agents: &[AgentSpec]) -> Result<(), CbfSettingsError> {
        for a in agents {
            self.cbf.validate_for_agent(a.radius_m)?;
        }
        Ok(())
    }
}
