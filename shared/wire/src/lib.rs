//! The transport between the coordinator and the agents: messages over iceoryx2 shared
//! memory, the configuration, prefix and private folder of a run, and the agents' test
//! modes. The algorithms it carries are in `shared`, which knows nothing of it.
//!
//! Every message is `#[repr(C)]`, `ZeroCopySend` with an explicit type name, of fixed
//! capacity and without pointers: a sample is written in place in shared memory
//! ([`loan_default`]) and read in place by the other process, with no serialization.
//!
//! Every agent has a channel of its own: three services below the run's prefix (`world`,
//! `turn`, `state`), named by [`AgentServiceNames`] after the agent and the generation of
//! its process; one more service, [`DONE_SERVICE`], is shared by the run. One channel
//! per agent, not services shared by all: every service then has exactly one port on
//! each side, so an agent that opens extra ports can starve no one but itself, a turn
//! reads one connection instead of N, and a replacement process never shares a service
//! with its predecessor.
//!
//! Everything an agent writes is untrusted: the coordinator reads a state sample only
//! through [`AgentState::read_checked`], which copies it out of shared memory and checks
//! every field before anything uses it.
//!
//! One concept per module:
//! - `message`: the messages ([`World`], [`AgentState`]) and their checks;
//! - `mission_file`: the mission (the scenario as run) as a file in the run's private
//!   folder ([`write_mission`], [`read_mission`]);
//! - `services`: the names of an agent's channel and the events rung on it;
//! - `doorbell`: the run's rings as futex words in shared memory ([`Doorbells`]), the
//!   default way to ring those events (iceoryx2's event services the other);
//! - `config`: the iceoryx2 configuration of a run ([`ipc_config`]);
//! - `prefix`: the run prefix ([`RunPrefix`]);
//! - `run_folder`: the run's private folder and files ([`RunRoot`]);
//! - `loan`: the one in-place initialisation of a loaned sample ([`loan_default`]);
//! - `clock`: the machine's monotonic clock ([`monotonic_ns`]);
//! - `poll`: waiting for a state no descriptor signals, with growing pauses
//!   ([`poll_until`]);
//! - `bench`: the latency floor's services and sample ([`BenchPing`]);
//! - [`cgroup`]: the run's control groups, one per sandboxed agent;
//! - [`logging`]: the stderr log, other crates' lines within a budget;
//! - [`misbehave`]: the agents' test modes.
#![warn(missing_docs)]

mod bench;
pub mod cgroup;
mod clock;
mod config;
mod descriptors;
mod doorbell;
mod loan;
pub mod logging;
mod message;
pub mod misbehave;
mod mission_file;
mod poll;
mod prefix;
mod run_folder;
mod services;

pub use bench::{
    BENCH_EVENT_DOORBELL, BENCH_EVENT_SOCKET, BENCH_EVENT_SPIN, BENCH_PING_EVENT,
    BENCH_PING_SERVICE, BENCH_PONG_EVENT, BENCH_PONG_SERVICE, BENCH_SOCKET_DONE, BENCH_SPIN_DONE,
    BenchPing,
};
pub use clock::monotonic_ns;
pub use config::{Role, ipc_config};
pub use descriptors::mark_cloexec_from;
pub use doorbell::{DoorbellError, Doorbells, WakeBy, Woken};
pub use loan::loan_default;
pub use message::{
    AgentState, CapacityError, MAX_COMPUTE_NS, MalformedState, StateKind, StateMsg, WireBody,
    WirePoint, WirePose, World,
};
pub use mission_file::{
    BadMissionDigest, MAX_MISSION_BYTES, MISSION_FILE_NAME, MissionDigest, MissionFileError,
    MissionText, mission_path, read_mission, read_mission_text, write_mission,
};
pub use poll::{FIRST_PAUSE, LONGEST_PAUSE, poll_until};
pub use prefix::{MAX_PREFIX_LEN, PARENT_ENV, PrefixError, RUN_ENV, RunPrefix};
pub use run_folder::{
    RunFilesError, RunRoot, check_run_root, effective_uid, make_run_files_private,
    remove_abandoned_shm_files, remove_run_files_in_shm, remove_run_root, run_root,
};
pub use services::{
    AgentServiceNames, DONE_SERVICE, EVENT_ECHO, EVENT_PREPARE, EVENT_QUIT, EVENT_TURN,
    PREPARE_SPIN, PREPARED_GRANT_WINDOW,
};
