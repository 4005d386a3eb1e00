//! The integration tests of the formation controller, in one binary: real agent
//! processes over real shared memory, real signals, real files, the bad-input corpus.
//! One module per concept; `support` is what they share.
//!
//! Two tiers:
//! - the **fast tier**, `cargo test --workspace` (the README's test command): any user,
//!   nothing installed beyond the toolchain; every behaviour checked once, on the
//!   smallest input that shows it;
//! - the **system tier**, the feature `system` (`cargo test --workspace --all-features`,
//!   as root): adds what needs root (the sandbox and its attacks, hosts in network
//!   namespaces, the user `nobody`) or is heavy (1 000 agents, the seeded kill
//!   campaigns, agents over Zenoh), in the module `system` (run it alone with the filter
//!   `system::`). A test of it that needs root and is started without says so in one
//!   line ([`support::system::require_root`]).

mod support;

mod architecture_paths;
mod bad_input;
mod bad_maps;
mod bench;
mod bound;
mod compare;
mod controller_protocol;
mod faults;
mod file_imports;
mod file_sizes;
mod multiprocess;
mod outputs;
mod parallel_kill;
mod plotting_apart;
mod resume;
mod rogue;
mod rogue_parallel;
mod rogue_processes;
mod run_log;
mod slow_agents;
#[cfg(feature = "system")]
mod system;
