//! What happens to an agent that dies, stays silent, or uses another agent's channel.

use std::time::Duration;

use shared::control::vocabulary::Kinematics;
use shared::geometry::Point;
use shared::run::record::{FaultKind, Recorder};

use super::driver::Driver;
use super::lateness::{Lateness, Verdict};

impl Driver<'_> {
    /// A sample on `channel_agent`'s channel was published by process `publisher_pid`,
    /// not by the agent's own: the culprit, if it is one of the run's agents, is killed
    /// and frozen.
    pub(super) fn on_impersonation(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        channel_agent: usize,
        publisher_pid: u32,
    ) -> anyhow::Result<()> {
        self.on_intruder(recorder, step, channel_agent, publisher_pid, "published on")
    }

    /// Process `pid` used `channel_agent`'s channel (`how`): recorded against the culprit
    /// agent, which is killed and frozen, or against the channel if it is no agent.
    pub(super) fn on_intruder(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        channel_agent: usize,
        pid: u32,
        how: &str,
    ) -> anyhow::Result<()> {
        let culprit = self.procs.agent_of_pid(pid);
        tracing::warn!(
            "step {step}: process {pid} (agent {culprit:?}) {how} agent {channel_agent}'s channel"
        );
        match culprit {
            Some(c) if recorder.world().alive()[c] && self.procs.pid(c) == Some(pid) => {
                recorder.note_fault(
                    step,
                    c,
                    FaultKind::Impersonation,
                    format!("process {pid} {how} agent {channel_agent}'s channel; killed"),
                    None,
                );
                self.on_death(
                    recorder,
                    step,
                    c,
                    Duration::ZERO,
                    "was killed for impersonation",
                )?;
            }
            // An earlier process of an agent, already killed and recorded.
            Some(_) => {}
            None => recorder.note_fault(
                step,
                channel_agent,
                FaultKind::Impersonation,
                format!("process {pid}, not an agent of this run, {how} this agent's channel"),
                None,
            ),
        }
        Ok(())
    }

    /// Look for processes attached to the channels of `agents` that are not theirs.
    pub(super) fn scan_for_intruders(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agents: &[usize],
    ) -> anyhow::Result<()> {
        for &agent in agents {
            let Some(pid) = self.procs.pid(agent) else {
                continue;
            };
            for intruder in self.ipc.intruders(agent, pid) {
                self.on_intruder(recorder, step, agent, intruder, "opened the services of")?;
            }
        }
        // The shared done service: one notifier per agent process; more is hoarding.
        for pid in self.ipc.done_hoarders() {
            if let Some(culprit) = self.procs.agent_of_pid(pid) {
                self.on_intruder(
                    recorder,
                    step,
                    culprit,
                    pid,
                    "hoarded the done service's ports, as",
                )?;
            }
        }
        Ok(())
    }

    /// Freeze a dead agent, clean its shared-memory resources, and respawn it if asked.
    pub(super) fn on_death(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
        after: Duration,
        how: &str,
    ) -> anyhow::Result<()> {
        let ms = after.as_secs_f64() * 1e3;
        tracing::warn!(
            "step {step}: agent {agent} {how}; frozen as an obstacle ({ms:.1} ms to notice)"
        );
        recorder.freeze_dead(step, agent, format!("the agent process {how}"), ms);
        self.procs.kill_now(agent);
        self.ipc.close_channel(agent);
        let cleaned = self.ipc.cleanup_dead_nodes();
        tracing::info!("cleaned the resources of {cleaned} dead node(s)");
        self.history.forget(agent);
        if self.options.respawn {
            self.respawn(recorder, step, agent)?;
        }
        Ok(())
    }

    /// A live agent missed its deadline: it keeps its place; after too many misses in its
    /// last turns it is declared hung, killed and frozen.
    pub(super) fn on_missed(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
        slot: Point,
    ) -> anyhow::Result<()> {
        let verdict = self.history.record(agent, Lateness::Missed);
        recorder.refuse(
            step,
            agent,
            slot,
            FaultKind::Missed,
            format!(
                "no move within the {:?} turn deadline",
                self.options.turn_deadline
            ),
        );
        if let Verdict::Hung { missed } = verdict {
            let window = self.history.window();
            tracing::warn!(
                "step {step}: agent {agent} missed {missed} of its last {window} turns: killing it"
            );
            recorder.note_fault(
                step,
                agent,
                FaultKind::Hung,
                format!("missed {missed} of its last {window} turns; killed"),
                None,
            );
            self.on_death(recorder, step, agent, Duration::ZERO, "was killed as hung")?;
        }
        Ok(())
    }

    /// A live agent answered later than the slow bound. After too many such answers in
    /// its last turns it is declared slow: this answer is refused (it stays), and it is
    /// killed and frozen; true then.
    pub(super) fn on_late_answer(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        agent: usize,
        slot: Point,
        latency: Duration,
    ) -> anyhow::Result<bool> {
        let bound = match self.scenario.agents.get(agent) {
            Some(spec) => self.options.slow_bound_for(&spec.kinematics),
            None => self.options.slow_bound_for(&Kinematics::Holonomic),
        };
        let turn = if latency > bound {
            Lateness::Slow
        } else {
            Lateness::OnTime
        };
        let Verdict::Slow { late } = self.history.record(agent, turn) else {
            return Ok(false);
        };
        let window = self.history.window();
        tracing::warn!(
            "step {step}: agent {agent} answered {late} of its last {window} turns later than {bound:?}: killing it"
        );
        recorder.refuse(
            step,
            agent,
            slot,
            FaultKind::Slow,
            format!(
                "answered {late} of its last {window} turns later than {bound:?} (this one after {latency:?}); killed"
            ),
        );
        self.on_death(recorder, step, agent, Duration::ZERO, "was killed as slow")?;
        Ok(true)
    }
}
