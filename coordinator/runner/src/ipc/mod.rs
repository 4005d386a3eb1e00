//! The coordinator's side of the iceoryx2 protocol (see [`wire`]): it creates
//! every agent's channel with one port on each side, publishes the worlds (the mission
//! goes to the agents as a file, [`wire::write_mission`]), rings turns, and takes the agents' states in, each checked and tagged with the
//! process that published it.

use std::time::Duration;

use anyhow::Context;
use iceoryx2::node::NodeView;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use iceoryx2_bb_posix::unique_system_id::UniqueSystemId;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha20Rng;
use shared::control::vocabulary::Body;
use shared::geometry::{Pose, Vector};
use shared::world::scenario::Scenario;
use wire::{AgentServiceNames, AgentState, EVENT_TURN, MalformedState, Role, StateMsg, World};

use crate::turns::WakeMode;

mod echo;
mod rings;

/// A turn's latency cut at the agent's timestamps (the machine's monotonic clock,
/// [`wire::monotonic_ns`]), microseconds; the three parts add up to the latency.
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
    pub fn of(granted_ns: u64, state: &StateMsg, held_ns: u64) -> Option<Self> {
        let (woke, sent) = (state.woke_ns, state.sent_ns);
        (granted_ns <= woke && woke <= sent && sent <= held_ns).then(|| Self {
            to_agent_us: (woke - granted_ns) as f64 / 1e3,
            in_agent_us: (sent - woke) as f64 / 1e3,
            to_coordinator_us: (held_ns - sent) as f64 / 1e3,
        })
    }
}

/// One state sample as it arrived on an agent's channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Incoming {
    /// The process that published it, from iceoryx2's connection (the publisher's
    /// unique id embeds its process id), not from anything the sample says; `None` when
    /// the sample could not be received at all.
    pub publisher_pid: Option<u32>,
    /// The checked message, or why it was refused.
    pub msg: Result<StateMsg, MalformedState>,
}

/// What one agent's turn shows it: the formation centre, the agent's own heading when its
/// kinematics has one, and the bodies it sees.
pub struct TurnWorld<'a> {
    /// The formation centre at this step.
    pub centre: &'a Pose,
    /// The agent's heading, `None` for a holonomic agent.
    pub heading_rad: Option<f64>,
    /// Every agent's body.
    pub bodies: &'a [Body],
    /// Which agents are alive.
    pub alive: &'a [bool],
    /// The agents the turn's agent sees (increasing), or every agent when `None`.
    pub visible: Option<&'a [usize]>,
    /// The centre's next poses along its plan that the turn's agent looks ahead to.
    pub ahead: &'a [Pose],
    /// With simultaneous turns: how far each agent moved over the last step (indexed by
    /// agent).
    pub velocities: Option<&'a [Vector]>,
}

/// The turn a world was published for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grant {
    /// The world's sequence number.
    pub seq: u64,
    /// The turn's unpredictable token.
    pub token: u64,
}

/// Every port of one agent's channel, and the services (kept to see who else opened
/// them).
struct Channel {
    generation: u32,
    world_service: PubSubFactory<ipc::Service, World, ()>,
    state_service: PubSubFactory<ipc::Service, AgentState, ()>,
    turn_service: EventFactory<ipc::Service>,
    world_pub: Publisher<ipc::Service, World, ()>,
    state_sub: Subscriber<ipc::Service, AgentState, ()>,
    /// Rung by iceoryx2 events only ([`WakeMode::Event`]).
    turn_notifier: Option<Notifier<ipc::Service>>,
}

/// Nodes a channel's service admits: the coordinator, the agent, and one more, so that
/// a process opening another agent's service is seen ([`CoordinatorIpc::intruders`])
/// rather than silently refused. Ports are one per side whatever the node count.
const CHANNEL_MAX_NODES: usize = 3;

/// Samples an agent's state buffer holds: the handshake and one move. The buffer does
/// not overflow: once full, further samples are refused at the publisher, so the
/// first answer to a turn is the one read.
const STATE_BUFFER: usize = 2;

/// Notifier ports the run's done service admits per agent: the agent's own, its
/// replacements', and room for a misbehaving process to be seen rather than to block an
/// honest one.
const DONE_NOTIFIERS_PER_AGENT: usize = 4;

/// The coordinator's node and every agent's channel for one run.
pub struct CoordinatorIpc {
    prefix: String,
    config: Config,
    node: Node<ipc::Service>,
    /// By agent; `None` once an agent's channel is closed.
    channels: Vec<Option<Channel>>,
    /// Generations used so far, by agent (a new channel takes the next one).
    next_generation: Vec<u32>,
    /// Draws the turns' tokens; seeded from the OS random source.
    tokens: ChaCha20Rng,
    seq: u64,
    /// The run's done service ([`wire::DONE_SERVICE`]): rung by every agent with its
    /// index when the run rings by iceoryx2 events; made either way, so that a process
    /// hoarding its ports is seen.
    done_service: EventFactory<ipc::Service>,
    /// How the run's processes ring each other.
    wake: WakeMode,
    /// The run's doorbells: how the run rings, written there for the agents, and the
    /// rings themselves with [`WakeMode::Doorbell`].
    doorbells: wire::Doorbells,
    /// With [`WakeMode::Event`]: the done service's listener.
    done_listener: Option<Box<Listener<ipc::Service>>>,
}

fn service_name(s: &str) -> anyhow::Result<ServiceName> {
    ServiceName::new(s).with_context(|| format!("service name {s}"))
}

/// A coordinator-to-agent publish-subscribe service: one publisher, one subscriber,
/// only the newest sample kept (history 1: the agent connecting late gets the last one).
fn downlink<T: std::fmt::Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
) -> anyhow::Result<PubSubFactory<ipc::Service, T, ()>> {
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<T>()
        .max_publishers(1)
        .max_subscribers(1)
        .max_nodes(CHANNEL_MAX_NODES)
        .history_size(1)
        .subscriber_max_buffer_size(1)
        .subscriber_max_borrowed_samples(1)
        .create()
        .with_context(|| format!("creating {name}"))
}

/// An event service with one notifier and one listener.
fn event_service(
    node: &Node<ipc::Service>,
    name: &str,
) -> anyhow::Result<EventFactory<ipc::Service>> {
    node.service_builder(&service_name(name)?)
        .event()
        .max_notifiers(1)
        .max_listeners(1)
        .max_nodes(CHANNEL_MAX_NODES)
        .create()
        .with_context(|| format!("creating {name}"))
}

/// The process id embedded in an iceoryx2 unique id.
fn pid_of_id(id: u128) -> u32 {
    u32::try_from(UniqueSystemId::from(id).pid().value()).unwrap_or(0)
}

/// A seed from the OS random source.
fn os_seed() -> anyhow::Result<[u8; 32]> {
    let mut seed = [0u8; 32];
    getrandom::fill(&mut seed).context("reading the OS random source")?;
    Ok(seed)
}

impl Channel {
    fn open(
        node: &Node<ipc::Service>,
        agent: usize,
        generation: u32,
        wake: WakeMode,
    ) -> anyhow::Result<Self> {
        let names = AgentServiceNames::new(agent, generation);
        let world_service = downlink::<World>(node, &names.world)?;
        let state_service = node
            .service_builder(&service_name(&names.state)?)
            .publish_subscribe::<AgentState>()
            .max_publishers(1)
            .max_subscribers(1)
            .max_nodes(CHANNEL_MAX_NODES)
            .enable_safe_overflow(false)
            .subscriber_max_buffer_size(STATE_BUFFER)
            .subscriber_max_borrowed_samples(1)
            .create()
            .with_context(|| format!("creating {}", names.state))?;
        let turn_service = event_service(node, &names.turn)?;
        Ok(Self {
            generation,
            world_pub: world_service
                .publisher_builder()
                .max_loaned_samples(1)
                .create()
                .with_context(|| format!("world publisher of agent {agent}"))?,
            state_sub: state_service
                .subscriber_builder()
                .create()
                .with_context(|| format!("state subscriber of agent {agent}"))?,
            turn_notifier: match wake {
                WakeMode::Event => Some(
                    turn_service
                        .notifier_builder()
                        .default_event_id(EventId::new(EVENT_TURN))
                        .create()
                        .with_context(|| format!("turn notifier of agent {agent}"))?,
                ),
                WakeMode::Doorbell => None,
            },
            world_service,
            state_service,
            turn_service,
        })
    }

    /// Process ids of the live nodes attached to this channel's services.
    fn node_pids(&self) -> Vec<u32> {
        let mut pids = Vec::new();
        let mut add = |state: NodeState<ipc::Service>| {
            if let NodeState::Alive(view) = state {
                pids.push(pid_of_id(view.id().value()));
            }
            CallbackProgression::Continue
        };
        let _ = self.world_service.nodes(&mut add);
        let _ = self.state_service.nodes(&mut add);
        let _ = self.turn_service.nodes(&mut add);
        pids.sort_unstable();
        pids.dedup();
        pids
    }
}

impl CoordinatorIpc {
    /// Create the node and a channel for each of `scenario`'s agents in run `prefix`
    /// (the mission file is written beforehand, [`wire::write_mission`]).
    pub fn create(prefix: &str, scenario: &Scenario, wake: WakeMode) -> anyhow::Result<Self> {
        let agents = scenario.agents.len();
        let config = wire::ipc_config(prefix, Role::Coordinator)?;
        let node = NodeBuilder::new()
            .name(&NodeName::new("coordinator").context("the node's name")?)
            .config(&config)
            .create::<ipc::Service>()
            .context("creating the coordinator node")?;
        // The node made the run's management segment in /dev/shm, open to everyone:
        // private before any other process of the run starts (see the function).
        wire::make_run_files_private(prefix)?;
        // Install iceoryx2's signal handlers now: Ctrl-C and SIGTERM then interrupt waits
        // and are polled with `termination_requested`, so outputs are flushed. Then count
        // them too: the second ends a coordinator stuck where no loop looks.
        let _ = node.wait(Duration::ZERO);
        crate::force_quit::install();
        let done_service = node
            .service_builder(&service_name(wire::DONE_SERVICE)?)
            .event()
            .max_listeners(1)
            // Every agent and every replacement, with room to spare: a process holding
            // more than one is found by `hoarders`.
            .max_notifiers(DONE_NOTIFIERS_PER_AGENT * agents.max(1))
            .max_nodes(DONE_NOTIFIERS_PER_AGENT * agents.max(1) + 1)
            .event_id_max_value(agents.max(1))
            .create()
            .with_context(|| format!("creating {}", wire::DONE_SERVICE))?;
        let wake_by = match wake {
            WakeMode::Doorbell => wire::WakeBy::Doorbells,
            WakeMode::Event => wire::WakeBy::Events,
        };
        let doorbells =
            wire::Doorbells::create(prefix, agents, wake_by).context("the run's doorbells")?;
        let done_listener = match wake {
            WakeMode::Doorbell => None,
            WakeMode::Event => Some(Box::new(
                done_service
                    .listener_builder()
                    .create()
                    .context("the done listener")?,
            )),
        };
        let mut ipc = Self {
            wake,
            doorbells,
            done_listener,
            prefix: prefix.to_string(),
            config,
            node,
            channels: (0..agents).map(|_| None).collect(),
            next_generation: vec![0; agents],
            tokens: ChaCha20Rng::from_seed(os_seed()?),
            seq: 0,
            done_service,
        };
        for agent in 0..agents {
            ipc.open_channel(agent)?;
        }
        Ok(ipc)
    }

    /// Open a new channel for `agent` (closing its old one); returns the channel's
    /// generation, which the agent's process must be given.
    pub fn open_channel(&mut self, agent: usize) -> anyhow::Result<u32> {
        let slot = self
            .next_generation
            .get_mut(agent)
            .with_context(|| format!("no agent {agent} in this run"))?;
        let generation = *slot;
        *slot += 1;
        self.channels[agent] = None;
        // A ring the old process left untaken is not the new one's.
        self.doorbells.clear(agent)?;
        let channel = Channel::open(&self.node, agent, generation, self.wake)?;
        self.channels[agent] = Some(channel);
        Ok(generation)
    }

    /// Close `agent`'s channel (its process is gone for good).
    pub fn close_channel(&mut self, agent: usize) {
        if let Some(c) = self.channels.get_mut(agent) {
            *c = None;
        }
    }

    fn channel(&self, agent: usize) -> anyhow::Result<&Channel> {
        self.channels
            .get(agent)
            .and_then(Option::as_ref)
            .with_context(|| format!("agent {agent} has no open channel"))
    }

    /// The run's prefix.
    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    /// Whether SIGINT or SIGTERM reached the coordinator (consumes the request).
    pub fn termination_requested(&self) -> bool {
        self.node
            .wait(Duration::ZERO)
            .is_err_and(|e| matches!(e, iceoryx2::node::NodeWaitFailure::TerminationRequest))
    }

    /// Connect to `agent`'s subscriber that appeared since the last send; call after its
    /// ready handshake.
    pub fn update_connections(&self, agent: usize) -> anyhow::Result<()> {
        let c = self.channel(agent)?;
        c.world_pub
            .update_connections()
            .with_context(|| format!("world connections of agent {agent}"))?;
        Ok(())
    }

    /// Publish `world` for `agent`'s turn at `step`, with a fresh token.
    pub fn publish_world(
        &mut self,
        step: usize,
        agent: usize,
        world: &TurnWorld<'_>,
    ) -> anyhow::Result<Grant> {
        self.seq += 1;
        let grant = Grant {
            seq: self.seq,
            token: self.tokens.next_u64(),
        };
        let c = self.channel(agent)?;
        let mut sample = wire::loan_default(&c.world_pub).context("loaning a world sample")?;
        let w = sample.payload_mut();
        w.seq = grant.seq;
        w.step = step as u64;
        w.token = grant.token;
        w.turn_agent = agent as u32;
        w.centre = (*world.centre).into();
        w.set_heading(world.heading_rad);
        w.set_ahead(world.ahead);
        let (bodies, alive) = (world.bodies, world.alive);
        match world.visible {
            Some(v) => w.set_bodies(bodies, alive, v.iter().copied())?,
            None => w.set_bodies(bodies, alive, 0..bodies.len())?,
        }
        if let Some(v) = world.velocities {
            w.set_velocities(v);
        }
        sample.send().context("sending the world")?;
        Ok(grant)
    }

    /// Take the next state sample from `agent`'s channel, copied out of shared memory and
    /// checked ([`AgentState::read_checked`]); `None` when there is none (or the channel
    /// is closed). A sample that cannot be received at all comes back as
    /// [`MalformedState::Unreadable`]: what the agent's process does to its channel is
    /// its fault, never the coordinator's error.
    pub fn receive(&self, agent: usize) -> Option<Incoming> {
        let c = self.channel(agent).ok()?;
        match c.state_sub.receive() {
            Ok(None) => None,
            Ok(Some(sample)) => Some(Incoming {
                publisher_pid: Some(pid_of_id(sample.origin().value())),
                msg: sample.payload().read_checked(agent),
            }),
            Err(e) => Some(Incoming {
                publisher_pid: None,
                msg: Err(MalformedState::Unreadable(format!("{e:?}"))),
            }),
        }
    }

    /// Processes holding more than one notifier on the run's done service: an agent needs
    /// one; more is hoarding the service's ports.
    pub fn done_hoarders(&self) -> Vec<u32> {
        let mut per_pid: std::collections::BTreeMap<u32, usize> = Default::default();
        self.done_service.dynamic_config().list_notifiers(|n| {
            *per_pid.entry(pid_of_id(n.node_id.value())).or_default() += 1;
            CallbackProgression::Continue
        });
        per_pid
            .into_iter()
            .filter(|&(_, n)| n > 1)
            .map(|(pid, _)| pid)
            .collect()
    }

    /// Processes other than the coordinator and `owner_pid` attached to `agent`'s
    /// channel: an agent has no business opening another agent's services.
    pub fn intruders(&self, agent: usize, owner_pid: u32) -> Vec<u32> {
        let own = std::process::id();
        self.channel(agent)
            .map(|c| {
                c.node_pids()
                    .into_iter()
                    .filter(|&p| p != own && p != owner_pid)
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The generation of `agent`'s open channel.
    pub fn generation(&self, agent: usize) -> Option<u32> {
        self.channel(agent).ok().map(|c| c.generation)
    }

    /// Remove the resources of this run's dead nodes (killed agents); returns how many
    /// nodes were cleaned ([`crate::dead_nodes`]).
    pub fn cleanup_dead_nodes(&self) -> usize {
        crate::dead_nodes::cleanup_dead_nodes(&self.node, &self.prefix)
    }

    /// Drop every port and the node, then remove the run's last shared-memory file.
    /// Call only once every agent process has exited.
    pub fn shut_down(self) -> anyhow::Result<()> {
        let config = self.config.clone();
        let self_prefix = self.prefix.clone();
        self.cleanup_dead_nodes();
        drop(self);
        // SAFETY: every process of this run has exited (the caller's contract), so no one
        // else uses the run's global management segment.
        unsafe { iceoryx2::testing::remove_global_mgmt_segment::<ipc::Service>(&config) }
            .context("removing the run's management segment")
            .context("cleaning up shared memory")?;
        wire::remove_run_root(&self_prefix).with_context(|| {
            format!(
                "removing the run's folder {:?}",
                wire::run_root(&self_prefix)
            )
        })?;
        // What iceoryx2's dead-node cleanup can miss (seen once under load).
        let swept = wire::remove_run_files_in_shm(&self_prefix);
        if swept > 0 {
            tracing::debug!("removed {swept} leftover file(s) of the run from /dev/shm");
        }
        Ok(())
    }
}
