//! The sandbox relay: on the coordinator's host and as the coordinator's user, it stands
//! for one agent that runs in a sandbox ([`crate::sandbox`]). It opens the agent's
//! iceoryx2 channel as a local agent would, starts the agent as a user of its own that
//! can open none of the run's files, and forwards each turn to it and its move back over
//! their socket ([`SocketLink`], [`forward_turns`]).
//!
//! So no agent writes the shared memory the coordinator reads: only relays do, and a
//! relay is trusted code. What the agent sends is untrusted: a frame too large, cut
//! short or not a message ends the relay, and the coordinator records the agent dead
//! (its process, the relay, is gone), as it records any agent whose process died; a
//! move that does not answer the turn is dropped, and the turn is missed.

use std::os::unix::net::UnixStream;
use std::time::Duration;

use anyhow::{Context, bail};
use net::{Down, Up};

use wire::cgroup::Limits;

use crate::args::Args;
use crate::forward::{AgentLink, RelayedChannel, forward_turns};
use crate::ipc::Mission;
use crate::sandbox::{AGENT_SOCKET_FD, Sandbox, adopt_orphans, spawn_sandboxed};
use crate::socket_link::{MAX_UP_FRAME_BYTES, SocketLink};
use crate::transport::Transport;

/// How long the relay waits at a time for its agent during the handshake, between
/// checks that the coordinator is still there.
const HANDSHAKE_SLICE: Duration = Duration::from_millis(50);

/// What a sandbox relay is given.
pub struct SandboxRelaySettings<'a> {
    /// The agent's channel.
    pub channel: RelayedChannel<'a>,
    /// The agent's sandbox.
    pub sandbox: Sandbox,
    /// Arguments passed on to the sandboxed agent (its test mode).
    pub agent_args: Vec<String>,
}

impl AgentLink for SocketLink {
    fn send(&mut self, message: &Down) -> anyhow::Result<()> {
        Ok(SocketLink::send(self, message)?)
    }

    fn receive(&mut self, timeout: Duration) -> anyhow::Result<Option<Up>> {
        Ok(SocketLink::receive(
            self,
            MAX_UP_FRAME_BYTES,
            Some(timeout),
        )?)
    }
}

/// Serve agent `settings.channel.agent` as its sandbox relay until the coordinator says
/// quit (then the agent is told too), or the agent is gone or breaks the link (an error:
/// the coordinator sees the exit).
pub fn serve_sandboxed(settings: &SandboxRelaySettings) -> anyhow::Result<()> {
    let channel = &settings.channel;
    let agent = channel.agent;
    let (mut ipc, json) = channel.open()?;
    let (ours, theirs) = UnixStream::pair().context("the agent's socket")?;
    let exe = std::env::current_exe().context("the agent executable")?;
    let mut args = vec![
        "--prefix".to_string(),
        channel.prefix.to_string(),
        "--agent".to_string(),
        agent.to_string(),
        "--socket-fd".to_string(),
        AGENT_SOCKET_FD.to_string(),
    ];
    args.extend(settings.agent_args.iter().cloned());
    adopt_orphans();
    let mut child = spawn_sandboxed(&exe, &args, theirs, &settings.sandbox)?;
    let mut link = SocketLink::new(ours);
    let agent_u32 = u32::try_from(agent).context("the agent's index")?;

    // The handshake: the mission, then the agent's word that it is ready.
    AgentLink::send(&mut link, &Down::Mission { nonce: 0, json })
        .context("handing the agent its mission")?;
    loop {
        if ipc.should_leave() {
            return Ok(());
        }
        if child.exited() {
            bail!("agent {agent}: the sandboxed process exited before it was ready");
        }
        match AgentLink::receive(&mut link, HANDSHAKE_SLICE) {
            Ok(Some(Up::Ready { agent: a, nonce: 0 })) if a == agent_u32 => break,
            Ok(_) => {}
            Err(e) => bail!("agent {agent}: {e}"),
        }
    }
    ipc.announce_ready()?;
    forward_turns(&mut ipc, &mut link, agent).with_context(|| format!("agent {agent}"))
}

/// Serve as the sandbox relay of agent `args.agent` ([`serve_sandboxed`]):
/// the agent is started here as user `uid`, with this agent's test mode.
pub(crate) fn run_sandbox_relay(
    args: &Args,
    prefix: &str,
    uid: u32,
    liveness: Duration,
    mission: &Mission,
) -> anyhow::Result<()> {
    let limits = Limits {
        pids_max: args.pids_max,
        memory_mib: args.memory_mib,
        cpu_percent: args.cpu_percent,
    };
    let cgroup = if args.cgroup {
        let run = wire::cgroup::CgroupDirs::for_run(prefix).context("the run's control group")?;
        Some(run.child(&format!("agent-{}-{}", args.agent, args.generation)))
    } else {
        None
    };
    let agent_args = match args.misbehave {
        Some(mode) => vec!["--misbehave".to_string(), mode.to_string()],
        None => Vec::new(),
    };
    serve_sandboxed(&SandboxRelaySettings {
        channel: RelayedChannel::for_agent(args, prefix, liveness, mission),
        sandbox: Sandbox {
            uid,
            cgroup,
            limits,
        },
        agent_args,
    })
}
