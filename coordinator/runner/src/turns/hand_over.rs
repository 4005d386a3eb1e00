//! The hand-over from one turn to the next ([`super::WaitMode`]): sleeping on both sides,
//! or spinning. When spinning, the agent whose turn comes next is told so (event
//! `prepare`) and polls its world; its turn is then granted by publishing the world alone,
//! with no ring, if it comes within [`PREPARED_GRANT_WINDOW`] of the notice; and the
//! coordinator spins on the agent's state for up to [`SPIN_BUDGET`] before it sleeps.

use std::time::Instant;

use shared::control::vocabulary::TurnMode;
use wire::PREPARED_GRANT_WINDOW;

use super::options::SPIN_BUDGET;
use crate::agents::AgentProcesses;
use crate::ipc::CoordinatorIpc;

/// How many agents of the next group are told their turn comes next (`--wait spin`).
/// Each polls its world on a core of its own while the group before computes, so more
/// pollers take cores from the group: measured on 2 vCPUs with `coordinator bench
/// --loop-scenario scenarios/swarm200-parallel.toml` (parallel turns), the step loop
/// took 2.48-2.66 s telling the whole next group, 1.66-1.74 s telling one agent, and
/// 1.71-2.14 s sleeping (`--wait block`). With sequential turns a group is one agent.
const PREPARED_AT_MOST: usize = 1;

/// The hand-over's state: whether it spins, and which agent was told its turn comes next.
pub(super) struct HandOver {
    /// Spin rather than sleep while a turn is short.
    spin: bool,
    /// When each agent was last told its turn comes next, and its process then: its turn
    /// is granted without a ring if it comes soon enough.
    told: Vec<Option<(Instant, Option<u32>)>>,
}

impl HandOver {
    /// The hand-over of a run of `agents` agents; `spin`: spinning, else sleeping.
    pub(super) fn new(spin: bool, agents: usize) -> Self {
        Self {
            spin,
            told: vec![None; agents],
        }
    }

    /// Whether to look at the state of a turn granted at `granted` again at once rather
    /// than sleep: spinning, within [`SPIN_BUDGET`].
    pub(super) fn keeps_spinning(&self, granted: Instant) -> bool {
        self.spin && granted.elapsed() < SPIN_BUDGET
    }

    /// Who is told to come next after group `k` of `groups`: the next group of the step,
    /// or after the last one (sequential turns, spinning), the first live agent (the
    /// next step's first turn).
    pub(super) fn next_after(
        &self,
        groups: &[Vec<usize>],
        k: usize,
        turns: TurnMode,
        alive: &[bool],
    ) -> Vec<usize> {
        match groups.get(k + 1) {
            Some(g) => g.clone(),
            None if self.spin && turns == TurnMode::Sequential => {
                alive.iter().position(|a| *a).into_iter().collect()
            }
            None => Vec::new(),
        }
    }

    /// Tell the first live agent of `next` not in `group` that its turn comes next
    /// (spinning only); it polls its world while `group` computes. One only: every
    /// poller takes a core from the group ([`PREPARED_AT_MOST`]).
    pub(super) fn tell_next(
        &mut self,
        ipc: &CoordinatorIpc,
        procs: &AgentProcesses,
        alive: &[bool],
        group: &[usize],
        next: &[usize],
    ) {
        if !self.spin {
            return;
        }
        let ahead = next
            .iter()
            .copied()
            .filter(|&a| alive[a] && !group.contains(&a))
            .take(PREPARED_AT_MOST);
        for agent in ahead {
            if ipc.notify_prepare(agent).is_ok() {
                self.told[agent] = Some((Instant::now(), procs.pid(agent)));
            }
        }
    }

    /// Whether `agent`, whose process is now `pid`, was told its turn comes next so
    /// lately that it is still polling its world ([`PREPARED_GRANT_WINDOW`]): then
    /// publishing its world is the grant. The mark is used up.
    pub(super) fn polls_world(&mut self, agent: usize, pid: Option<u32>) -> bool {
        self.told
            .get_mut(agent)
            .and_then(Option::take)
            .is_some_and(|(at, told)| told == pid && at.elapsed() < PREPARED_GRANT_WINDOW)
    }

    /// At the end of a step, spinning: take in the `done` rings left pending. Once a
    /// step, not once a group: iceoryx2 sends one datagram per ring only while the
    /// listener has been drained since, so rings left pending cost neither the agents a
    /// send nor the coordinator a receive per turn.
    pub(super) fn end_step(&self, ipc: &CoordinatorIpc) {
        if self.spin {
            ipc.drain_done();
        }
    }
}
