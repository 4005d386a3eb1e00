//! The rings between the coordinator and the agents: "your turn" (and "you are next",
//! "quit") one way, "my state is published" the other, by the run's doorbells or by
//! iceoryx2 events ([`WakeMode`]).

use std::time::Instant;

use anyhow::Context;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::prelude::*;
use wire::{EVENT_PREPARE, EVENT_QUIT, EVENT_TURN};

use super::CoordinatorIpc;
use crate::turns::WakeMode;

impl CoordinatorIpc {
    /// Ring `agent`'s turn event.
    pub fn notify_turn(&self, agent: usize) -> anyhow::Result<()> {
        self.ring(agent, EVENT_TURN)
            .with_context(|| format!("ringing agent {agent}'s turn"))
    }

    /// Ring `event` for `agent`, if its channel is open.
    pub(super) fn ring(&self, agent: usize, event: usize) -> anyhow::Result<()> {
        let channel = self.channel(agent)?;
        match (self.wake, &channel.turn_notifier) {
            (WakeMode::Doorbell, _) => self.doorbells.ring(agent, event)?,
            (WakeMode::Event, Some(notifier)) => {
                notifier.notify_with_custom_event_id(EventId::new(event))?;
            }
            // A channel of a run rung by events is made with its notifier.
            (WakeMode::Event, None) => {
                anyhow::bail!("agent {agent}'s channel has no turn notifier")
            }
        }
        Ok(())
    }

    /// Tell `agent` its turn comes next, so it spins on its world instead of sleeping
    /// (`--wait spin`).
    pub fn notify_prepare(&self, agent: usize) -> anyhow::Result<()> {
        self.ring(agent, EVENT_PREPARE)
            .with_context(|| format!("ringing agent {agent}'s prepare"))
    }

    /// Take every pending ring off the run's done service without waiting: when the
    /// coordinator spins on the states instead of waiting on the rings, they would pile
    /// up in the listener's buffer.
    pub fn drain_done(&self) {
        if let Some(done_listener) = &self.done_listener {
            let _ = done_listener.try_wait(|_| {});
        }
    }

    /// Ask `agent` to leave cleanly.
    pub fn notify_quit(&self, agent: usize) -> anyhow::Result<()> {
        self.ring(agent, EVENT_QUIT)
            .with_context(|| format!("asking agent {agent} to quit"))
    }

    /// Block (no polling) until `agent` signals a published state (rung by events) or any
    /// agent counts an answer (rung by doorbells: the caller looks at `agent`'s channel
    /// again), or `until` passes; false at the deadline or when a signal interrupted the
    /// wait (look at [`Self::termination_requested`]). A wait that fails (a closed
    /// channel) sleeps until `until` instead, so callers poll at their own pace.
    pub fn wait_done(&self, agent: usize, until: Instant) -> bool {
        match &self.done_listener {
            Some(done_listener) => wait_done_event(done_listener, agent, until),
            None => self.wait_doorbell(agent, until),
        }
    }

    /// [`Self::wait_done`] on the doorbells: until any answer is counted (the caller
    /// looks at `agent`'s channel again) or `until` passes.
    fn wait_doorbell(&self, agent: usize, until: Instant) -> bool {
        let doorbells = &self.doorbells;
        // The counter first: an answer counted after this read ends the sleep at once,
        // one counted before it is on the channel already.
        let seen = doorbells.answers();
        if self
            .channel(agent)
            .is_ok_and(|c| c.state_sub.has_samples().unwrap_or(true))
        {
            return true;
        }
        let now = Instant::now();
        if now >= until {
            return false;
        }
        match doorbells.wait_answer(seen, until - now) {
            wire::Woken::Interrupted => false,
            wire::Woken::Look => Instant::now() < until,
        }
    }
}

/// [`CoordinatorIpc::wait_done`] on iceoryx2 events: until `agent` rings the run's done
/// service or `until` passes.
fn wait_done_event(done_listener: &Listener<ipc::Service>, agent: usize, until: Instant) -> bool {
    let now = Instant::now();
    if now >= until {
        return false;
    }
    // Every agent rings the one done service with its own index; a ring for another
    // agent is taken off and waited past (that agent's state is looked at directly
    // before anyone waits for it, so nothing is lost).
    loop {
        let mut done = false;
        let now = Instant::now();
        if now >= until {
            return false;
        }
        match done_listener.timed_wait(|event| done |= event.id.as_value() == agent, until - now) {
            Ok(_) if done => return true,
            Ok(0) => return Instant::now() < until,
            Ok(_) => continue,
            Err(ListenerWaitError::InterruptSignal) => return false,
            Err(e) => {
                tracing::debug!("waiting for agent {agent}: {e:?}");
                std::thread::sleep(until.saturating_duration_since(Instant::now()));
                return false;
            }
        }
    }
}
