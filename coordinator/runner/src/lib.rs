//! Running a formation over agent processes: the coordinator's side of a run. It spawns
//! the agents (sandboxed or trusted, over iceoryx2 or Zenoh), drives the step loop of
//! `shared` with them as the source of moves, checks every move with its own safety
//! monitor, keeps the crash-safe run log and writes the run folder.
//!
//! - [`turns`]: the run itself: its options, its resources behind one handle, the
//!   driver that grants turns and collects answers, the judge, the step report;
//! - [`agents`], [`ipc`], [`network`], [`netns`]: the agent processes and how they are
//!   reached (shared memory, Zenoh, a second host in a network namespace);
//! - `monitor`: the independent safety monitor (parry's geometry, not `shared`'s);
//! - [`run_log`]: the crash-safe MCAP log, and [`resume`] from it;
//! - [`output`]: the run folder's files;
//! - [`loaded`]: a scenario loaded, checked and planned;
//! - [`stale_runs`], [`dead_nodes`], [`procfs`]: what crashed runs left behind, and the
//!   processes' own figures;
//! - [`names`]: names given on a command line read into what they name;
//! - [`stats`]: the small statistics the reports share; [`logging`]: the log's set-up.

mod agent_uids;
pub mod agents;
pub mod dead_nodes;
mod error;
mod force_quit;
pub mod ipc;
pub mod loaded;
pub mod logging;
mod monitor;
pub mod names;
pub mod netns;
pub mod network;
pub mod output;
pub mod procfs;
pub mod resume;
pub mod run_log;
pub mod stale_runs;
pub mod stats;
pub mod turns;

pub use error::CliError;
