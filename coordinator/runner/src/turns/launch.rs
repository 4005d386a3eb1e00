//! How the run starts an agent's process ([`AgentLaunch`]): its command line beyond its
//! prefix and index.

use super::fault_injection::FaultInjection;
use super::options::SandboxOptions;
use crate::network::NetworkOptions;

/// What every agent process of a run is started with.
#[derive(Clone, Debug)]
pub(super) struct AgentLaunch {
    /// The faults injected (an agent's test mode among them).
    pub(super) faults: FaultInjection,
    /// The mission file's digest, handed to every process started.
    pub(super) mission_digest: wire::MissionDigest,
    /// How agents are sandboxed, their user ids as the run claimed them; `None`: not.
    pub(super) sandbox: Option<SandboxOptions>,
    /// How agents reach the router, as it was opened (the run's own TLS folder named);
    /// `None`: every agent on iceoryx2 (or the router not open yet).
    pub(super) network: Option<NetworkOptions>,
    /// Whether the run has a control group for its sandboxed agents.
    pub(super) run_cgroup: bool,
}

impl AgentLaunch {
    /// The command-line arguments of agent `agent`'s process beyond its prefix and index:
    /// its channel's `generation`, the mission's digest, its test mode unless it is a
    /// `replacement` (a replacement never misbehaves), and its relay's settings: a
    /// sandbox relay for an agent this host starts when the run sandboxes (over Zenoh
    /// too), a network relay for the others over Zenoh.
    pub(super) fn args(&self, agent: usize, replacement: bool, generation: u32) -> Vec<String> {
        let mut extra = vec![
            "--generation".to_string(),
            generation.to_string(),
            "--mission-sha256".to_string(),
            self.mission_digest.to_string(),
        ];
        if !replacement && let Some(mode) = self.faults.misbehaviour_of(agent) {
            extra.extend(["--misbehave".to_string(), mode.to_string()]);
        }
        // An agent this host starts is sandboxed when the run sandboxes, over Zenoh too:
        // behind the sandbox's socket relay, with no key and no link of its own. An agent
        // started elsewhere (`--remote`) has a network relay here.
        let here = self.network.as_ref().is_none_or(|n| n.starts_here(agent));
        match (&self.sandbox, &self.network) {
            (Some(sandbox), _) if here => extra.extend(sandbox.relay_args(agent, self.run_cgroup)),
            (_, Some(network)) => extra.extend(network.relay_args(agent)),
            (_, None) => {}
        }
        extra
    }
}
