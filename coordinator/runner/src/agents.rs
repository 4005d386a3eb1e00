//! The agent processes: spawned, watched, killed on request, stopped cleanly, reaped.
//! Dropping [`AgentProcesses`] kills and reaps whatever is still running, so no path out
//! of the coordinator (error, panic) leaves an orphan.
//!
//! An agent is an untrusted process, and it may start processes of its own. None of them
//! outlives the run:
//! - each agent leads a process group of its own, and every signal to an agent goes to
//!   the whole group (`killpg`), while the agent is not yet reaped: its pid, the group's
//!   id, cannot name anyone else then. When an agent exits, its group is killed before
//!   the agent is reaped.
//! - the coordinator is a child subreaper (`PR_SET_CHILD_SUBREAPER`): a process whose
//!   parent dies is handed to it, not to init, even if it left the group (`setsid`).
//!   A sandboxed agent's relay is one too, for what its agent leaves: it kills the
//!   agent's control group and reaps every process it adopted before it exits.
//! - every agent gets [`wire::RUN_ENV`]`=<prefix>` in its environment, and whatever it
//!   starts inherits it. When the run ends ([`AgentProcesses::stop_all`], drop), every
//!   live process of the run found through `/proc/PID/environ` is killed, and every
//!   process of the run killed is reaped, by pid (never `waitpid(-1)`: several runs may
//!   share this process, as in the integration tests, and no run touches another's).
//!
//! Limits (a same-user process can always do these; only a cgroup or a PID namespace
//! holds every descendant for sure): a process that both leaves the agent's group and
//! clears or rewrites its environment (or makes itself unreadable with
//! `PR_SET_DUMPABLE`) is not found, and survives the run; a process of the run that
//! exits on its own after its agent is gone stays a zombie of the coordinator (it holds
//! a pid, nothing else) until the coordinator exits.

use std::os::fd::BorrowedFd;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use std::collections::BTreeMap;

use anyhow::{Context, bail};
use nix::errno::Errno;
use nix::fcntl::{FcntlArg, FdFlag, fcntl};
use nix::sys::signal::{Signal, kill, killpg};
use nix::sys::wait::{Id, WaitPidFlag, WaitStatus, waitid, waitpid};
use nix::unistd::Pid;

use crate::procfs::{self, ProcStat, all_processes};

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

/// Open files the coordinator holds per agent, measured with iceoryx2 0.10 (`ls
/// /proc/PID/fd` while 200 agents run: 3 014, 15 per agent exactly): each of the three
/// services of a channel (world, state, turn) keeps its static config, dynamic config and
/// port tag open (9); the world publisher's data segment, the state connection and their
/// counterparts (4); the turn notifier's socket and event segment (2). The mission is a
/// file and the done event one shared service, not services per agent: services per
/// agent for them would cost 25 files per agent, and 1 000 agents would not fit a hard
/// limit of 20 000. One more for the sandbox's claim on the agent's user id.
const FDS_PER_AGENT: u64 = 16;
/// Open files the coordinator holds whatever the number of agents (about 10 measured),
/// with room for the files it opens while it runs (/proc, outputs).
const FDS_BASE: u64 = 64;

/// Raise this process's open-file limit so that a run of `agents` agents fits: the soft
/// limit goes to the hard limit, and when even the hard limit is too small (1 000 agents
/// need 15 064 files) the hard limit is raised
/// too, which a process with `CAP_SYS_RESOURCE` may do up to `fs.nr_open`. A run
/// that still does not fit is refused here, before anything is created: past the limit
/// iceoryx2 cannot open an agent's connections, and the agents would fail their
/// handshakes one by one instead.
pub fn raise_fd_limit(agents: usize) -> anyhow::Result<()> {
    use nix::sys::resource::{Resource, getrlimit, setrlimit};
    let need = FDS_BASE + FDS_PER_AGENT * agents as u64;
    let (soft, hard) = getrlimit(Resource::RLIMIT_NOFILE).context("reading RLIMIT_NOFILE")?;
    let wanted = hard.max(need);
    if soft < wanted && setrlimit(Resource::RLIMIT_NOFILE, wanted, wanted).is_err() && soft < hard {
        // Not allowed to raise the hard limit: the soft one up to it, and see below.
        let _ = setrlimit(Resource::RLIMIT_NOFILE, hard, hard);
    }
    let (soft, hard) = getrlimit(Resource::RLIMIT_NOFILE).context("reading RLIMIT_NOFILE")?;
    if soft < need {
        bail!(
            "{agents} agents need about {need} open files in the coordinator, but its limit is \
             {soft} (hard limit {hard}); raise it (`ulimit -n {need}`, as a user allowed to)"
        );
    }
    Ok(())
}

/// Mark every open descriptor above stderr close-on-exec, so agents do not inherit the
/// coordinator's iceoryx2 files (iceoryx2 opens them without `O_CLOEXEC`).
///
/// One `close_range(3, ~0, CLOSE_RANGE_CLOEXEC)` call (Linux 5.11): the coordinator holds
/// [`FDS_PER_AGENT`] descriptors per agent and marks them before every spawn, so one
/// `fcntl` per descriptor would make starting N agents quadratic (measured on 2 vCPUs:
/// 1 000 agents took 32 s to spawn with one `fcntl` per descriptor; with the one call,
/// 780 agents are spawned and ready in 7 s). Older kernels fall back to one `fcntl` per
/// descriptor listed in `/proc/self/fd`.
fn set_cloexec_on_all_fds() {
    if wire::mark_cloexec_from(3) {
        return;
    }
    for fd in procfs::open_fds().into_iter().filter(|fd| *fd > 2) {
        // SAFETY: `fd` was listed as open a moment ago; a descriptor closed since then
        // only makes fcntl fail, which is harmless here.
        let borrowed = unsafe { BorrowedFd::borrow_raw(fd) };
        let _ = fcntl(borrowed, FcntlArg::F_SETFD(FdFlag::FD_CLOEXEC));
    }
}

/// The gate agents started early wait behind ([`AgentProcesses::spawn_behind`]): a pipe
/// that is their standard input. They pass it when it ends, once [`StartGate::open`]
/// closes its writing end (or this process dies, which closes it too).
///
/// What it is for: every `posix_spawn` copies this process's table of open files and
/// the new program then closes each of them, and the run's channels hold 15 files per
/// agent. Started one after the other once the channels exist, N agents cost O(N^2)
/// closed files (at 1000 agents, 15 000 files for each start); started behind the gate
/// before the channels exist, each start copies a handful.
pub struct StartGate {
    read: std::io::PipeReader,
    write: Option<std::io::PipeWriter>,
}

impl StartGate {
    /// A closed gate.
    pub fn new() -> anyhow::Result<Self> {
        let (read, write) = std::io::pipe().context("the agents' start gate")?;
        Ok(Self {
            read,
            write: Some(write),
        })
    }

    /// The standard input of one more process behind the gate.
    pub fn stdin(&self) -> anyhow::Result<Stdio> {
        let read = self
            .read
            .try_clone()
            .context("the start gate for one more agent")?;
        Ok(Stdio::from(read))
    }

    /// Open the gate: every process behind it goes on.
    pub fn open(&mut self) {
        self.write = None;
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

/// How long the end-of-run sweep may take before it gives up on what it cannot reap.
const SWEEP_TIMEOUT: Duration = Duration::from_secs(2);

/// The run's agent processes, by agent index.
pub struct AgentProcesses {
    bin: PathBuf,
    prefix: String,
    children: Vec<Option<Child>>,
    /// Every process started in this run, with its agent.
    spawned: Vec<(u32, usize)>,
    /// Other processes of the run that were signalled (members of an agent's group, or
    /// found by the sweep), by pid, with their start time: reaped by pid once dead.
    strays: BTreeMap<u32, u64>,
    /// The run's control group, when its agents are sandboxed: the sweep kills whatever
    /// is in it, whatever pid, session or environment it took.
    cgroup: Option<wire::cgroup::CgroupDirs>,
    /// How each agent's last reaped process ended.
    exits: Vec<Option<std::process::ExitStatus>>,
}

impl AgentProcesses {
    /// No process yet; `bin` is the agent executable, `prefix` the run's prefix. Makes
    /// this process a child subreaper (process-wide, idempotent): orphans of the run come
    /// back to it to be reaped.
    pub fn new(bin: PathBuf, prefix: &str, agents: usize) -> Self {
        if let Err(e) = nix::sys::prctl::set_child_subreaper(true) {
            tracing::warn!("cannot become a child subreaper ({e}): an agent's orphans go to init");
        }
        Self {
            bin,
            prefix: prefix.to_string(),
            children: (0..agents).map(|_| None).collect(),
            spawned: Vec::new(),
            strays: BTreeMap::new(),
            cgroup: None,
            exits: vec![None; agents],
        }
    }

    /// The same, the sandboxed agents of the run in `cgroup`.
    pub fn with_cgroup(mut self, cgroup: Option<wire::cgroup::CgroupDirs>) -> Self {
        self.cgroup = cgroup;
        self
    }

    /// Start agent `agent`'s process (in its own process group, so a Ctrl-C on the
    /// terminal reaches only the coordinator, which then stops the agents cleanly, and so
    /// a signal to the agent reaches whatever it started in its group too).
    pub fn spawn(&mut self, agent: usize, extra_args: &[String]) -> anyhow::Result<u32> {
        self.spawn_with_stdin(agent, extra_args, Stdio::null())
    }

    /// [`Self::spawn`], the process waiting behind `gate` (`--gate-stdin`) until it
    /// opens.
    pub fn spawn_behind(
        &mut self,
        agent: usize,
        extra_args: &[String],
        gate: &StartGate,
    ) -> anyhow::Result<u32> {
        let mut args = vec!["--gate-stdin".to_string()];
        args.extend_from_slice(extra_args);
        self.spawn_with_stdin(agent, &args, gate.stdin()?)
    }

    fn spawn_with_stdin(
        &mut self,
        agent: usize,
        extra_args: &[String],
        stdin: Stdio,
    ) -> anyhow::Result<u32> {
        set_cloexec_on_all_fds();
        let mut command = Command::new(&self.bin);
        // Nothing runs between fork and exec, so the standard library starts the
        // process with posix_spawn (no copy of this process's page tables, which with
        // many agents' shared memory mapped made each fork cost tens of milliseconds).
        // The agent asks to die with the coordinator itself, first thing, and exits if
        // the coordinator is already gone ([`wire::PARENT_ENV`]).
        command
            .args(["--prefix", &self.prefix, "--agent", &agent.to_string()])
            .args(extra_args)
            .env(wire::RUN_ENV, &self.prefix)
            .env(wire::PARENT_ENV, std::process::id().to_string())
            .stdin(stdin)
            .process_group(0);
        let child = command
            .spawn()
            .with_context(|| format!("starting {} for agent {agent}", self.bin.display()))?;
        let pid = child.id();
        self.children[agent] = Some(child);
        self.exits[agent] = None;
        self.spawned.push((pid, agent));
        Ok(pid)
    }

    /// How agent `agent`'s last reaped process ended (its exit code, or the signal that
    /// killed it), if one was reaped.
    pub fn exit_status(&self, agent: usize) -> Option<std::process::ExitStatus> {
        self.exits.get(agent).copied().flatten()
    }

    /// The process id of agent `agent`, if it has one.
    pub fn pid(&self, agent: usize) -> Option<u32> {
        self.children[agent].as_ref().map(Child::id)
    }

    /// The newest process started for agent `agent` in this run, running or not.
    pub fn last_pid(&self, agent: usize) -> Option<u32> {
        self.spawned
            .iter()
            .rev()
            .find(|&&(_, a)| a == agent)
            .map(|&(pid, _)| pid)
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
        self.reap_exited(&[agent]);
        match self.children[agent] {
            Some(_) => Exit::Running,
            None => Exit::Exited,
        }
    }

    /// Whether any child of this process (an agent, or an orphan handed to it) has
    /// exited and is not reaped yet, or that cannot be told: one `waitid` call, reaping
    /// nothing. False means every agent's process still runs.
    pub fn any_child_exited(&self) -> bool {
        let flags = WaitPidFlag::WEXITED | WaitPidFlag::WNOHANG | WaitPidFlag::WNOWAIT;
        !matches!(waitid(Id::All, flags), Ok(WaitStatus::StillAlive))
    }

    /// Wait until agent `agent`'s process has exited, without reaping it (the next
    /// [`Self::poll`] does), at most `timeout`; true if it has exited.
    pub fn wait_exited(&self, agent: usize, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        loop {
            if self.children[agent].is_none() || self.has_exited(agent) {
                return true;
            }
            if Instant::now() >= deadline {
                return false;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Whether agent `agent`'s process has exited, without reaping it.
    fn has_exited(&self, agent: usize) -> bool {
        let Some(child) = &self.children[agent] else {
            return false;
        };
        let flags = WaitPidFlag::WEXITED | WaitPidFlag::WNOHANG | WaitPidFlag::WNOWAIT;
        match waitid(Id::Pid(Pid::from_raw(child.id() as i32)), flags) {
            Ok(WaitStatus::StillAlive) => false,
            Ok(_) => true,
            Err(e) => {
                tracing::warn!("agent {agent}: cannot query its process: {e}");
                false
            }
        }
    }

    /// Reap those of `agents` whose process exited, after killing what is left in their
    /// process groups (the unreaped zombie still holds the group's id).
    fn reap_exited(&mut self, agents: &[usize]) {
        let exited: Vec<usize> = agents
            .iter()
            .copied()
            .filter(|&i| self.has_exited(i))
            .collect();
        if exited.is_empty() {
            return;
        }
        self.signal(&exited, Signal::SIGKILL);
        for i in exited {
            if let Some(mut child) = self.children[i].take() {
                match child.wait() {
                    Ok(status) => {
                        tracing::info!("agent {i} exited: {status}");
                        self.exits[i] = Some(status);
                    }
                    Err(e) => tracing::warn!("agent {i}: cannot reap its process: {e}"),
                }
            }
        }
    }

    /// Send `signal` to the process group of each of `agents` that is not reaped yet, and
    /// to the agent itself (in case it left its group). Members of the groups are noted
    /// first, to be reaped once dead (they are handed to this process when their agent
    /// dies). Returns the pids of the agents signalled.
    fn signal(&mut self, agents: &[usize], signal: Signal) -> Vec<u32> {
        let leaders: Vec<u32> = agents.iter().filter_map(|&i| self.pid(i)).collect();
        if leaders.is_empty() {
            return leaders;
        }
        for p in all_processes() {
            if leaders.contains(&p.pgid) && !leaders.contains(&p.pid) {
                self.strays.insert(p.pid, p.start);
            }
        }
        leaders
            .into_iter()
            .filter(|&pid| {
                // An unreaped agent's pid cannot be reused, so neither can its group's id.
                let pid = Pid::from_raw(pid as i32);
                let group = killpg(pid, signal);
                let leader = kill(pid, signal);
                group.is_ok() || leader.is_ok()
            })
            .collect()
    }

    /// Send SIGKILL to agent `agent`'s process group without reaping the agent (fault
    /// injection: the coordinator must then notice the death the way it would notice any
    /// other).
    pub fn signal_kill(&mut self, agent: usize) -> Option<u32> {
        self.signal(&[agent], Signal::SIGKILL).first().copied()
    }

    /// Kill agent `agent`'s process group with SIGKILL and reap the agent.
    pub fn kill_now(&mut self, agent: usize) {
        self.signal(&[agent], Signal::SIGKILL);
        if let Some(mut child) = self.children[agent].take() {
            let _ = child.wait();
        }
    }

    /// Agents whose process is running.
    pub fn running(&mut self) -> Vec<usize> {
        let all: Vec<usize> = (0..self.children.len()).collect();
        self.reap_exited(&all);
        (0..self.children.len())
            .filter(|&i| self.children[i].is_some())
            .collect()
    }

    /// Wait until every process has exited or `timeout` passes; true if all exited.
    pub fn wait_all(&mut self, timeout: Duration) -> bool {
        wire::poll_until(timeout, || self.running().is_empty())
    }

    /// Stop every process: the caller has already asked them to quit; wait `grace`, then
    /// SIGTERM, then SIGKILL whatever still runs. Every agent is reaped, and every other
    /// process of the run is killed and reaped (`sweep`).
    pub fn stop_all(&mut self, grace: Duration) {
        // The sandboxed agents, before their relays' exits orphan them: this process
        // adopts them, and must know them to reap them.
        self.note_cgroup_members();
        if !self.wait_all(grace) {
            let late = self.running();
            for &i in &late {
                tracing::warn!("agent {i} did not quit in {grace:?}: sending SIGTERM");
            }
            self.signal(&late, Signal::SIGTERM);
            if !self.wait_all(Duration::from_secs(2)) {
                for i in self.running() {
                    tracing::warn!("agent {i} ignored SIGTERM: killing it");
                    self.kill_now(i);
                }
            }
        }
        self.sweep();
    }

    /// Kill every live process of the run other than the agents (found by
    /// [`wire::RUN_ENV`] in its environment) and reap every process of the run noted
    /// dead, by pid, until none is left or [`SWEEP_TIMEOUT`] passes. Call once the agents
    /// are reaped: an orphan is handed to this process only once its parent is gone.
    fn sweep(&mut self) {
        let me = std::process::id();
        let deadline = Instant::now() + SWEEP_TIMEOUT;
        loop {
            let agents: Vec<u32> = (0..self.children.len())
                .filter_map(|i| self.pid(i))
                .collect();
            let mut found = 0;
            for p in procfs::live_processes_of_run(&self.prefix) {
                if !agents.contains(&p.pid) {
                    tracing::warn!(
                        "process {} of run {} outlived its agent: killing it",
                        p.pid,
                        self.prefix
                    );
                    let _ = kill(Pid::from_raw(p.pid as i32), Signal::SIGKILL);
                    self.strays.insert(p.pid, p.start);
                    found += 1;
                }
            }
            // What the sandboxed agents hold, found for sure: noted (to be reaped once
            // this process adopts it), then the whole group killed at once.
            let members = self.note_cgroup_members();
            if members > 0
                && let Some(group) = &self.cgroup
                && let Err(e) = group.kill_all(SWEEP_TIMEOUT)
            {
                tracing::warn!("run {}: its control group: {e}", self.prefix);
            }
            found += members;
            self.reap_strays(me);
            if found == 0 && self.strays.is_empty() {
                return;
            }
            if Instant::now() >= deadline {
                tracing::warn!(
                    "run {}: processes {:?} could not be reaped in {SWEEP_TIMEOUT:?}",
                    self.prefix,
                    self.strays.keys().collect::<Vec<_>>()
                );
                return;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Note every process in the run's control group as a stray to reap; how many.
    fn note_cgroup_members(&mut self) -> usize {
        let Some(group) = &self.cgroup else {
            return 0;
        };
        let mut noted = 0;
        for pid in group.processes() {
            if let Some(p) = ProcStat::read(pid) {
                self.strays.insert(pid, p.start);
                noted += 1;
            }
        }
        noted
    }

    /// Reap every noted stray that is now a zombie child of this process (`me`); forget
    /// the ones that are gone (their parent, a process of the run, reaped them).
    fn reap_strays(&mut self, me: u32) {
        self.strays.retain(|&pid, &mut start| {
            let Some(p) = ProcStat::read(pid).filter(|p| p.start == start) else {
                return false;
            };
            if !(p.zombie() && p.ppid == me) {
                // Alive still (dying), or a zombie whose parent, a process of the run, is
                // still dying: handed to this process once that parent is gone.
                return true;
            }
            // Our zombie child, with the start time noted: this very process.
            !matches!(
                waitpid(Pid::from_raw(pid as i32), Some(WaitPidFlag::WNOHANG)),
                Ok(WaitStatus::Exited(..) | WaitStatus::Signaled(..)) | Err(Errno::ECHILD)
            )
        });
    }
}

impl Drop for AgentProcesses {
    fn drop(&mut self) {
        let live = self.running();
        if !live.is_empty() {
            self.signal(&live, Signal::SIGTERM);
            let deadline = Instant::now() + Duration::from_millis(500);
            while Instant::now() < deadline && !self.running().is_empty() {
                std::thread::sleep(Duration::from_millis(5));
            }
            for i in self.running() {
                self.kill_now(i);
            }
        }
        self.sweep();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two processes reading their standard input behind one gate cannot finish before
    /// it opens, and both reach its end when it does: this process's writing end reaches
    /// neither of them (were it inherited, the input would never end and the test would
    /// hang).
    #[test]
    fn every_process_behind_a_gate_goes_on_when_it_opens() {
        let mut gate = StartGate::new().expect("gate");
        let mut children: Vec<Child> = (0..2)
            .map(|_| {
                Command::new("sh")
                    .args(["-c", "cat > /dev/null"])
                    .stdin(gate.stdin().expect("stdin"))
                    .spawn()
                    .expect("sh")
            })
            .collect();
        for child in &mut children {
            assert!(child.try_wait().expect("try_wait").is_none(), "waits");
        }
        gate.open();
        for child in &mut children {
            assert!(child.wait().expect("wait").success());
        }
    }

    /// Once an agent's process has exited and been reaped it has no process any more,
    /// but the newest one started for it is still known (a failed start looks for
    /// intruders on its channel with it); another agent's processes are not its.
    #[test]
    fn the_newest_process_of_an_agent_is_known_after_it_is_reaped() {
        let mut procs = AgentProcesses::new("/bin/true".into(), "fc0x0test_", 2);
        let first = procs.spawn(0, &[]).expect("spawned");
        let second = loop {
            if procs.poll(0) == Exit::Exited {
                assert_eq!(procs.pid(0), None);
                assert_eq!(procs.last_pid(0), Some(first));
                break procs.spawn(0, &[]).expect("spawned again");
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        assert_ne!(first, second);
        assert_eq!(procs.last_pid(0), Some(second));
        assert_eq!(procs.last_pid(1), None);
        assert_eq!(procs.agent_of_pid(first), Some(0));
    }
}
