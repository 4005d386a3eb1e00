//! The agent's side of the protocol over Zenoh ([`net`]): an agent on another machine
//! than the coordinator. It connects to the coordinator's router, announces itself with a
//! liveliness token, answers its relay's probe, takes the mission and serves turns.

use std::time::Duration;

use anyhow::{Context, bail};
use net::zenoh::Session;
use net::zenoh::Wait;
use net::zenoh::handlers::FifoChannelHandler;
use net::zenoh::liveliness::LivelinessToken;
use net::zenoh::pubsub::{Publisher, Subscriber};
use net::zenoh::sample::Sample;
use net::{Down, Endpoint, Security, Up};
use shared::world::scenario::Checks;

use crate::link::{mission_view, net_move, turn_input};
use crate::relay::Token;
use crate::transport::{Command, MissionView, Reply, Transport};

/// How long a waiting agent waits for a message before it looks at the coordinator's
/// token again, at most. The look is local (the token's comings and goings are pushed
/// to this process), so it is cheap; it bounds how late an agent leaves once the
/// coordinator is gone ([`Token::gone`]), whatever `--liveness-ms` says.
const TOKEN_LOOK: Duration = Duration::from_millis(250);

/// The agent's Zenoh session and ports.
pub struct NetTransport {
    agent: usize,
    _session: Session,
    _token: LivelinessToken,
    down: Subscriber<FifoChannelHandler<Sample>>,
    up: Publisher<'static>,
    coordinator: Subscriber<FifoChannelHandler<Sample>>,
    /// The coordinator's token as last seen.
    coordinator_token: Token,
    mission: Option<MissionView>,
    liveness: Duration,
}

impl NetTransport {
    /// Connect agent `agent` to the router at `connect`. `liveness` is how often it looks
    /// for the coordinator while it waits (every 250 ms at most: the look is local).
    pub fn connect(
        connect: &Endpoint,
        security: &Security,
        agent: usize,
        liveness: Duration,
    ) -> anyhow::Result<Self> {
        let session = net::open_client(connect, security)
            .with_context(|| format!("connecting to {connect}"))?;
        let z = |e: net::zenoh::Error| anyhow::anyhow!("zenoh: {e}");
        let down = session
            .declare_subscriber(net::agent_down_key(agent))
            .wait()
            .map_err(z)?;
        let up = session
            .declare_publisher(net::agent_up_key(agent))
            // Sent at once, never held back to be batched with others.
            .express(true)
            .wait()
            .map_err(z)?;
        let coordinator = session
            .liveliness()
            .declare_subscriber(net::COORDINATOR_ALIVE_KEY)
            .history(true)
            .wait()
            .map_err(z)?;
        let token = session
            .liveliness()
            .declare_token(net::agent_alive_key(agent))
            .wait()
            .map_err(z)?;
        Ok(Self {
            agent,
            _session: session,
            _token: token,
            down,
            up,
            coordinator,
            coordinator_token: Token::Unseen,
            mission: None,
            liveness: liveness.min(TOKEN_LOOK),
        })
    }

    fn send(&self, message: &Up) -> anyhow::Result<()> {
        Ok(net::send(&self.up, message)?)
    }

    /// Whether the coordinator's token came and has been gone for a while
    /// ([`Token::gone`]).
    fn coordinator_gone(&mut self) -> bool {
        while let Ok(Some(sample)) = self.coordinator.try_recv() {
            self.coordinator_token = self.coordinator_token.after(sample.kind());
        }
        self.coordinator_token.gone()
    }

    /// The next message from the relay, waiting at most `timeout`; a message that does
    /// not decode is logged and skipped.
    fn receive(&mut self, timeout: Duration) -> anyhow::Result<Option<Down>> {
        match net::receive::<Down>(&self.down, timeout)? {
            Some(Ok(message)) => Ok(Some(message)),
            Some(Err(e)) => {
                tracing::warn!("agent {}: from the relay: {e}", self.agent);
                Ok(None)
            }
            None => Ok(None),
        }
    }

    /// Answer a probe or a mission (the handshake, again after a relay's respawn);
    /// true once a mission was taken.
    fn handshake_step(&mut self, message: &Down) -> anyhow::Result<bool> {
        let agent = u32::try_from(self.agent).context("the agent's index")?;
        match message {
            Down::Probe { nonce } => {
                self.send(&Up::Hello {
                    agent,
                    nonce: *nonce,
                })?;
                Ok(false)
            }
            Down::Mission { nonce, json } => {
                self.mission = Some(mission_view(json, self.agent, Checks::All)?);
                self.send(&Up::Ready {
                    agent,
                    nonce: *nonce,
                })?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }
}

impl Transport for NetTransport {
    fn announce_ready(&mut self) -> anyhow::Result<()> {
        // Readiness is said in the handshake, when a relay sends the mission.
        loop {
            if self.coordinator_gone() {
                bail!("the coordinator left before the handshake");
            }
            if let Some(message) = self.receive(self.liveness)?
                && self.handshake_step(&message)?
            {
                return Ok(());
            }
        }
    }

    fn next_command(&mut self) -> anyhow::Result<Command> {
        loop {
            match self.receive(self.liveness)? {
                Some(Down::Turn(t)) => match turn_input(t) {
                    Ok(turn) => return Ok(Command::Turn(turn)),
                    Err(e) => tracing::warn!("agent {}: {e:#}", self.agent),
                },
                Some(Down::Quit) => return Ok(Command::Quit),
                Some(message) => {
                    self.handshake_step(&message)?;
                }
                None => {}
            }
            if self.coordinator_gone() {
                tracing::warn!("agent {}: coordinator gone, leaving", self.agent);
                return Ok(Command::Quit);
            }
        }
    }

    fn mission(&mut self) -> anyhow::Result<MissionView> {
        self.mission
            .clone()
            .context("no mission yet: the handshake is not done")
    }

    fn publish_move(&mut self, reply: Reply<'_>) -> anyhow::Result<()> {
        self.send(&Up::Move(net_move(self.agent, reply)?))
    }
}
