//! The echo: an agent rung for an empty turn, which it answers at once without reading
//! a world, planning or moving (`coordinator bench`: the wake-ups alone).

use std::time::Instant;

use anyhow::Context;
use wire::{EVENT_ECHO, StateKind};

use super::{CoordinatorIpc, TurnSplit};

impl CoordinatorIpc {
    /// Ring `agent`'s echo and wait until `deadline` for its empty answer from process
    /// `pid`: the round trip of a turn without world, planning or move (benchmarks).
    /// `None` if no answer came in time or the agent did not stamp it.
    pub fn echo(
        &self,
        agent: usize,
        pid: u32,
        deadline: Instant,
    ) -> anyhow::Result<Option<TurnSplit>> {
        let rung_ns = self.ring_echo(agent)?;
        Ok(self.await_echo(agent, pid, rung_ns, deadline))
    }

    /// Ring the echo of every agent of `group` (agent, process) at once, then wait until
    /// `deadline` for each answer in turn: a group's turns without world, planning or
    /// move (benchmarks). How many answered in time.
    pub fn echo_group(&self, group: &[(usize, u32)], deadline: Instant) -> anyhow::Result<usize> {
        let mut rung = Vec::with_capacity(group.len());
        for &(agent, pid) in group {
            rung.push((agent, pid, self.ring_echo(agent)?));
        }
        Ok(rung
            .into_iter()
            .filter(|&(agent, pid, rung_ns)| {
                self.await_echo(agent, pid, rung_ns, deadline).is_some()
            })
            .count())
    }

    /// Ring `agent`'s echo: the moment it was rung ([`wire::monotonic_ns`]).
    fn ring_echo(&self, agent: usize) -> anyhow::Result<u64> {
        let rung_ns = wire::monotonic_ns();
        self.ring(agent, EVENT_ECHO)
            .with_context(|| format!("ringing agent {agent}'s echo"))?;
        Ok(rung_ns)
    }

    /// Wait until `deadline` for `agent`'s answer, from process `pid`, to the echo rung
    /// at `rung_ns`: its split, or `None` if none came in time or it was not stamped.
    fn await_echo(
        &self,
        agent: usize,
        pid: u32,
        rung_ns: u64,
        deadline: Instant,
    ) -> Option<TurnSplit> {
        loop {
            while let Some(incoming) = self.receive(agent) {
                // An answer sent before the ring is a late one from an earlier echo.
                if let Ok(msg) = &incoming.msg
                    && incoming.publisher_pid == Some(pid)
                    && msg.kind == StateKind::Echo
                    && msg.sent_ns >= rung_ns
                {
                    let held_ns = wire::monotonic_ns();
                    return TurnSplit::of(rung_ns, msg, held_ns);
                }
                // A sample that could not be received at all ends the wait.
                incoming.publisher_pid?;
            }
            if !self.wait_done(agent, deadline) {
                return None;
            }
        }
    }
}
