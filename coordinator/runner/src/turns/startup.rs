//! Starting agents: the ready handshake, failed starts, replacements.

use std::time::{Duration, Instant};

use anyhow::bail;
use shared::run::record::{Fault, FaultKind, Recorder};
use wire::StateKind;

use super::driver::Driver;
use super::options::LIVENESS_SLICE;
use crate::agents::Exit;

/// How long a replacement process has to shake hands.
const REPLACEMENT_TIMEOUT: Duration = Duration::from_secs(10);

/// Where an agent's ready handshake stands ([`Driver::read_handshake`]).
enum Handshake {
    /// Not there yet.
    Waiting,
    /// Received, naming the agent's own process.
    Done,
    /// Wrong or malformed: why.
    Failed(String),
}

impl Driver<'_> {
    /// Wait for the ready handshake of every agent in `agents` (their processes are
    /// started). An agent that exits first, sends a bad handshake or none in `timeout`
    /// is recorded `failed-to-start` and frozen (or replaced, with `respawn`). For
    /// `replacements`, success is recorded `respawned` and failure `respawn_failed`,
    /// never retried.
    pub(super) fn start_agents(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agents: &[usize],
        timeout: Duration,
        replacements: bool,
    ) -> anyhow::Result<()> {
        let waiting = Instant::now();
        let deadline = waiting + timeout;
        let mut pending: Vec<usize> = agents.to_vec();
        let mut failed: Vec<(usize, String)> = Vec::new();
        // The process each agent started with: one quarantined meanwhile and replaced
        // (with `respawn`) had its replacement's handshake taken by the respawn itself.
        let started_as: Vec<Option<u32>> = (0..self.scenario.agents.len())
            .map(|a| self.procs.pid(a))
            .collect();
        while !pending.is_empty() {
            for agent in pending.clone() {
                let pid = self.procs.pid(agent);
                if pid.is_none() || pid != started_as[agent] || self.ipc.generation(agent).is_none()
                {
                    // Quarantined while the others started (and maybe replaced).
                    pending.retain(|&a| a != agent);
                    continue;
                }
                match self.read_handshake(recorder, step, agent, replacements)? {
                    Handshake::Waiting => {}
                    Handshake::Done => pending.retain(|&a| a != agent),
                    Handshake::Failed(why) => {
                        failed.push((agent, why));
                        pending.retain(|&a| a != agent);
                    }
                }
            }
            // Quarantined agents (impersonators) are no longer waited for.
            pending.retain(|&a| {
                let pid = self.procs.pid(a);
                pid.is_some() && pid == started_as[a]
            });
            for agent in pending.clone() {
                if self.procs.poll(agent) == Exit::Exited {
                    failed.push((agent, "it exited before its handshake".to_string()));
                    pending.retain(|&a| a != agent);
                }
            }
            if pending.is_empty() {
                break;
            }
            if self.ipc.termination_requested() {
                bail!("interrupted while the agents were starting");
            }
            if Instant::now() >= deadline {
                // Over the network, the relay is up but the agent never answered it.
                let hint = if self.options.network.is_some() {
                    " (over Zenoh: the agent did not connect, or was refused: no valid certificate)"
                } else {
                    ""
                };
                for &agent in &pending {
                    failed.push((
                        agent,
                        format!("no handshake within {:.1} s{hint}", timeout.as_secs_f64()),
                    ));
                }
                break;
            }
            self.ipc
                .wait_done(pending[0], (Instant::now() + LIVENESS_SLICE).min(deadline));
        }
        let started: Vec<usize> = agents
            .iter()
            .copied()
            .filter(|a| !failed.iter().any(|(f, _)| f == a))
            .collect();
        let scanning = Instant::now();
        self.scan_for_intruders(recorder, step, &started)?;
        if !replacements {
            let phases = &mut self.progress.startup_phases;
            phases.handshakes = (scanning - waiting).as_secs_f64();
            phases.intruder_scan = scanning.elapsed().as_secs_f64();
        }
        self.settle_failed_starts(recorder, step, failed, replacements)
    }

    /// Take in what `agent`'s channel holds before its handshake: `Done` once its ready
    /// handshake names its own process (a replacement is then recorded `respawned` and
    /// put back into the formation), `Failed` with why for a handshake that is wrong or
    /// malformed, `Waiting` while there is none yet.
    fn read_handshake(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
        replacements: bool,
    ) -> anyhow::Result<Handshake> {
        let pid = self.procs.pid(agent);
        while let Some(incoming) = self.receive_own(recorder, step, agent)? {
            match incoming.msg {
                Ok(msg) if msg.kind == StateKind::Ready && Some(msg.pid) == pid => {
                    if let Err(e) = self.ipc.update_connections(agent) {
                        tracing::warn!("agent {agent}: {e:#}");
                    }
                    if replacements {
                        recorder.mark_alive(agent);
                        recorder.note_fault(
                            step,
                            agent,
                            FaultKind::Respawned,
                            format!(
                                "replacement process {} takes the slot from the last position",
                                msg.pid
                            ),
                            None,
                        );
                    }
                    return Ok(Handshake::Done);
                }
                Ok(msg) if msg.kind == StateKind::Ready => {
                    let why = format!("its handshake claims process {}, not {pid:?}", msg.pid);
                    return Ok(Handshake::Failed(why));
                }
                Ok(msg) => recorder.note_fault(
                    step,
                    agent,
                    FaultKind::Unsolicited,
                    format!("a {:?} message before its handshake; ignored", msg.kind),
                    None,
                ),
                Err(why) => {
                    recorder.note_fault(
                        step,
                        agent,
                        FaultKind::Malformed,
                        format!("handshake: {why}"),
                        None,
                    );
                    return Ok(Handshake::Failed(format!("a malformed handshake ({why})")));
                }
            }
        }
        Ok(Handshake::Waiting)
    }

    /// Record the agents that did not start (`failed`, with why): a replacement as
    /// `respawn_failed`, its process and channel gone (never retried); any other frozen
    /// where it stands, or replaced with `respawn`.
    fn settle_failed_starts(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        failed: Vec<(usize, String)>,
        replacements: bool,
    ) -> anyhow::Result<()> {
        for (agent, why) in failed {
            if replacements {
                tracing::warn!("agent {agent}: the replacement did not start: {why}");
                self.procs.kill_now(agent);
                self.ipc.close_channel(agent);
                self.ipc.cleanup_dead_nodes();
                recorder.note_fault(step, agent, FaultKind::RespawnFailed, why, None);
            } else {
                self.on_failed_start(recorder, step, agent, &why)?;
            }
        }
        Ok(())
    }

    /// `agent` did not start: frozen where it stands, replaced if `respawn` asks.
    pub(super) fn on_failed_start(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
        why: &str,
    ) -> anyhow::Result<()> {
        tracing::warn!("step {step}: agent {agent} failed to start: {why}");
        // Its process, even if it exited already (and was reaped: an intruder that took
        // its channel may be why).
        let pid = self.procs.pid(agent).or_else(|| self.procs.last_pid(agent));
        self.procs.kill_now(agent);
        // Whoever sat on its channel is named before the channel goes.
        if let Some(pid) = pid {
            for intruder in self.ipc.intruders(agent, pid) {
                self.on_intruder(recorder, step, agent, intruder, "opened the services of")?;
            }
        }
        self.ipc.close_channel(agent);
        self.ipc.cleanup_dead_nodes();
        if recorder.world().alive()[agent] {
            recorder.freeze(Fault {
                agent,
                step,
                kind: FaultKind::FailedToStart,
                detail: format!("the agent process did not start: {why}"),
                detection_ms: None,
            });
        }
        if self.options.respawn {
            self.respawn(recorder, step, agent)?;
        }
        Ok(())
    }

    /// Start a replacement process for `agent` on a channel of its own.
    pub(super) fn respawn(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
    ) -> anyhow::Result<()> {
        let opened = self
            .ipc
            .open_channel(agent)
            .and_then(|_| self.spawn(agent, true));
        if let Err(e) = opened {
            tracing::warn!("agent {agent}: the replacement did not start: {e:#}");
            recorder.note_fault(
                step,
                agent,
                FaultKind::RespawnFailed,
                format!("{e:#}"),
                None,
            );
            return Ok(());
        }
        // The replacement's own failure is recorded, and not retried (no respawn loop).
        self.start_agents(recorder, step, &[agent], REPLACEMENT_TIMEOUT, true)
    }
}
