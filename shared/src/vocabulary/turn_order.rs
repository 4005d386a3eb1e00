//! In which order the agents of a step take their turns.

use serde::{Deserialize, Serialize};

use super::Named;

/// In which order the agents of a step take their turns (`[turns] order` in a scenario).
///
/// Safety does not depend on it (every move is checked against the bodies standing still
/// at that moment), but under a top speed the deviation does: an agent whose way to its
/// slot is blocked by a mate that has not moved yet this step detours or waits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TurnOrder {
    /// In agent order, the order of the formation's slots (the paper's turns).
    #[default]
    Agent,
    /// The agent furthest ahead first: by where each stands along the formation centre's
    /// heading, from front to back (agents level with each other in agent order). The
    /// agents behind then find the way cleared by those in front, which moved already.
    /// In parallel turns the groups are formed in this order.
    FrontFirst,
}

impl TurnOrder {
    /// Every order.
    pub const ALL: [TurnOrder; 2] = [Self::Agent, Self::FrontFirst];

    /// The name used in files and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Agent => "agent",
            Self::FrontFirst => "front-first",
        }
    }

    /// The order called `name`, if any.
    ///
    /// ```
    /// use shared::vocabulary::TurnOrder;
    /// assert_eq!(TurnOrder::from_name("front-first"), Some(TurnOrder::FrontFirst));
    /// assert_eq!(TurnOrder::from_name("front"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        <Self as Named>::from_name(name)
    }
}

impl Named for TurnOrder {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "turn order";

    fn name(&self) -> &'static str {
        TurnOrder::name(self)
    }
}
