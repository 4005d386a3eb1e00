//! What a run leaves in shared memory when it cannot finish cleanly: its own files when
//! its coordinator node could not be set up, and whole runs whose coordinator died.

use std::time::Duration;

use iceoryx2::prelude::*;
use wire::{Role, RunPrefix};

use crate::procfs;

/// Remove the files of run `prefix` after its coordinator node could not be set up (no
/// agent was started).
pub fn remove_run_files(prefix: &str) {
    if let Ok(config) = wire::ipc_config(prefix, Role::Coordinator) {
        // SAFETY: no agent of this run was started, and its coordinator node is gone.
        let _ = unsafe { iceoryx2::testing::remove_global_mgmt_segment::<ipc::Service>(&config) };
    }
    let _ = wire::remove_run_root(prefix);
}

/// Remove what crashed runs left behind: every run prefix ([`wire::RunPrefix`]) found in
/// /dev/shm or below the iceoryx2 root whose coordinator process no longer exists. Dead
/// nodes are cleaned through iceoryx2 first; files that no node owns any more (the dead
/// coordinator's services) are removed after. Only this user's files count: another
/// user's (or a symbolic link) is never a leftover of ours. Returns the prefixes cleaned.
pub fn clean_stale_runs() -> Vec<String> {
    use std::os::unix::fs::MetadataExt;
    let root = std::path::PathBuf::from(Config::default().global.root_path().to_string());
    let euid = wire::effective_uid();
    let mut prefixes = std::collections::BTreeSet::new();
    let mut files = Vec::new();
    let mut scan = |dir: &std::path::Path| {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            // `DirEntry::metadata` does not follow a symbolic link.
            let ours = e
                .metadata()
                .is_ok_and(|m| m.uid() == euid && !m.file_type().is_symlink());
            if ours && let Some(prefix) = stale_prefix(&name) {
                prefixes.insert(prefix.to_string());
                files.push(e.path());
            }
        }
    };
    scan(std::path::Path::new("/dev/shm"));
    scan(&root);
    for sub in ["nodes", "services"] {
        scan(&root.join(sub));
    }
    if let Ok(entries) = std::fs::read_dir(root.join("nodes")) {
        for e in entries.flatten().filter(|e| e.path().is_dir()) {
            scan(&e.path());
        }
    }
    for prefix in &prefixes {
        let Ok(config) = wire::ipc_config(prefix, Role::Coordinator) else {
            continue;
        };
        let _ = Node::<ipc::Service>::list(&config, |state| {
            if let NodeState::Dead(view) = state {
                let _ = view.try_remove_stale_resources();
            }
            CallbackProgression::Continue
        });
        // SAFETY: the run's coordinator is gone and its agents exit when it does; nothing
        // uses this prefix any more.
        let _ = unsafe { iceoryx2::testing::remove_global_mgmt_segment::<ipc::Service>(&config) };
    }
    for f in files.iter().filter(|f| f.exists()) {
        let _ = if f.is_dir() {
            std::fs::remove_dir_all(f)
        } else {
            std::fs::remove_file(f)
        };
    }
    prefixes.extend(clean_stale_cgroups());
    if !prefixes.is_empty() {
        tracing::info!("cleaned stale runs {prefixes:?}");
    }
    prefixes.into_iter().collect()
}

/// Kill and remove the control groups of sandboxed runs whose coordinator is gone (one
/// killed with SIGKILL could not remove its own); returns their prefixes.
fn clean_stale_cgroups() -> Vec<String> {
    let mut cleaned = Vec::new();
    let mounts = std::fs::read_dir("/sys/fs/cgroup")
        .into_iter()
        .flatten()
        .flatten();
    let tops = std::iter::once(std::path::PathBuf::from("/sys/fs/cgroup"))
        .chain(mounts.map(|e| e.path()).filter(|p| p.is_dir()));
    for top in tops {
        let Ok(entries) = std::fs::read_dir(&top) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            let Some(prefix) = name.strip_prefix("formation-").and_then(stale_prefix) else {
                continue;
            };
            let prefix = prefix.to_string();
            if cleaned.contains(&prefix) {
                continue;
            }
            if let Ok(group) = wire::cgroup::CgroupDirs::for_run(&prefix) {
                let killed = group.kill_all(Duration::from_secs(2));
                if let Err(e) = killed.and_then(|_| group.remove(Duration::from_secs(2))) {
                    tracing::warn!("stale run {prefix}: its control group: {e}");
                }
            }
            cleaned.push(prefix);
        }
    }
    cleaned
}

/// The run prefix file `name` starts with, if its coordinator process is gone.
fn stale_prefix(name: &str) -> Option<RunPrefix> {
    let prefix = RunPrefix::parse(name)?;
    if procfs::process_exists(prefix.pid()) {
        return None;
    }
    // Its agents may still be on their way out (they leave within a second).
    if processes_serving(prefix.as_str()) {
        return None;
    }
    Some(prefix)
}

/// Whether a process was started for run `prefix` (its command line holds
/// `--prefix <prefix>`).
fn processes_serving(prefix: &str) -> bool {
    let needle: Vec<u8> = [b"--prefix\0".as_slice(), prefix.as_bytes(), b"\0"].concat();
    procfs::any_command_line_holds(&needle)
}
