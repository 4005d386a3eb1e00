//! The agent's test modes (`agent --misbehave MODE`, [`Misbehave`]): an agent that
//! misbehaves or attacks on purpose, so users and the integration tests can check that
//! the coordinator survives every one of them. Compiled only with the crate's
//! `misbehave` feature (the integration tests turn it on: `cargo test --workspace`); the
//! shipping agent has none of this code.
//!
//! Every mode is a decorator around the honest agent, which runs unchanged inside it; the
//! roles reach these through the agent's `TestMode` (`test_mode.rs`), never directly:
//! - [`Misbehaving`], a [`Transport`](crate::Transport) decorator: the moves that go out
//!   (bad moves, moves out of turn); over iceoryx2 and over Zenoh alike;
//! - [`Tampered`], a decorator of the iceoryx2 ports ([`Channel`](crate::ipc::Channel)):
//!   raw bytes in the samples that go out, a handshake in another agent's name, the
//!   prepare notice that comes in dropped;
//! - [`before_opening`]: what acts outside the channel, before it is opened (processes
//!   that try to outlive the run, attacks on other agents' channels, the attacks a
//!   sandbox must hold against: files scribbled over, processes stopped, fork bombs).

mod moves;
mod rogue;
mod sandbox_attacks;
mod strays;
mod tamper;

use std::any::Any;

use wire::misbehave::Misbehave;

use crate::ipc::IpcTransport;

pub use moves::{Misbehaving, corrupt};
pub use strays::{start_strays, stray_marker};
pub use tamper::Tampered;

/// What test mode `mode` does before agent `agent` of run `prefix` reads the mission:
/// `rewrite-mission` forges the file (the agent then reads its own forgery, as any agent
/// that reads it after). A trusted agent only: a sandboxed one tries it from inside its
/// sandbox ([`before_opening`]), and a relay attacks nothing.
pub fn before_reading(prefix: &str, agent: usize, mode: Misbehave) {
    if mode == Misbehave::RewriteMission {
        sandbox_attacks::rewrite_mission(prefix, agent);
    }
}

/// Carry out what mode `mode` of agent `agent` does before the agent opens its channel
/// in run `prefix`: start the `fork` mode's strays, then the attacks on other agents'
/// channels (which race their owners). Returns what must stay open (ports, services,
/// nodes) for the life of the process.
pub fn before_opening(
    prefix: &str,
    agent: usize,
    mode: Misbehave,
) -> anyhow::Result<Vec<Box<dyn Any>>> {
    if mode == Misbehave::Fork {
        start_strays(prefix)?;
    }
    sandbox_attacks::before_opening(prefix, agent, mode);
    Ok(rogue::before_opening(prefix, agent, mode))
}

/// Serve agent `agent`'s turns over its opened iceoryx2 channel `transport` as mode
/// `mode` has it: its ports [`Tampered`], its moves [`Misbehaving`]. The
/// `exit-before-ready` mode leaves here, without closing anything.
pub fn serve_ipc(transport: IpcTransport, agent: usize, mode: Misbehave) -> anyhow::Result<()> {
    let transport = transport.map_channel(|ports| Tampered::new(ports, mode));
    if mode == Misbehave::ExitBeforeReady {
        // Leave at once, without closing anything: the coordinator must cope.
        std::process::exit(3);
    }
    crate::serve::serve(&mut Misbehaving::new(transport, agent, mode), agent)
}
