//! What every relay does, whatever its link to the agent it stands for (Zenoh to
//! another machine, a socket to a sandboxed agent): open the agent's channel, read the
//! mission, and then forward each turn to the agent and the move that answers it back.

use std::time::{Duration, Instant};

use anyhow::Context;
use net::{Down, Up};

use crate::args::Args;
use crate::ipc::{IpcTransport, Mission};
use crate::link::{move_of, net_turn};
use crate::transport::{Command, Reply, Transport};

/// How long a relay waits for a move before it goes back to the coordinator (which has
/// long since counted the turn as missed): the next turn or a quit is then heard.
pub const MOVE_WAIT: Duration = Duration::from_secs(1);

/// The agent's channel, as the coordinator handed it to the relay.
#[derive(Clone, Copy, Debug)]
pub struct RelayedChannel<'a> {
    /// The run's prefix.
    pub prefix: &'a str,
    /// The agent's index.
    pub agent: usize,
    /// Its process generation.
    pub generation: u32,
    /// The run's mission, read by the digest the coordinator handed over.
    pub mission: &'a Mission,
    /// How often to check the coordinator while waiting.
    pub liveness: Duration,
}

impl<'a> RelayedChannel<'a> {
    /// The channel of agent `args.agent` in run `prefix`, as its relay opens it: checking
    /// the coordinator every `liveness`, `mission` read.
    pub fn for_agent(
        args: &Args,
        prefix: &'a str,
        liveness: Duration,
        mission: &'a Mission,
    ) -> Self {
        Self {
            prefix,
            agent: args.agent,
            generation: args.generation,
            mission,
            liveness,
        }
    }

    /// Open the agent's channel; with it, the mission file's text the agent is handed,
    /// as the coordinator wrote it.
    pub fn open(&self) -> anyhow::Result<(IpcTransport, String)> {
        let ipc = IpcTransport::open(
            self.prefix,
            self.agent,
            self.generation,
            self.liveness,
            self.mission.view.clone(),
        )?;
        Ok((ipc, self.mission.text.clone()))
    }
}

/// A relay's link to its agent.
pub trait AgentLink {
    /// Send `message` to the agent.
    fn send(&mut self, message: &Down) -> anyhow::Result<()>;
    /// The agent's next message within `timeout` (`None`: none came); an error ends the
    /// relay (the agent is gone, or broke the link).
    fn receive(&mut self, timeout: Duration) -> anyhow::Result<Option<Up>>;
}

/// Forward every turn of `ipc` to `agent` over `link`, and the move that answers it (its
/// agent, sequence number and token) back, until the coordinator says quit (the agent is
/// told too) or the link fails.
pub fn forward_turns(
    ipc: &mut IpcTransport,
    link: &mut impl AgentLink,
    agent: usize,
) -> anyhow::Result<()> {
    let agent_u32 = u32::try_from(agent).context("the agent's index")?;
    loop {
        let turn = match ipc.next_command()? {
            Command::Quit => {
                let _ = link.send(&Down::Quit);
                return Ok(());
            }
            Command::Turn(turn) => turn,
        };
        link.send(&Down::Turn(net_turn(&turn)))?;
        let asked = Instant::now();
        while asked.elapsed() < MOVE_WAIT && !ipc.should_leave() {
            let Some(Up::Move(m)) = link.receive(MOVE_WAIT.saturating_sub(asked.elapsed()))? else {
                continue;
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
