//! The run's control groups: one per sandboxed agent, below one of the run, so that an
//! agent's processes are bounded (processes, memory, CPU) and are all killed through their
//! group, whatever pids or sessions they took.
//!
//! Two layouts are handled. Pure cgroup v2 (`/sys/fs/cgroup/cgroup.controllers`
//! exists): one tree, the limits `pids.max`, `memory.max`, `cpu.max`, and `cgroup.kill`.
//! The hybrid layout (cgroup v1 controllers under `/sys/fs/cgroup/<controller>`, an
//! unified v2 tree at `/sys/fs/cgroup/unified` with no controllers): the limits in v1's
//! `pids`, `memory` and `cpu` trees, and the v2 tree for `cgroup.kill` alone; without a
//! v2 tree, every process listed is killed until none is left.

use std::io::Write as _;
use std::os::fd::{AsRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Where the cgroup file systems are mounted.
const CGROUP_ROOT: &str = "/sys/fs/cgroup";

/// Limits of one agent's group.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Processes and threads at most (`pids.max`).
    pub pids_max: u32,
    /// Memory at most, in MiB (`memory.max`).
    pub memory_mib: u64,
    /// CPU at most, in percent of one core (`cpu.max`).
    pub cpu_percent: u32,
}

impl Default for Limits {
    /// 64 tasks, 512 MiB, one core.
    fn default() -> Self {
        Self {
            pids_max: 64,
            memory_mib: 512,
            cpu_percent: 100,
        }
    }
}

/// Why a group could not be made, joined or killed.
#[derive(Debug, thiserror::Error)]
pub enum CgroupError {
    /// No cgroup file system that can hold the groups (not Linux, not mounted, no
    /// `pids` controller).
    #[error("no usable cgroup file system under {CGROUP_ROOT}")]
    Unavailable,
    /// A cgroup file or folder could not be made, written or read.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What failed.
        #[source]
        source: std::io::Error,
    },
    /// Processes were still in the run's groups after they were killed.
    #[error("{left} processes of the run still in its groups after {waited:?}")]
    Survivors {
        /// How many.
        left: usize,
        /// How long they were given.
        waited: Duration,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> CgroupError + '_ {
    move |source| CgroupError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The folders of one group: where its limits are written and its processes listed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CgroupDirs {
    /// Where `pids` is limited (v2: the group).
    pids: PathBuf,
    /// Where `memory` is limited, if the controller is there.
    memory: Option<PathBuf>,
    /// Where `cpu` is limited, if the controller is there.
    cpu: Option<PathBuf>,
    /// The v2 group (pure v2, or the hybrid layout's unified tree), if any: `cgroup.kill`.
    unified: Option<PathBuf>,
    /// Whether the layout is pure v2 (the v1 file names otherwise).
    v2: bool,
}

impl CgroupDirs {
    /// The run's groups on this machine, named after `name` (not yet made).
    pub fn for_run(name: &str) -> Result<Self, CgroupError> {
        let root = Path::new(CGROUP_ROOT);
        let folder = format!("formation-{name}");
        if root.join("cgroup.controllers").is_file() {
            let dir = root.join(&folder);
            return Ok(Self {
                pids: dir.clone(),
                memory: Some(dir.clone()),
                cpu: Some(dir.clone()),
                unified: Some(dir),
                v2: true,
            });
        }
        let v1 = |controller: &str| {
            let mount = root.join(controller);
            mount.join("tasks").is_file().then(|| mount.join(&folder))
        };
        let pids = v1("pids").ok_or(CgroupError::Unavailable)?;
        let unified = root.join("unified");
        Ok(Self {
            pids,
            memory: v1("memory"),
            cpu: v1("cpu"),
            unified: unified
                .join("cgroup.procs")
                .is_file()
                .then(|| unified.join(&folder)),
            v2: false,
        })
    }

    /// The group `name` below this one.
    pub fn child(&self, name: &str) -> Self {
        Self {
            pids: self.pids.join(name),
            memory: self.memory.as_ref().map(|d| d.join(name)),
            cpu: self.cpu.as_ref().map(|d| d.join(name)),
            unified: self.unified.as_ref().map(|d| d.join(name)),
            v2: self.v2,
        }
    }

    /// Every folder of the group, each once.
    fn folders(&self) -> Vec<&Path> {
        let mut out: Vec<&Path> = vec![&self.pids];
        for d in [&self.memory, &self.cpu, &self.unified]
            .into_iter()
            .flatten()
        {
            if !out.contains(&d.as_path()) {
                out.push(d);
            }
        }
        out
    }

    /// Make the group (its folders may exist already); in pure v2, let its children be
    /// limited too.
    pub fn create(&self) -> Result<(), CgroupError> {
        for dir in self.folders() {
            match std::fs::create_dir(dir) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(io(dir)(e)),
            }
        }
        if self.v2 {
            // Best effort: a controller the parent does not pass down stays unlimited.
            let control = self.pids.join("cgroup.subtree_control");
            for controller in ["+pids", "+memory", "+cpu"] {
                if let Err(e) = write_file(&control, controller) {
                    tracing::debug!("{e}");
                }
            }
        }
        Ok(())
    }

    /// Write `limits` into the group. The `pids` limit must hold; memory and CPU are set
    /// where their controller is there.
    pub fn limit(&self, limits: &Limits) -> Result<(), CgroupError> {
        write_file(&self.pids.join("pids.max"), &limits.pids_max.to_string())?;
        let bytes = limits.memory_mib.saturating_mul(1 << 20);
        if let Some(dir) = &self.memory {
            let file = if self.v2 {
                "memory.max"
            } else {
                "memory.limit_in_bytes"
            };
            write_file(&dir.join(file), &bytes.to_string())?;
        }
        if let Some(dir) = &self.cpu {
            let period_us = 100_000u64;
            let quota_us = period_us * u64::from(limits.cpu_percent.max(1)) / 100;
            if self.v2 {
                write_file(&dir.join("cpu.max"), &format!("{quota_us} {period_us}"))?;
            } else {
                write_file(&dir.join("cpu.cfs_period_us"), &period_us.to_string())?;
                write_file(&dir.join("cpu.cfs_quota_us"), &quota_us.to_string())?;
            }
        }
        Ok(())
    }

    /// The group's `cgroup.procs` files, opened for writing: a process that writes `0`
    /// into each joins the group (what a child does between fork and exec, where it may
    /// not allocate: see [`join_opened`]).
    pub fn open_procs(&self) -> Result<Vec<OwnedFd>, CgroupError> {
        self.folders()
            .into_iter()
            .map(|dir| {
                let path = dir.join("cgroup.procs");
                std::fs::OpenOptions::new()
                    .write(true)
                    .open(&path)
                    .map(OwnedFd::from)
                    .map_err(io(&path))
            })
            .collect()
    }

    /// The processes in the group and every group below it.
    pub fn processes(&self) -> Vec<u32> {
        let mut pids = Vec::new();
        let mut pending = vec![self.pids.clone()];
        while let Some(dir) = pending.pop() {
            if let Ok(text) = std::fs::read_to_string(dir.join("cgroup.procs")) {
                pids.extend(text.lines().filter_map(|l| l.trim().parse::<u32>().ok()));
            }
            if let Ok(entries) = std::fs::read_dir(&dir) {
                pending.extend(entries.flatten().map(|e| e.path()).filter(|p| p.is_dir()));
            }
        }
        pids.sort_unstable();
        pids.dedup();
        pids
    }

    /// Kill every process in the group and below (SIGKILL), and wait until none is
    /// left, at most `timeout`.
    pub fn kill_all(&self, timeout: Duration) -> Result<(), CgroupError> {
        let kill_file = self
            .unified
            .as_ref()
            .map(|d| d.join("cgroup.kill"))
            .filter(|f| f.is_file());
        let mut left = 0;
        let mut failed = None;
        let emptied = crate::poll_until(timeout, || {
            let pids = self.processes();
            left = pids.len();
            if pids.is_empty() {
                return true;
            }
            match &kill_file {
                // Every process below, at once: none can fork away meanwhile.
                Some(file) => {
                    if let Err(e) = write_file(file, "1") {
                        failed = Some(e);
                        return true;
                    }
                }
                // One by one, round after round: a forking process is bounded by its
                // `pids.max`, so the rounds end.
                None => {
                    for &pid in &pids {
                        // SAFETY: kill(2) with a pid read from the group's own list.
                        unsafe { libc::kill(pid as libc::pid_t, libc::SIGKILL) };
                    }
                }
            }
            false
        });
        match failed {
            Some(e) => Err(e),
            None if emptied => Ok(()),
            None => Err(CgroupError::Survivors {
                left,
                waited: timeout,
            }),
        }
    }

    /// Remove the group and every group below it (kill their processes first), waiting
    /// up to `timeout` for the kernel to let go of them.
    pub fn remove(&self, timeout: Duration) -> Result<(), CgroupError> {
        let deadline = Instant::now() + timeout;
        for top in self.folders() {
            let mut dirs = Vec::new();
            let mut pending = vec![top.to_path_buf()];
            while let Some(dir) = pending.pop() {
                if let Ok(entries) = std::fs::read_dir(&dir) {
                    pending.extend(entries.flatten().map(|e| e.path()).filter(|p| p.is_dir()));
                }
                dirs.push(dir);
            }
            // Deepest first.
            for dir in dirs.iter().rev() {
                let mut last = None;
                let removed =
                    crate::poll_until(deadline.saturating_duration_since(Instant::now()), || {
                        match std::fs::remove_dir(dir) {
                            Ok(()) => true,
                            Err(e) if e.kind() == std::io::ErrorKind::NotFound => true,
                            Err(e) => {
                                last = Some(e);
                                false
                            }
                        }
                    });
                if !removed && let Some(e) = last {
                    return Err(io(dir)(e));
                }
            }
        }
        Ok(())
    }
}

/// Join the groups whose `cgroup.procs` files are `procs` (from
/// [`CgroupDirs::open_procs`]): the calling process writes `0` into each. Safe to call
/// between fork and exec: it only calls write(2).
pub fn join_opened(procs: &[i32]) -> std::io::Result<()> {
    for &fd in procs {
        // SAFETY: write(2) of two static bytes to a descriptor the caller keeps open.
        let written = unsafe { libc::write(fd, b"0\n".as_ptr().cast(), 2) };
        if written < 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// The raw descriptors of `fds`, for [`join_opened`] in a child.
pub fn raw_fds(fds: &[OwnedFd]) -> Vec<i32> {
    fds.iter().map(AsRawFd::as_raw_fd).collect()
}

fn write_file(path: &Path, value: &str) -> Result<(), CgroupError> {
    std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .and_then(|mut f| f.write_all(value.as_bytes()))
        .map_err(io(path))
}
