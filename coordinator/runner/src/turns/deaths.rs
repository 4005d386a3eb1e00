//! Deterministic deaths ([`super::FaultInjection::deaths`]): an agent killed before its
//! group's turns are granted, so its death is always detected during its turn, as the
//! reference simulation has it (`shared::run::simulate::simulate_along_with_deaths`).
//!
//! The kill of [`super::FaultInjection::kills`] comes right after the grant instead, and races
//! with the agent's answer: the move may get out first, and the death is then noticed at
//! the next step. Here nothing races: the process is gone before any turn of its group is
//! granted.

use std::time::Duration;

use shared::run::record::{FaultKind, Recorder};

use super::driver::Driver;

/// How long a SIGKILLed agent may take to be gone before the run goes on regardless (its
/// death is then noticed a little later: during its turn, or at the next step).
const DEATH_TIMEOUT: Duration = Duration::from_secs(5);

impl Driver<'_> {
    /// Kill those live agents of `group` that are to die at `step`, and wait until each
    /// process is gone (not reaped: waiting for its turn's answer finds it dead, as for
    /// any agent that dies during its turn). Recorded as a `killed` fault.
    pub(super) fn kill_before_turns(
        &mut self,
        recorder: &mut Recorder<'_>,
        step: usize,
        group: &[usize],
    ) {
        for &agent in group {
            if !self.options.faults.dies_before_turn(agent, step)
                || !recorder.world().alive()[agent]
            {
                continue;
            }
            let Some(pid) = self.procs.signal_kill(agent) else {
                continue;
            };
            if !self.procs.wait_exited(agent, DEATH_TIMEOUT) {
                tracing::warn!(
                    "step {step}: agent {agent} (process {pid}) still there {DEATH_TIMEOUT:?} after SIGKILL"
                );
            }
            recorder.note_fault(
                step,
                agent,
                FaultKind::Killed,
                format!("fault injection: SIGKILL to process {pid} before its group's turns"),
                None,
            );
        }
    }
}
