//! What a run holds while it goes, opened by [`RunBuilder`] and released by the
//! [`RunHandle`]: the run's private folder, its agents' user ids, the agent processes and
//! their control group, the channels, the Zenoh router. However the run ends (its last
//! step, an error, a panic), they are released in one order: the agents stopped (and
//! what they left in their control group killed), the router closed, the channels shut
//! down and the run's files removed, the folder last.

use std::time::{Duration, Instant};

use shared::world::scenario::Scenario;
use wire::cgroup::CgroupDirs;
use wire::{RunPrefix, RunRoot};

use super::launch::AgentLaunch;
use super::options::{RunOptions, SandboxOptions};
use crate::agent_uids::AgentUids;
use crate::agents::{self, AgentProcesses, StartGate};
use crate::force_quit::RunGuard;
use crate::ipc::CoordinatorIpc;
use crate::network::Router;

/// How long a stopping agent has between SIGTERM and SIGKILL, and the run's control group
/// to empty.
const STOP_GRACE: Duration = Duration::from_secs(2);

/// Opens the resources of a run of `scenario` as `options` has it ([`RunBuilder::open`]).
pub(super) struct RunBuilder<'a> {
    /// The scenario run.
    pub(super) scenario: &'a Scenario,
    /// How it is run.
    pub(super) options: &'a RunOptions,
}

/// A run's resources, open; released in order by [`RunHandle::release`], or when dropped
/// (a run that failed: the run's files are then removed without the channels' shut-down).
/// The fields are dropped in the order they are declared.
pub(super) struct RunHandle {
    /// The agent processes: stopped first.
    pub(super) agents: RunAgents,
    /// The Zenoh router, when agents go over the network: closed next.
    router: RouterHandle,
    /// The channels of every agent.
    pub(super) ipc: CoordinatorIpc,
    /// The run's files in /dev/shm and its folder, removed after the channels are gone.
    files: RunFiles,
    /// The agents started before the channels existed, waiting behind their gate.
    pub(super) early: Option<EarlyStart>,
    /// How an agent's process is started.
    pub(super) launch: AgentLaunch,
    /// Until the run is released, a second interrupt removes what it holds and leaves.
    _forced_exit_cleans: RunGuard,
    /// The sandboxed agents' user ids, claimed until the run ends.
    _uids: Option<AgentUids>,
    /// The run's private folder, removed last.
    _root: RunRoot,
}

/// The agents started before the run's channels existed, waiting behind a gate
/// ([`crate::agents::StartGate`]) that the driver opens
/// when the run's steps begin.
pub(super) struct EarlyStart {
    /// The gate they wait behind.
    pub(super) gate: StartGate,
    /// The agents whose process could not be started, and why.
    pub(super) failed: Vec<(usize, String)>,
    /// How long starting them took, seconds.
    pub(super) spawn_s: f64,
}

/// The agent processes of a run and their control group: stopped when dropped, what
/// they left in the group killed, the group removed.
pub(super) struct RunAgents {
    /// The processes (dropped before the group: its sweep empties the group).
    pub(super) procs: AgentProcesses,
    /// The run's control group, removed once empty.
    cgroup: RunCgroup,
}

impl Drop for RunAgents {
    fn drop(&mut self) {
        self.procs.stop_all(STOP_GRACE);
    }
}

/// The run's control group for its sandboxed agents, if it has one: removed when dropped.
struct RunCgroup(Option<CgroupDirs>);

impl Drop for RunCgroup {
    fn drop(&mut self) {
        if let Some(group) = &self.0
            && let Err(e) = group.remove(STOP_GRACE)
        {
            tracing::warn!("the run's control group: {e}");
        }
    }
}

/// The run's Zenoh router, if it has one: closed when dropped.
struct RouterHandle(Option<Router>);

impl Drop for RouterHandle {
    fn drop(&mut self) {
        if let Some(router) = self.0.take() {
            router.close();
        }
    }
}

/// The run's files in /dev/shm and its folder: removed when dropped, unless the channels
/// were shut down (which removes them).
struct RunFiles {
    /// The run's prefix.
    prefix: String,
    /// Whether they are still to be removed.
    armed: bool,
}

impl Drop for RunFiles {
    fn drop(&mut self) {
        if self.armed {
            crate::stale_runs::remove_run_files(&self.prefix);
        }
    }
}

impl RunBuilder<'_> {
    /// Open the run's resources, the agents `alive` marks started (behind a gate until
    /// their channels exist, unless over a network). Whatever fails releases what was
    /// opened before it.
    pub(super) fn open(self, alive: &[bool]) -> anyhow::Result<RunHandle> {
        let (scenario, options) = (self.scenario, self.options);
        let n = scenario.agents.len();
        let bin = agents::locate_agent_binary(options.agent_bin.as_deref())?;
        agents::raise_fd_limit(n)?;
        crate::stale_runs::clean_stale_runs();
        // No other run on this machine uses it, and no one can predict it.
        let prefix = RunPrefix::new_random()?.to_string();
        // The run's private folder, made before anything else of the run (a folder
        // already there is refused).
        let root = RunRoot::create(&prefix)?;
        // Agents of different runs are different users: this run's ids.
        let uids = options
            .sandbox
            .map(|s| AgentUids::claim(s.first_uid, n))
            .transpose()?;
        let sandbox = claimed_sandbox(options.sandbox, uids.as_ref(), n);
        let files = RunFiles {
            prefix: prefix.clone(),
            armed: true,
        };
        // The scenario as run, for the agents to read at start-up.
        let mission_digest = wire::write_mission(&prefix, scenario)?;
        let cgroup = sandbox.and_then(|_| sandbox_cgroup(&prefix));
        let mut agents = RunAgents {
            procs: AgentProcesses::new(bin, &prefix, n).with_cgroup(cgroup.clone()),
            cgroup: RunCgroup(cgroup),
        };
        let launch = AgentLaunch {
            faults: options.faults.clone(),
            mission_digest,
            sandbox,
            network: None,
            run_cgroup: agents.cgroup.0.is_some(),
        };
        // The agents start now, while this process has few open files for each start to
        // copy, and wait behind a gate until their channels exist ([`StartGate`]). Over a
        // network their relays need the router's settings first: they start later.
        let early = match options.network {
            Some(_) => None,
            None => start_early(&launch, &mut agents.procs, alive),
        };
        let ipc = CoordinatorIpc::create(&prefix, scenario, options.wake)?;
        let forced_exit_cleans = RunGuard::new(&prefix, agents.cgroup.0.clone());
        let router = RouterHandle(
            options
                .network
                .as_ref()
                .map(|network| Router::open(network, n, root.path()))
                .transpose()?,
        );
        // Relays are told the network as the router opened it (the run's own TLS folder).
        let launch = AgentLaunch {
            network: router.0.as_ref().map(Router::options).cloned(),
            ..launch
        };
        Ok(RunHandle {
            agents,
            router,
            ipc,
            files,
            early,
            launch,
            _forced_exit_cleans: forced_exit_cleans,
            _uids: uids,
            _root: root,
        })
    }
}

impl RunHandle {
    /// The run's prefix (every resource of the run starts with it).
    pub(super) fn prefix(&self) -> &str {
        &self.files.prefix
    }

    /// Stop the agents (each told to quit first) and release everything, in order: the
    /// error of the channels' shut-down, if any.
    pub(super) fn release(self) -> anyhow::Result<()> {
        let RunHandle {
            mut agents,
            router,
            ipc,
            mut files,
            ..
        } = self;
        for i in agents.procs.running() {
            let _ = ipc.notify_quit(i);
        }
        drop(agents);
        drop(router);
        // The shut-down removes the run's files itself.
        files.armed = false;
        ipc.shut_down()
    }
}

/// The sandbox settings as the run claimed them: agent `i` runs as user `uids.first() +
/// i`, which is `sandbox.first_uid + i` unless another run or a live process held those.
fn claimed_sandbox(
    sandbox: Option<SandboxOptions>,
    uids: Option<&AgentUids>,
    agents: usize,
) -> Option<SandboxOptions> {
    let (sandbox, uids) = (sandbox?, uids?);
    if uids.first() != sandbox.first_uid {
        tracing::info!(
            "agents' user ids {} to {} (from {}: taken by another run or a live process)",
            uids.first(),
            u64::from(uids.first()) + agents as u64 - 1,
            sandbox.first_uid
        );
    }
    Some(SandboxOptions {
        first_uid: uids.first(),
        ..sandbox
    })
}

/// Start every agent `alive` marks behind a new gate. Each fails alone: its failure is
/// handed to the driver, which freezes or replaces it. Without a gate (no pipe to be
/// had), none: the driver starts them once the channels exist.
fn start_early(
    launch: &AgentLaunch,
    procs: &mut AgentProcesses,
    alive: &[bool],
) -> Option<EarlyStart> {
    let spawning = Instant::now();
    let gate = match StartGate::new() {
        Ok(gate) => gate,
        Err(e) => {
            tracing::warn!("{e:#}: the agents start once their channels exist");
            return None;
        }
    };
    let mut failed = Vec::new();
    for (agent, _) in alive.iter().enumerate().filter(|(_, a)| **a) {
        // A fresh run's channels start at generation 0, and so do a resumed run's.
        let args = launch.args(agent, false, 0);
        if let Err(e) = procs.spawn_behind(agent, &args, &gate) {
            failed.push((agent, format!("its process could not be started: {e:#}")));
        }
    }
    Some(EarlyStart {
        gate,
        failed,
        spawn_s: spawning.elapsed().as_secs_f64(),
    })
}

/// The run's control group for its sandboxed agents, made; `None` (with a warning) where
/// the machine's cgroups cannot be used: the agents are then bounded by their users'
/// process limits only.
fn sandbox_cgroup(prefix: &str) -> Option<CgroupDirs> {
    let made = CgroupDirs::for_run(prefix).and_then(|group| {
        group.create()?;
        Ok(group)
    });
    match made {
        Ok(group) => Some(group),
        Err(e) => {
            tracing::warn!(
                "no control groups for the sandboxed agents ({e}): only their process limits hold"
            );
            None
        }
    }
}
