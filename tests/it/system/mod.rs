//! The system tier: what needs root or is heavy. Compiled with the feature `system`
//! (`cargo test --workspace --all-features`, as root); `-- system::` runs it alone.
//! Each module extends the fast tier's module of the same concept with what the fast
//! tier leaves out.

mod bench;
mod faults;
mod multiprocess;
mod network;
mod network_security;
mod run_log;
mod sandbox;
