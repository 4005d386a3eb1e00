//! The turns of a run over agent processes ([`run_scenario`], used by `coordinator run`,
//! `compare` and `bench`): one agent process per agent, turns granted over iceoryx2,
//! every move checked by the safety monitor, faults survived, the run recorded.
//!
//! Liveness: while it waits for a move, the coordinator wakes every
//! 10 ms (`LIVENESS_SLICE`) to ask the kernel whether the agent's process still exists, so a
//! killed agent is noticed within a slice, not at the end of the turn deadline. A dead
//! agent is frozen as an obstacle where it last stood and leaves the formation; with
//! `respawn`, a replacement process takes its place from there.
//!
//! Trust: every agent is another process, so what arrives on its channel is checked
//! before use ([`wire::AgentState::read_checked`]) and judged here:
//! - a sample published by any process but the agent's own is `impersonation`: the
//!   process that sent it, if it is one of the run's agents, is killed and frozen;
//! - a sample that fails the checks is `malformed`; during a turn it ends the turn (the
//!   agent stays where it was);
//! - a move must carry the turn's token (drawn from a generator seeded by the OS random
//!   source when the world is published); anything else, and anything that arrives
//!   between turns, is `unsolicited` and changes nothing;
//! - an agent that exits, fails its handshake or never sends one is `failed-to-start`
//!   and frozen where it starts (or replaced, with `respawn`); the run goes on.
//!
//! If the coordinator itself fails (an error or a panic), its agents are still stopped,
//! the run's shared memory is still removed, and the steps completed so far are returned
//! in [`RunFailure::partial`].

mod answer;
mod deaths;
mod driver;
mod fault_injection;
mod faults;
mod hand_over;
mod judge;
mod lateness;
mod launch;
mod options;
mod outcome;
mod run;
mod run_handle;
mod startup;
mod step_report;
mod turn;

pub use fault_injection::FaultInjection;
pub use options::{
    RunOptions, SPIN_BUDGET, STARTUP_PER_AGENT, SandboxOptions, WaitMode, WakeMode, running_as_root,
};
pub use outcome::TurnSample;
pub use outcome::{RunFailure, RunOutcome};
pub use run::{run_scenario, run_scenario_with};
pub use step_report::{BetweenSteps, PROGRESS_TARGET};

pub use crate::network::NetworkOptions;
