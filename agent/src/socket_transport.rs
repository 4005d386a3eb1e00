//! A sandboxed agent's side of its link: it takes its turns from its relay over the
//! socket it inherited ([`crate::socket_link`]), and never opens the run's shared memory
//! (its user cannot). The relay is trusted (the coordinator's user): the mission and the
//! turns it sends are still checked as any input is.

use std::os::fd::FromRawFd;
use std::os::unix::net::UnixStream;

use anyhow::{Context, bail};
use net::{Down, MAX_MESSAGE_BYTES, Up};
use shared::world::scenario::Checks;

use crate::args::Args;
use crate::link::{mission_view, net_move, turn_input};
use crate::socket_link::{LinkError, SocketLink};
use crate::test_mode::TestMode;
use crate::transport::{Command, MissionView, Reply, Transport};

/// The agent's end of its relay's socket.
pub struct SocketTransport {
    agent: usize,
    link: SocketLink,
    mission: Option<MissionView>,
}

impl SocketTransport {
    /// Agent `agent` on the socket it inherited as descriptor `fd`.
    ///
    /// # Safety
    ///
    /// `fd` must be an open Unix stream socket that nothing else in this process owns.
    pub unsafe fn from_fd(fd: i32, agent: usize) -> Self {
        // SAFETY: the caller hands over `fd`, open and owned by no one else.
        let stream = unsafe { UnixStream::from_raw_fd(fd) };
        Self {
            agent,
            link: SocketLink::new(stream),
            mission: None,
        }
    }

    fn send(&mut self, message: &Up) -> anyhow::Result<()> {
        self.link.send(message).context("writing to the relay")
    }

    /// The next message from the relay (blocking); `None` once the relay is gone.
    fn receive(&mut self) -> anyhow::Result<Option<Down>> {
        match self.link.receive::<Down>(MAX_MESSAGE_BYTES, None) {
            Ok(message) => Ok(message),
            Err(LinkError::Closed) => Ok(None),
            Err(e) => Err(e).context("reading from the relay"),
        }
    }
}

impl Transport for SocketTransport {
    fn announce_ready(&mut self) -> anyhow::Result<()> {
        let agent = u32::try_from(self.agent).context("the agent's index")?;
        loop {
            match self.receive()? {
                Some(Down::Mission { nonce, json }) => {
                    // From this agent's own relay, which read the file by its digest.
                    self.mission = Some(mission_view(&json, self.agent, Checks::Values)?);
                    return self.send(&Up::Ready { agent, nonce });
                }
                Some(Down::Quit) | None => bail!("the relay left before the mission"),
                Some(_) => {}
            }
        }
    }

    fn next_command(&mut self) -> anyhow::Result<Command> {
        loop {
            match self.receive()? {
                Some(Down::Turn(t)) => match turn_input(t) {
                    Ok(turn) => return Ok(Command::Turn(turn)),
                    Err(e) => tracing::warn!("agent {}: {e:#}", self.agent),
                },
                Some(Down::Quit) | None => return Ok(Command::Quit),
                Some(_) => {}
            }
        }
    }

    fn mission(&mut self) -> anyhow::Result<MissionView> {
        self.mission
            .clone()
            .context("no mission yet: the handshake is not done")
    }

    fn publish_move(&mut self, reply: Reply<'_>) -> anyhow::Result<()> {
        let message = Up::Move(net_move(self.agent, reply)?);
        self.send(&message)
    }
}

/// Serve as a sandboxed agent over the socket `fd` its relay handed it. Its test mode's
/// attacks on the run's shared memory are tried as they would be by any agent (its user
/// can open none of it); its moves misbehave as asked.
pub(crate) fn serve_sandboxed_agent(
    args: &Args,
    prefix: &str,
    fd: i32,
    mode: TestMode,
) -> anyhow::Result<()> {
    // SAFETY: the relay handed this descriptor over; nothing else in this process owns it.
    mode.serve_socket(prefix, || unsafe {
        SocketTransport::from_fd(fd, args.agent)
    })
}
