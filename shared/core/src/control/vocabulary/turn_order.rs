//! In which order the agents of a step take their turns.

use serde::{Deserialize, Serialize};

use super::{AgentSpec, Kinematics, Named};

/// In which order the agents of a step take their turns (`[turns] order` in a scenario).
///
/// Safety does not depend on it (every move is checked against the bodies standing still
/// at that moment), but under a top speed the deviation does: an agent whose way to its
/// slot is blocked by a mate that has not moved yet this step detours or waits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TurnOrder {
    /// In agent order, the order of the formation's slots (the paper's turns; the
    /// default without a top speed, see [`TurnOrder::default_for`]).
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

    /// The order a scenario's agents take their turns in when the file names none:
    /// [`TurnOrder::FrontFirst`] when every agent has a top speed and `horizon_steps > 0`
    /// (the default; the setting counts, whatever the controller) and none is a car, else
    /// [`TurnOrder::Agent`], the paper's order. An agent that cannot keep up with its slot
    /// then finds the way ahead cleared by the mates in front; without a top speed every
    /// agent reaches its best point each step, and with `horizon_steps = 0` an agent
    /// chases its slot as it did before the look-ahead, in the order it did. Cars keep
    /// agent order: on `paper-car` with seeds 1 to 9 the two orders come close (mean
    /// deviation 0.112 m in agent order, 0.099 m front to back, each lower on some fields,
    /// and the figures move by as much with any change to the car's search;
    /// `docs/measurements.md`).
    ///
    /// ```
    /// use shared::control::formation::Slot;
    /// use shared::control::vocabulary::{AgentSpec, Kinematics, TurnOrder};
    /// let paper = AgentSpec::new(Slot::new(1.0, 0.0), 0.25);
    /// let capped = AgentSpec { max_step_m: Some(0.5), horizon_steps: 10, ..paper };
    /// let chasing = AgentSpec { horizon_steps: 0, ..capped };
    /// let car = AgentSpec {
    ///     kinematics: Kinematics::Car { turning_radius_m: 0.5, reverse: true },
    ///     ..capped
    /// };
    /// assert_eq!(TurnOrder::default_for(&[capped, capped]), TurnOrder::FrontFirst);
    /// assert_eq!(TurnOrder::default_for(&[capped, chasing]), TurnOrder::Agent);
    /// assert_eq!(TurnOrder::default_for(&[capped, paper]), TurnOrder::Agent);
    /// assert_eq!(TurnOrder::default_for(&[capped, car]), TurnOrder::Agent);
    /// ```
    pub fn default_for(agents: &[AgentSpec]) -> Self {
        let front_first = |a: &AgentSpec| {
            a.max_step_m.is_some()
                && a.horizon_steps > 0
                && !matches!(a.kinematics, Kinematics::Car { .. })
        };
        if !agents.is_empty() && agents.iter().all(front_first) {
            Self::FrontFirst
        } else {
            Self::Agent
        }
    }

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
    /// use shared::control::vocabulary::TurnOrder;
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
