//! The sandbox relay: on the coordinator's host and as the coordinator's user, it stands
//! for one agent that runs in a sandbox ([`crate::sandbox`]). It opens the agent's
//! iceoryx2 channel as a local agent would ([`IpcTransport`]), starts the agent as a
//! user of its own that can open none of the run's files, and forwards each turn to it
//! and its move back over their socket ([`SocketLink`]).
//!
//! So no agent writes the shared memory the coordinator reads: only relays do, and a
//! relay is trusted code. What the agent sends is untrusted: a frame too large, cut
//! short or not a message ends the relay, and the coordinator records the agent dead
//! (its process, the relay, is gone), as it records any agent whose process died; a
//! move that does not answer the turn is dropped, and the turn is missed.

use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use net::{Down, Up};

use crate::ipc::IpcTransport;
use crate::link::{move_of, net_turn};
use crate::sandbox::{AGENT_SOCKET_FD, Sandbox, spawn_sandboxed};
use crate::socket_link::{MAX_UP_FRAME_BYTES, SocketLink};
use crate::transport::{Command, Reply, Transport};

/// How long the relay waits at a time for its agent during the handshake, between
/// checks that the coordinator is still there.
const HANDSHAKE_SLICE: Duration = Duration::from_millis(50);

/// How long the relay waits for a move before it goes back to the coordinator (which has
/// long since counted the turn as missed): the next turn or a quit is then heard.
const MOVE_WAIT: Duration = Duration::from_secs(1);

/// What a sandbox relay is given.
pub struct SandboxRelaySettings<'a> {
    /// The run's prefix.
    pub prefix: &'a str,
    /// The agent's index.
    pub agent: usize,
    /// Its process generation.
    pub generation: u32,
    /// The mission file's digest, as the coordinator handed it.
    pub mission_digest: Option<wire::MissionDigest>,
    /// How often to check the coordinator while waiting.
    pub liveness: Duration,
    /// The agent's sandbox.
    pub sandbox: Sandbox,
    /// Arguments passed on to the sandboxed agent (its test mode).
    pub agent_args: Vec<String>,
}

/// Serve agent `settings.agent` as its sandbox relay until the coordinator says quit
/// (then the agent is told too), or the agent is gone or breaks the link (an error: the
/// coordinator sees the exit).
pub fn serve_sandboxed(settings: &SandboxRelaySettings) -> anyhow::Result<()> {
    let agent = settings.agent;
    let mut ipc = IpcTransport::open(
        settings.prefix,
        agent,
        settings.generation,
        settings.liveness,
        settings.mission_digest,
    )?;
    let toml = wire::read_mission(settings.prefix, settings.mission_digest)
        .context("the mission file")?
        .to_resolved_toml("the coordinator")
        .map_err(|e| anyhow::anyhow!("the mission as TOML: {e}"))?;
    let (ours, theirs) = UnixStream::pair().context("the agent's socket")?;
    let exe = std::env::current_exe().context("the agent executable")?;
    let mut args = vec![
        "--prefix".to_string(),
        settings.prefix.to_string(),
        "--agent".to_string(),
        agent.to_string(),
        "--socket-fd".to_string(),
        AGENT_SOCKET_FD.to_string(),
    ];
    args.extend(settings.agent_args.iter().cloned());
    let mut child = spawn_sandboxed(&exe, &args, theirs, &settings.sandbox)?;
    let mut link = SocketLink::new(ours);
    let agent_u32 = u32::try_from(agent).context("the agent's index")?;

    // The handshake: the mission, then the agent's word that it is ready.
    link.send(&Down::Mission { nonce: 0, toml })
        .context("handing the agent its mission")?;
    loop {
        if ipc.should_leave() {
            return Ok(());
        }
        if child.exited() {
            bail!("agent {agent}: the sandboxed process exited before it was ready");
        }
        match link.receive::<Up>(MAX_UP_FRAME_BYTES, Some(HANDSHAKE_SLICE)) {
            Ok(Some(Up::Ready { agent: a, nonce: 0 })) if a == agent_u32 => break,
            Ok(_) => {}
            Err(e) => bail!("agent {agent}: {e}"),
        }
    }
    ipc.announce_ready()?;

    loop {
        let turn = match ipc.next_command()? {
            Command::Quit => {
                let _ = link.send(&Down::Quit);
                return Ok(());
            }
            Command::Turn(turn) => turn,
        };
        link.send(&Down::Turn(net_turn(&turn)))
            .with_context(|| format!("agent {agent}: sending its turn"))?;
        let asked = Instant::now();
        while asked.elapsed() < MOVE_WAIT && !ipc.should_leave() {
            let left = MOVE_WAIT.saturating_sub(asked.elapsed());
            let m = match link.receive::<Up>(MAX_UP_FRAME_BYTES, Some(left)) {
                Ok(Some(Up::Move(m))) => m,
                Ok(_) => continue,
                Err(e) => bail!("agent {agent}: {e}"),
            };
            if m.agent != agent_u32 || m.token != turn.token || m.seq != turn.seq {
                continue;
            }
            if let Some((mv, status, compute)) = move_of(agent, m) {
                ipc.publish_move(Reply {
                    turn: &turn,
                    mv: &mv,
                    status,
                    compute,
                })?;
            }
            break;
        }
    }
}
