//! How the agents of a step take their turns: one at a time, in groups that cannot
//! meet, or all at once (ORCA's own model).

use serde::{Deserialize, Serialize};

use super::Named;

/// How the agents of a step take their turns (`[turns] mode` in a scenario).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TurnMode {
    /// One agent moves at a time, in the turn order ([`super::TurnOrder`]), while every
    /// other stands still (the paper's Assumption 6).
    #[default]
    Sequential,
    /// Agents that cannot meet within the step move at once: each step the live agents
    /// are split into groups ([`crate::world::groups::turn_groups`]); a group's agents plan
    /// against the same snapshot and the groups follow one another. Needs a top speed.
    Parallel,
    /// Every live agent moves at once, knowing how each body moved over the last step:
    /// ORCA's own model (reciprocal avoidance, RVO2), for the `orca` controller only. No
    /// group is kept apart, so the safety monitor checks every move against every mate's
    /// whole move and refuses those that would meet. Needs a top speed.
    Simultaneous,
}

impl TurnMode {
    /// Every mode.
    pub const ALL: [TurnMode; 3] = [Self::Sequential, Self::Parallel, Self::Simultaneous];

    /// The name used in files and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Sequential => "sequential",
            Self::Parallel => "parallel",
            Self::Simultaneous => "simultaneous",
        }
    }

    /// The mode called `name`, if any.
    ///
    /// ```
    /// use shared::control::vocabulary::TurnMode;
    /// assert_eq!(TurnMode::from_name("parallel"), Some(TurnMode::Parallel));
    /// assert_eq!(TurnMode::from_name("Parallel"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        <Self as Named>::from_name(name)
    }
}

impl Named for TurnMode {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "turn mode";

    fn name(&self) -> &'static str {
        TurnMode::name(self)
    }
}
