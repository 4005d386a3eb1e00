//! The agent processes: spawned, watched, killed on request, stopped cleanly, reaped.
//! Dropping [`AgentProcesses`] kills and reaps whatever is still running, so no path out
//! of the coordinator (error, panic) leaves an orphan.

use std::os::fd::BorrowedFd;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use nix::fcntl::{FcntlArg, FdFlag, fcntl};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;

/// Find the `agent` executable: `explicit` if given, else `FORMATION_AGENT_BIN`, else
/// the `agent` file beside the running coordinator.
pub fn locate_agent_binary(explicit: Option<&Path>) -> anyhow::Result<PathBuf> {
    let path = match explicit {
        Some(p) => p.to_path_buf(),
        None => match std::env::var_os("FORMATION_AGENT_BIN") {
            Some(p) => PathBuf::from(p),
            None => std::env::current_exe()
                .context("locating the coordinator executable")?
                .with_file_name("agent"),
        },
    };
    if !path.is_file() {
        bail!(
            "agent executable {} not found (build it with `cargo build -p agent`, or pass --agent-bin)",
            path.display()
        );
    }
    Ok(path)
}

/// Raise this process's open-file limit to its hard limit: the coordinator holds about
/// 26 + 9 file descriptors per agent.
pub fn raise_fd_limit() {
    use nix::sys::resource::{Resource, getrlimit, setrlimit};
    if let Ok((soft, hard)) = getrlimit(Resource::RLIMIT_NOFILE)
        && soft < hard
        && let Err(e) = setrlimit(Resource::RLIMIT_NOFILE, hard, hard)
    {
        tracing::warn!("could not raise the open-file limit from {soft} to {hard}: {e}");
    }
}

/// Mark every open descriptor above stderr close-on-exec, so agents do not inherit the
/// coordinator's iceoryx2 files (iceoryx2 opens them without `O_CLOEXEC`).
fn set_cloexec_on_all_fds() {
    let Ok(dir) = std::fs::read_dir("/proc/self/fd") else {
        return;
    };
    let fds: Vec<i32> = dir
        .flatten()
        .filter_map(|e| e.file_name().to_string_lossy().parse().ok())
        .filter(|fd| *fd > 2)
        .collect();
    for fd in fds {
        // SAFETY: `fd` was listed as open a moment ago; a descriptor closed since then
        // only makes fcntl fail, which is harmless here.
        let borrowed = unsafe { BorrowedFd::borrow_raw(fd) };
        let _ = fcntl(borrowed, FcntlArg::F_SETFD(FdFlag::FD_CLOEXEC));
    }
}

/// How an agent process ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// Still running.
    Running,
    /// Exited (code or signal as text in the log).
    Exited,
}

/// The run's agent processes, by agent index.
pub struct AgentProcesses {
    bin: PathBuf,
    prefix: String,
    children: Vec<Option<Child>>,
    /// Every process started in this run, with its agent.
    spawned: Vec<(u32, usize)>,
}

impl AgentProcesses {
    /// No process yet; `bin` is the agent executable, `prefix` the run's prefix.
    pub fn new(bin: PathBuf, prefix: &str, agents: usize) -> Self {
        Self {
            bin,
            prefix: prefix.to_string(),
            children: (0..agents).map(|_| None).collect(),
            spawned: Vec::new(),
        }
    }

    /// Start agent `agent`'s process (in its own process group, so a Ctrl-C on the
    /// terminal reaches only the coordinator, which then stops the agents cleanly).
    pub fn spawn(&mut self, agent: usize, extra_args: &[String]) -> anyhow::Result<u32> {
        set_cloexec_on_all_fds();
        let child = Command::new(&self.bin)
            .args(["--run", &self.prefix, "--agent", &agent.to_string()])
            .args(extra_args)
            .stdin(Stdio::null())
            .process_group(0)
            .spawn()
            .with_context(|| format!("starting {} for agent {agent}", self.bin.display()))?;
        let pid = child.id();
        self.children[agent] = Some(child);
        self.spawned.push((pid, agent));
        Ok(pid)
    }

    /// The process id of agent `agent`, if it has one.
    pub fn pid(&self, agent: usize) -> Option<u32> {
        self.children[agent].as_ref().map(Child::id)
    }

    /// The agent whose process is or was `pid` in this run, if any.
    pub fn agent_of_pid(&self, pid: u32) -> Option<usize> {
        self.spawned
            .iter()
            .find(|&&(p, _)| p == pid)
            .map(|&(_, agent)| agent)
    }

    /// Whether agent `agent`'s process still runs (reaping it if it exited).
    pub fn poll(&mut self, agent: usize) -> Exit {
        match self.children[agent].as_mut().map(Child::try_wait) {
            Some(Ok(None)) => Exit::Running,
            Some(Ok(Some(status))) => {
                tracing::info!("agent {agent} exited: {status}");
                self.children[agent] = None;
                Exit::Exited
            }
            Some(Err(e)) => {
                tracing::warn!("agent {agent}: cannot query its process: {e}");
                Exit::Running
            }
            None => Exit::Exited,
        }
    }

    /// Send SIGKILL to agent `agent`'s process without reaping it (fault injection: the
    /// coordinator must then notice the death the way it would notice any other).
    pub fn signal_kill(&mut self, agent: usize) -> Option<u32> {
        let pid = self.pid(agent)?;
        kill(Pid::from_raw(pid as i32), Signal::SIGKILL).ok()?;
        Some(pid)
    }

    /// Kill agent `agent` with SIGKILL and reap it.
    pub fn kill_now(&mut self, agent: usize) {
        if let Some(mut child) = self.children[agent].take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }

    /// Agents whose process is running.
    pub fn running(&mut self) -> Vec<usize> {
        (0..self.children.len())
            .filter(|&i| self.poll(i) == Exit::Running)
            .collect()
    }

    /// Wait until every process has exited or `timeout` passes; true if all exited.
    pub fn wait_all(&mut self, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        loop {
            if self.running().is_empty() {
                return true;
            }
            if Instant::now() >= deadline {
                return false;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Stop every process: the caller has already asked them to quit; wait `grace`, then
    /// SIGTERM, then SIGKILL whatever still runs. Every process is reaped.
    pub fn stop_all(&mut self, grace: Duration) {
        if self.wait_all(grace) {
            return;
        }
        for i in self.running() {
            if let Some(pid) = self.pid(i) {
                tracing::warn!("agent {i} did not quit in {grace:?}: sending SIGTERM");
                let _ = kill(Pid::from_raw(pid as i32), Signal::SIGTERM);
            }
        }
        if self.wait_all(Duration::from_secs(2)) {
            return;
        }
        for i in self.running() {
            tracing::warn!("agent {i} ignored SIGTERM: killing it");
            self.kill_now(i);
        }
    }
}

impl Drop for AgentProcesses {
    fn drop(&mut self) {
        for child in self.children.iter_mut().filter_map(Option::take) {
            let mut child = child;
            let _ = kill(Pid::from_raw(child.id() as i32), Signal::SIGTERM);
            let deadline = Instant::now() + Duration::from_millis(500);
            while Instant::now() < deadline {
                if let Ok(Some(_)) = child.try_wait() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(5));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}
