//! Cleaning up after a run's dead nodes (killed agents), without the hang iceoryx2's own
//! cleanup can fall into.
//!
//! iceoryx2 0.10 creates a shared-memory segment with `shm_open` and sizes it afterwards.
//! A process killed in between leaves a file of size zero, and `Node::try_cleanup_dead_nodes`,
//! opening that file to detach the dead port, waits for it to be sized with no deadline.
//! So the cleanup here lists the dead nodes, waits until their processes are gone, removes
//! the empty files no process holds open ([`wire::remove_abandoned_shm_files`]), then
//! cleans those nodes one by one.

use std::time::{Duration, Instant};

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;

use crate::procfs::ProcStat;

/// How long [`cleanup_dead_nodes`] waits for a dead node's process to finish exiting
/// (it is killed already; an exiting process closes its files one by one).
const PROCESS_EXIT_WAIT: Duration = Duration::from_secs(1);

/// Remove the resources of the dead nodes of `node`'s run (prefix `prefix`); returns how
/// many nodes were cleaned.
pub fn cleanup_dead_nodes(node: &Node<ipc::Service>, prefix: &str) -> usize {
    let mut dead = Vec::new();
    let _ = Node::<ipc::Service>::list(node.config(), |state| {
        if let NodeState::Dead(view) = state {
            dead.push(view);
        }
        CallbackProgression::Continue
    });
    if dead.is_empty() {
        return 0;
    }
    for view in &dead {
        if let Some(pid) = view
            .id()
            .pid::<ipc::Service>()
            .ok()
            .and_then(|p| u32::try_from(p.value()).ok())
        {
            wait_until_gone(pid, PROCESS_EXIT_WAIT);
        }
    }
    let abandoned = wire::remove_abandoned_shm_files(prefix);
    if abandoned > 0 {
        tracing::info!("removed {abandoned} segment(s) a killed process left unfinished");
    }
    dead.into_iter()
        .filter(|view| view.clone().try_remove_stale_resources().is_ok())
        .count()
}

/// Wait until process `pid` has exited (gone, or a zombie: its files are closed), at most
/// `timeout`.
fn wait_until_gone(pid: u32, timeout: Duration) {
    let deadline = Instant::now() + timeout;
    while Instant::now() < deadline {
        match ProcStat::read(pid) {
            Some(stat) if !stat.zombie() => std::thread::sleep(Duration::from_millis(1)),
            _ => return,
        }
    }
}
