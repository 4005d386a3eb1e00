//! The key expressions of a run over Zenoh. One router (the coordinator's) serves one
//! run, so the keys need no run name.

/// Where agent `agent`'s relay publishes to the agent ([`crate::Down`]).
pub fn agent_down_key(agent: usize) -> String {
    format!("formation/agent/{agent}/down")
}

/// Where agent `agent` publishes to its relay ([`crate::Up`]).
pub fn agent_up_key(agent: usize) -> String {
    format!("formation/agent/{agent}/up")
}

/// Agent `agent`'s liveliness token: it lasts as long as the agent's session.
pub fn agent_alive_key(agent: usize) -> String {
    format!("formation/agent/{agent}/alive")
}

/// The coordinator's liveliness token: an agent leaves when it is gone.
pub const COORDINATOR_ALIVE_KEY: &str = "formation/coordinator/alive";
