//! Faults: what went wrong with an agent, or happened to it, and when. One enum names
//! every kind, so the run, the reference simulation and every reader spell them alike.

use serde::{Deserialize, Serialize};

use crate::control::vocabulary::Named;

/// What went wrong with an agent, and when.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fault {
    /// The agent.
    pub agent: usize,
    /// The step it happened in.
    pub step: usize,
    /// What happened.
    pub kind: FaultKind,
    /// Details for people.
    pub detail: String,
    /// For a detected death: milliseconds from the moment the coordinator started waiting
    /// on the agent (its turn, or the step's liveness check) to the detection.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub detection_ms: Option<f64>,
}

/// The kind of a fault, as `summary.json` names it ([`FaultKind::name`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FaultKind {
    /// The agent's move failed the safety checks: it stayed where it was.
    #[serde(rename = "rejected")]
    Rejected,
    /// No move within the turn deadline while the process was alive.
    #[serde(rename = "missed")]
    Missed,
    /// Too many missed turns: the process is killed, a [`FaultKind::Dead`] follows.
    #[serde(rename = "hung")]
    Hung,
    /// Fault injection sent the agent SIGKILL during its turn.
    #[serde(rename = "killed")]
    Killed,
    /// The agent's process was found gone: it stays as a static obstacle.
    #[serde(rename = "dead")]
    Dead,
    /// A replacement process took the dead agent's place.
    #[serde(rename = "respawned")]
    Respawned,
    /// The replacement process did not come up: the agent stays dead.
    #[serde(rename = "respawn_failed")]
    RespawnFailed,
    /// The agent's process never completed its ready handshake.
    #[serde(rename = "failed-to-start")]
    FailedToStart,
    /// A sample from the agent failed the checks before anything used it.
    #[serde(rename = "malformed")]
    Malformed,
    /// States that answer no turn (no valid token, or between turns): ignored.
    #[serde(rename = "unsolicited")]
    Unsolicited,
    /// A process published on another agent's channel, or attached to its services.
    #[serde(rename = "impersonation")]
    Impersonation,
    /// A moving obstacle's motion came within the agent's reach.
    #[serde(rename = "struck")]
    Struck,
    /// The agent answered too many of its last turns later than the slow bound; killed.
    #[serde(rename = "slow")]
    Slow,
}

/// A fault name that is none of [`FaultKind::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown fault kind {0:?}")]
pub struct UnknownFaultKind(pub String);

impl FaultKind {
    /// Every kind, in the order the documentation lists them.
    pub const ALL: [FaultKind; 13] = [
        Self::Rejected,
        Self::Missed,
        Self::Hung,
        Self::Killed,
        Self::Dead,
        Self::Respawned,
        Self::RespawnFailed,
        Self::FailedToStart,
        Self::Malformed,
        Self::Unsolicited,
        Self::Impersonation,
        Self::Struck,
        Self::Slow,
    ];

    /// The name `summary.json` gives it.
    ///
    /// ```
    /// use shared::run::record::FaultKind;
    /// assert_eq!(FaultKind::FailedToStart.name(), "failed-to-start");
    /// assert_eq!("respawn_failed".parse(), Ok(FaultKind::RespawnFailed));
    /// ```
    pub fn name(&self) -> &'static str {
        match self {
            Self::Rejected => "rejected",
            Self::Missed => "missed",
            Self::Hung => "hung",
            Self::Killed => "killed",
            Self::Dead => "dead",
            Self::Respawned => "respawned",
            Self::RespawnFailed => "respawn_failed",
            Self::FailedToStart => "failed-to-start",
            Self::Malformed => "malformed",
            Self::Unsolicited => "unsolicited",
            Self::Impersonation => "impersonation",
            Self::Struck => "struck",
            Self::Slow => "slow",
        }
    }
}

impl std::fmt::Display for FaultKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for FaultKind {
    type Err = UnknownFaultKind;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        <Self as Named>::from_name(name).ok_or_else(|| UnknownFaultKind(name.to_string()))
    }
}

impl Named for FaultKind {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "fault kind";

    fn name(&self) -> &'static str {
        FaultKind::name(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_serialises_to_its_name_and_parses_back() {
        for kind in FaultKind::ALL {
            let json = serde_json::to_string(&kind).expect("serialise");
            assert_eq!(json, format!("\"{}\"", kind.name()));
            let back: FaultKind = serde_json::from_str(&json).expect("deserialise");
            assert_eq!(back, kind);
            assert_eq!(kind.name().parse::<FaultKind>(), Ok(kind));
        }
        assert!("Dead".parse::<FaultKind>().is_err());
    }
}
