//! The coordinator's side of the iceoryx2 protocol (see [`shared::wire`]): it creates
//! every service with limits sized for the run, publishes the mission and the world,
//! rings turns, and collects the agents' states.

use std::time::{Duration, Instant};

use anyhow::{Context, anyhow};
use iceoryx2::node::NodeView;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use shared::geometry::Pose;
use shared::scenario::Scenario;
use shared::turn::Body;
use shared::wire::{
    self, AgentState, DONE_SERVICE, EVENT_ECHO, EVENT_QUIT, EVENT_TURN, MISSION_SERVICE, Mission,
    Role, StateKind, WORLD_SERVICE, World,
};

/// A state sample copied out of shared memory.
pub type StateCopy = AgentState;

/// A turn's latency cut at the agent's timestamps (the machine's monotonic clock,
/// [`shared::wire::monotonic_ns`]), microseconds; the three parts add up to the latency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurnSplit {
    /// From ringing the turn to the agent awake: the wake-up of the agent's process.
    pub to_agent_us: f64,
    /// From awake to sending the move: reading the world, computing, writing the move.
    pub in_agent_us: f64,
    /// From the move sent to the coordinator holding it: the coordinator's wake-up.
    pub to_coordinator_us: f64,
}

impl TurnSplit {
    /// The whole round trip, microseconds.
    pub fn total_us(&self) -> f64 {
        self.to_agent_us + self.in_agent_us + self.to_coordinator_us
    }

    /// The split of a turn rung at `granted_ns` and held at `held_ns`, if the agent's
    /// stamps are known and in order.
    pub fn of(granted_ns: u64, state: &AgentState, held_ns: u64) -> Option<Self> {
        let (woke, sent) = (state.woke_ns, state.sent_ns);
        (granted_ns <= woke && woke <= sent && sent <= held_ns).then(|| Self {
            to_agent_us: (woke - granted_ns) as f64 / 1e3,
            in_agent_us: (sent - woke) as f64 / 1e3,
            to_coordinator_us: (held_ns - sent) as f64 / 1e3,
        })
    }
}

/// The coordinator's node and ports for one run.
pub struct CoordinatorIpc {
    prefix: String,
    config: Config,
    node: Node<ipc::Service>,
    mission_pub: Publisher<ipc::Service, Mission, ()>,
    world_pub: Publisher<ipc::Service, World, ()>,
    /// One per agent: a turn reads only the connection of the agent it waits for.
    state_subs: Vec<Subscriber<ipc::Service, AgentState, ()>>,
    done_listener: Listener<ipc::Service>,
    turn_notifiers: Vec<Notifier<ipc::Service>>,
    seq: u64,
}

fn service_name(s: &str) -> anyhow::Result<ServiceName> {
    ServiceName::new(s).map_err(|e| anyhow!("service name {s}: {e:?}"))
}

/// A coordinator-to-agents publish-subscribe service: one publisher, one subscriber per
/// agent, and only the newest sample kept (history 1: an agent that connects late gets
/// the last one).
fn broadcast_service<T: std::fmt::Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
    agents: usize,
) -> anyhow::Result<PubSubFactory<ipc::Service, T, ()>> {
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<T>()
        .max_publishers(1)
        .max_subscribers(agents.max(1))
        .max_nodes(agents + 1)
        .history_size(1)
        .subscriber_max_buffer_size(1)
        .subscriber_max_borrowed_samples(1)
        .create()
        .map_err(|e| anyhow!("creating {name}: {e:?}"))
}

impl CoordinatorIpc {
    /// Create the node and every service of run `prefix` for `agents` agents.
    pub fn create(prefix: &str, agents: usize) -> anyhow::Result<Self> {
        let config = wire::ipc_config(prefix, Role::Coordinator)?;
        let node = NodeBuilder::new()
            .name(&NodeName::new("coordinator").map_err(|e| anyhow!("{e:?}"))?)
            .config(&config)
            .create::<ipc::Service>()
            .map_err(|e| anyhow!("creating the coordinator node: {e:?}"))?;
        // The node made the run's management segment in /dev/shm, open to everyone:
        // private before any other process of the run starts (see the function).
        wire::make_run_files_private(prefix)?;
        // Install iceoryx2's signal handlers now: Ctrl-C and SIGTERM then interrupt waits
        // and are polled with `termination_requested`, so outputs are flushed.
        let _ = node.wait(Duration::ZERO);
        let nodes = agents + 1;

        let mission = broadcast_service::<Mission>(&node, MISSION_SERVICE, agents)?;
        let world = broadcast_service::<World>(&node, WORLD_SERVICE, agents)?;
        let done = node
            .service_builder(&service_name(DONE_SERVICE)?)
            .event()
            .max_notifiers(agents.max(1))
            .max_listeners(1)
            .max_nodes(nodes)
            .create()
            .map_err(|e| anyhow!("creating {DONE_SERVICE}: {e:?}"))?;
        let mut turn_notifiers = Vec::with_capacity(agents);
        let mut state_subs = Vec::with_capacity(agents);
        for i in 0..agents {
            // The ready handshake and one move fit in 2. Two publishers and three nodes:
            // a respawned agent may open the service before its dead predecessor's
            // publisher is cleaned up.
            let state = node
                .service_builder(&service_name(&wire::state_service_name(i))?)
                .publish_subscribe::<AgentState>()
                .max_publishers(2)
                .max_subscribers(1)
                .max_nodes(3)
                .subscriber_max_buffer_size(2)
                .subscriber_max_borrowed_samples(2)
                .create()
                .map_err(|e| anyhow!("creating the state service of agent {i}: {e:?}"))?;
            state_subs.push(
                state
                    .subscriber_builder()
                    .create()
                    .map_err(|e| anyhow!("state subscriber {i}: {e:?}"))?,
            );
            let turn = node
                .service_builder(&service_name(&wire::turn_service_name(i))?)
                .event()
                .max_notifiers(1)
                .max_listeners(1)
                .max_nodes(2)
                .create()
                .map_err(|e| anyhow!("creating the turn service of agent {i}: {e:?}"))?;
            turn_notifiers.push(
                turn.notifier_builder()
                    .default_event_id(EventId::new(EVENT_TURN))
                    .create()
                    .map_err(|e| anyhow!("turn notifier {i}: {e:?}"))?,
            );
        }
        Ok(Self {
            prefix: prefix.to_string(),
            mission_pub: mission
                .publisher_builder()
                .max_loaned_samples(1)
                .create()
                .map_err(|e| anyhow!("mission publisher: {e:?}"))?,
            world_pub: world
                .publisher_builder()
                .max_loaned_samples(1)
                .create()
                .map_err(|e| anyhow!("world publisher: {e:?}"))?,
            state_subs,
            done_listener: done
                .listener_builder()
                .create()
                .map_err(|e| anyhow!("done listener: {e:?}"))?,
            turn_notifiers,
            config,
            node,
            seq: 0,
        })
    }

    /// The run's prefix.
    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    /// The run's iceoryx2 configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Whether SIGINT or SIGTERM reached the coordinator (consumes the request).
    pub fn termination_requested(&self) -> bool {
        self.node
            .wait(Duration::ZERO)
            .is_err_and(|e| matches!(e, iceoryx2::node::NodeWaitFailure::TerminationRequest))
    }

    /// Publish the static scenario (kept as history for agents that connect later).
    pub fn publish_mission(&self, scenario: &Scenario) -> anyhow::Result<()> {
        let sample = self
            .mission_pub
            .loan_uninit()
            .map_err(|e| anyhow!("loaning the mission: {e:?}"))?;
        // Build the 400 kB mission in place, never on the stack.
        let mut sample = sample;
        // SAFETY: the pointer is the sample's own payload slot, valid and exclusive.
        unsafe { Mission::placement_default(sample.payload_mut().as_mut_ptr()) };
        // SAFETY: placement_default initialised every byte of the payload.
        let mut sample = unsafe { sample.assume_init() };
        sample.payload_mut().fill(scenario)?;
        sample
            .send()
            .map_err(|e| anyhow!("sending the mission: {e:?}"))?;
        Ok(())
    }

    /// Connect to subscribers that appeared since the last send and hand them history
    /// (the mission); call after the agents' ready handshake.
    pub fn update_connections(&self) -> anyhow::Result<()> {
        self.mission_pub
            .update_connections()
            .map_err(|e| anyhow!("mission connections: {e:?}"))?;
        self.world_pub
            .update_connections()
            .map_err(|e| anyhow!("world connections: {e:?}"))?;
        Ok(())
    }

    /// Publish the world for `agent`'s turn at `step`; returns its sequence number.
    pub fn publish_world(
        &mut self,
        step: usize,
        agent: usize,
        centre: &Pose,
        bodies: &[Body],
        alive: &[bool],
    ) -> anyhow::Result<u64> {
        self.seq += 1;
        let sample = self
            .world_pub
            .loan_uninit()
            .map_err(|e| anyhow!("loaning a world sample: {e:?}"))?;
        let mut sample = sample;
        // SAFETY: as in `publish_mission`.
        unsafe { World::placement_default(sample.payload_mut().as_mut_ptr()) };
        // SAFETY: placement_default initialised the payload.
        let mut sample = unsafe { sample.assume_init() };
        let w = sample.payload_mut();
        w.seq = self.seq;
        w.step = step as u64;
        w.turn_agent = agent as u32;
        w.centre = (*centre).into();
        w.set_bodies(bodies, alive)?;
        sample
            .send()
            .map_err(|e| anyhow!("sending the world: {e:?}"))?;
        Ok(self.seq)
    }

    /// Ring `agent`'s turn event.
    pub fn notify_turn(&self, agent: usize) -> anyhow::Result<()> {
        self.turn_notifiers[agent]
            .notify()
            .map_err(|e| anyhow!("ringing agent {agent}'s turn: {e:?}"))?;
        Ok(())
    }

    /// Ring `agent`'s echo and wait until `deadline` for its empty answer: the round
    /// trip of a turn without world, planning or move (benchmarks). `None` if no answer
    /// came in time or the agent did not stamp it.
    pub fn echo(&self, agent: usize, deadline: Instant) -> anyhow::Result<Option<TurnSplit>> {
        let rung_ns = wire::monotonic_ns();
        self.turn_notifiers[agent]
            .notify_with_custom_event_id(EventId::new(EVENT_ECHO))
            .map_err(|e| anyhow!("ringing agent {agent}'s echo: {e:?}"))?;
        // An answer sent before the ring is a late one from an earlier echo.
        let answer = self.wait_state(&[agent], deadline, |s| {
            s.state_kind() == Some(StateKind::Echo)
                && s.agent as usize == agent
                && s.sent_ns >= rung_ns
        })?;
        let held_ns = wire::monotonic_ns();
        Ok(answer.and_then(|s| TurnSplit::of(rung_ns, &s, held_ns)))
    }

    /// Ask `agent` to leave cleanly.
    pub fn notify_quit(&self, agent: usize) -> anyhow::Result<()> {
        self.turn_notifiers[agent]
            .notify_with_custom_event_id(EventId::new(EVENT_QUIT))
            .map_err(|e| anyhow!("asking agent {agent} to quit: {e:?}"))?;
        Ok(())
    }

    /// Wait (blocking, no polling) until `want` accepts a state sample of one of
    /// `agents` or `deadline` passes. Every sample received is offered to `want` in
    /// order; the first it accepts is returned as a copy. Returns `None` at the deadline.
    pub fn wait_state(
        &self,
        agents: &[usize],
        deadline: Instant,
        mut want: impl FnMut(&AgentState) -> bool,
    ) -> anyhow::Result<Option<StateCopy>> {
        loop {
            for &agent in agents {
                let sub = self
                    .state_subs
                    .get(agent)
                    .with_context(|| format!("no agent {agent} in this run"))?;
                while let Some(sample) = sub
                    .receive()
                    .map_err(|e| anyhow!("receiving agent {agent}'s state: {e:?}"))?
                {
                    if want(&sample) {
                        return Ok(Some(copy_state(&sample)));
                    }
                }
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            match self.done_listener.timed_wait(|_| {}, deadline - now) {
                Ok(_) => {}
                // A signal: let the caller look at it through `termination_requested`.
                Err(ListenerWaitError::InterruptSignal) => return Ok(None),
                Err(e) => return Err(anyhow!("waiting for agents: {e:?}")),
            }
        }
    }

    /// Remove the resources of this run's dead nodes (killed agents); returns how many
    /// nodes were cleaned.
    pub fn cleanup_dead_nodes(&self) -> usize {
        self.node.try_cleanup_dead_nodes().cleanups as usize
    }

    /// Whether a node named `agent-{agent}` of this run is alive.
    pub fn agent_node_alive(&self, agent: usize) -> bool {
        let want = format!("agent-{agent}");
        let mut alive = false;
        let _ = Node::<ipc::Service>::list(&self.config, |state| {
            if let NodeState::Alive(view) = state
                && view
                    .details()
                    .as_ref()
                    .is_some_and(|d| d.name().to_string() == want)
            {
                alive = true;
                return CallbackProgression::Stop;
            }
            CallbackProgression::Continue
        });
        alive
    }

    /// Drop every port and the node, then remove the run's last shared-memory file.
    /// Call only once every agent process has exited.
    pub fn shut_down(self) -> anyhow::Result<()> {
        let config = self.config.clone();
        let self_prefix = self.prefix.clone();
        let _ = self.node.try_cleanup_dead_nodes();
        drop(self);
        // SAFETY: every process of this run has exited (the caller's contract), so no one
        // else uses the run's global management segment.
        unsafe { iceoryx2::testing::remove_global_mgmt_segment::<ipc::Service>(&config) }
            .map_err(|e| anyhow!("removing the run's management segment: {e:?}"))
            .context("cleaning up shared memory")?;
        wire::remove_run_root(&self_prefix).with_context(|| {
            format!(
                "removing the run's folder {:?}",
                wire::run_root(&self_prefix)
            )
        })?;
        Ok(())
    }
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
                prefixes.insert(prefix);
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
    if !prefixes.is_empty() {
        tracing::info!("cleaned stale runs {prefixes:?}");
    }
    prefixes.into_iter().collect()
}

/// The run prefix file `name` starts with, if its coordinator process is gone.
fn stale_prefix(name: &str) -> Option<String> {
    let prefix = wire::RunPrefix::parse(name)?;
    if std::path::Path::new(&format!("/proc/{}", prefix.pid())).exists() {
        return None;
    }
    // Its agents may still be on their way out (they leave within a second).
    if processes_serving(prefix.as_str()) {
        return None;
    }
    Some(prefix.as_str().to_string())
}

/// Whether a process was started for run `prefix` (its command line holds
/// `--run <prefix>`).
fn processes_serving(prefix: &str) -> bool {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return false;
    };
    let needle: Vec<u8> = [b"--run\0".as_slice(), prefix.as_bytes(), b"\0"].concat();
    entries.flatten().any(|e| {
        std::fs::read(e.path().join("cmdline"))
            .map(|c| c.windows(needle.len()).any(|w| w == needle.as_slice()))
            .unwrap_or(false)
    })
}

fn copy_state(s: &AgentState) -> AgentState {
    let mut c = AgentState {
        seq: s.seq,
        step: s.step,
        compute_ns: s.compute_ns,
        woke_ns: s.woke_ns,
        sent_ns: s.sent_ns,
        agent: s.agent,
        kind: s.kind,
        status: s.status,
        pid: s.pid,
        slot: s.slot,
        best: s.best,
        ..AgentState::default()
    };
    // Same capacity on both sides: this cannot fail.
    let _ = c.set_waypoints(&s.waypoint_points());
    c
}
