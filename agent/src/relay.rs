//! The relay: on the coordinator's host, it stands for an agent that runs elsewhere. It
//! opens the agent's iceoryx2 channel as a local agent would
//! ([`IpcTransport`](crate::ipc::IpcTransport)) and forwards each turn to the agent and
//! its move back over Zenoh ([`net`]).
//!
//! The coordinator's checks, deadlines and fault handling see the relay as the agent:
//! when the agent's session ends (its process died, its link went down for longer than
//! [`net::LINK_LEASE`]), its liveliness token goes, the relay exits, and the coordinator
//! freezes the agent as it freezes any agent whose process died. A relay started again
//! (`--respawn`) probes for the agent and admits it again if it is (still or again)
//! there; without a respawn, an agent that comes back finds no relay and takes no turn.

use std::process::{Child, Command as ProcessCommand, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use net::zenoh::Wait;
use net::zenoh::handlers::FifoChannelHandler;
use net::zenoh::pubsub::{Publisher, Subscriber};
use net::zenoh::sample::{Sample, SampleKind};
use net::{Down, Endpoint, Security, Up};

use crate::args::Args;
use crate::forward::{AgentLink, RelayedChannel, forward_turns};
use crate::ipc::Mission;
use crate::transport::Transport;

/// How often the relay probes for its agent until it answers.
const PROBE_PERIOD: Duration = Duration::from_millis(50);

/// What a relay is given.
pub struct RelaySettings<'a> {
    /// The agent's channel.
    pub channel: RelayedChannel<'a>,
    /// The router.
    pub connect: &'a Endpoint,
    /// Plain or TLS.
    pub security: &'a Security,
    /// The TLS folder, passed on to a spawned agent.
    pub tls_dir: Option<&'a std::path::Path>,
    /// Start the agent itself, on this host (single-host use and tests), with these extra
    /// arguments.
    pub spawn_agent: Option<Vec<String>>,
}

/// An agent process the relay started; killed and reaped with the relay.
struct SpawnedAgent(Child);

impl Drop for SpawnedAgent {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

struct Link {
    agent: usize,
    down: Publisher<'static>,
    up: Subscriber<FifoChannelHandler<Sample>>,
    alive: Subscriber<FifoChannelHandler<Sample>>,
    /// The agent's token, as last seen.
    token: Token,
}

/// A liveliness token as a watcher sees it: never yet, there, or gone since when. A
/// token that comes back within [`REJOIN_GRACE`] (the session was dropped and the client
/// reconnected) is taken as never gone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Token {
    /// Not seen yet.
    Unseen,
    /// There.
    Present,
    /// Gone since then.
    GoneSince(Instant),
}

/// How long a token seen before may be gone before its owner counts as gone: a client
/// whose session dropped reconnects (and declares its token again) within about a lease.
pub(crate) const REJOIN_GRACE: Duration = net::LINK_LEASE;

impl Token {
    /// The state after `sample`.
    pub(crate) fn after(self, kind: SampleKind) -> Self {
        match (self, kind) {
            (_, SampleKind::Put) => Self::Present,
            (Self::Unseen, SampleKind::Delete) => Self::Unseen,
            (Self::GoneSince(t), SampleKind::Delete) => Self::GoneSince(t),
            (Self::Present, SampleKind::Delete) => Self::GoneSince(Instant::now()),
        }
    }

    /// Whether the token was seen and has been gone for [`REJOIN_GRACE`].
    pub(crate) fn gone(self) -> bool {
        matches!(self, Self::GoneSince(t) if t.elapsed() >= REJOIN_GRACE)
    }
}

impl AgentLink for Link {
    fn send(&mut self, message: &Down) -> anyhow::Result<()> {
        Ok(net::send(&self.down, message)?)
    }

    fn receive(&mut self, timeout: Duration) -> anyhow::Result<Option<Up>> {
        Link::receive(self, timeout)
    }
}

impl Link {
    /// Fails once the agent's liveliness token, seen before, has been gone for
    /// [`REJOIN_GRACE`].
    fn check_alive(&mut self) -> anyhow::Result<()> {
        while let Ok(Some(sample)) = self.alive.try_recv() {
            let before = self.token;
            self.token = self.token.after(sample.kind());
            if matches!(before, Token::GoneSince(_)) && self.token == Token::Present {
                tracing::warn!(
                    "relay of agent {}: the agent's session dropped and came back",
                    self.agent
                );
            }
        }
        if self.token.gone() {
            bail!("agent {}: its session is gone", self.agent);
        }
        Ok(())
    }

    /// The next message from the agent within `timeout`; one that does not decode is
    /// logged and skipped (the agent is another machine: untrusted).
    fn receive(&mut self, timeout: Duration) -> anyhow::Result<Option<Up>> {
        self.check_alive()?;
        match net::receive::<Up>(&self.up, timeout)? {
            Some(Ok(message)) => Ok(Some(message)),
            Some(Err(e)) => {
                tracing::warn!("relay of agent {}: {e}", self.agent);
                Ok(None)
            }
            None => Ok(None),
        }
    }
}

/// Serve agent `settings.channel.agent` as its relay until the coordinator says quit (then the
/// agent is told too) or the agent is gone (an error: the coordinator sees the exit).
pub fn serve_relay(settings: &RelaySettings) -> anyhow::Result<()> {
    let agent = settings.channel.agent;
    let (mut ipc, json) = settings.channel.open()?;
    let session = net::open_client(settings.connect, settings.security)
        .with_context(|| format!("connecting to {}", settings.connect))?;
    let z = |e: net::zenoh::Error| anyhow::anyhow!("zenoh: {e}");
    let mut link = Link {
        agent,
        down: session
            .declare_publisher(net::agent_down_key(agent))
            // Sent at once, never held back to be batched with others.
            .express(true)
            .wait()
            .map_err(z)?,
        up: session
            .declare_subscriber(net::agent_up_key(agent))
            .wait()
            .map_err(z)?,
        alive: session
            .liveliness()
            .declare_subscriber(net::agent_alive_key(agent))
            .history(true)
            .wait()
            .map_err(z)?,
        token: Token::Unseen,
    };
    let _spawned = match &settings.spawn_agent {
        Some(extra) => Some(spawn_agent(settings, extra)?),
        None => None,
    };

    // The handshake: probe until the agent says hello, then hand it the mission.
    let nonce = random_nonce()?;
    let agent_u32 = u32::try_from(agent).context("the agent's index")?;
    let mut probed = Instant::now() - PROBE_PERIOD;
    let mut mission_sent = false;
    loop {
        if ipc.should_leave() {
            return Ok(());
        }
        if !mission_sent && probed.elapsed() >= PROBE_PERIOD {
            link.send(&Down::Probe { nonce })?;
            probed = Instant::now();
        }
        match link.receive(PROBE_PERIOD)? {
            Some(Up::Hello { agent: a, nonce: n }) if a == agent_u32 && n == nonce => {
                link.send(&Down::Mission {
                    nonce,
                    json: json.clone(),
                })?;
                mission_sent = true;
            }
            Some(Up::Ready { agent: a, nonce: n }) if a == agent_u32 && n == nonce => break,
            _ => {}
        }
    }
    ipc.announce_ready()?;
    forward_turns(&mut ipc, &mut link, agent)
}

fn random_nonce() -> anyhow::Result<u64> {
    let mut bytes = [0u8; 8];
    getrandom::fill(&mut bytes).map_err(|e| anyhow::anyhow!("the OS random source: {e}"))?;
    Ok(u64::from_le_bytes(bytes))
}

/// Start agent `settings.channel.agent` on this host, connected to the same router.
fn spawn_agent(settings: &RelaySettings, extra: &[String]) -> anyhow::Result<SpawnedAgent> {
    let exe = std::env::current_exe().context("the agent executable")?;
    let mut command = ProcessCommand::new(exe);
    command
        .args(["--connect", &settings.connect.to_string()])
        .args(["--agent", &settings.channel.agent.to_string()])
        .args([
            "--liveness-ms",
            &settings.channel.liveness.as_millis().to_string(),
        ])
        .args(extra)
        // Its parent is this relay, not the coordinator (`wire::PARENT_ENV`).
        .env_remove(wire::PARENT_ENV)
        .stdin(Stdio::null());
    if let Some(dir) = settings.tls_dir {
        command.arg("--tls-dir").arg(dir);
    }
    let child = command.spawn().context("starting the agent")?;
    Ok(SpawnedAgent(child))
}

/// Serve as the relay of agent `args.agent` ([`serve_relay`]); with `--spawn-agent`, the
/// agent is started here, with this agent's test mode and settings.
pub(crate) fn run_relay(
    args: &Args,
    prefix: &str,
    connect: &net::Endpoint,
    security: &net::Security,
    liveness: Duration,
    mission: &Mission,
) -> anyhow::Result<()> {
    let mut extra = vec!["--die-with-parent".to_string()];
    if let Some(mode) = args.misbehave {
        extra.extend(["--misbehave".to_string(), mode.to_string()]);
    }
    if args.allow_plain_tcp {
        extra.push("--allow-plain-tcp".to_string());
    }
    serve_relay(&RelaySettings {
        channel: RelayedChannel::for_agent(args, prefix, liveness, mission),
        connect,
        security,
        tls_dir: args.tls_dir.as_deref(),
        spawn_agent: args.spawn_agent.then_some(extra),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_token_counts_as_gone_only_after_the_grace_and_not_before_it_was_seen() {
        let t = Token::Unseen.after(SampleKind::Delete);
        assert_eq!(t, Token::Unseen);
        assert!(!t.gone());
        let present = t.after(SampleKind::Put);
        assert_eq!(present, Token::Present);
        let dropped = present.after(SampleKind::Delete);
        assert!(matches!(dropped, Token::GoneSince(_)));
        assert!(!dropped.gone(), "gone at once, before the grace");
        // A second delete keeps the first time; a put brings it back.
        assert_eq!(dropped.after(SampleKind::Delete), dropped);
        assert_eq!(dropped.after(SampleKind::Put), Token::Present);
        let long_ago = Instant::now()
            .checked_sub(REJOIN_GRACE + Duration::from_millis(1))
            .expect("a monotonic clock that far back");
        assert!(Token::GoneSince(long_ago).gone());
    }
}
