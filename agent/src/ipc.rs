//! The agent's side of the iceoryx2 protocol (see [`wire`]), in two layers:
//!
//! - [`Channel`]: the agent's ports on its own channel ([`AgentServiceNames`]), as
//!   primitives: wait for the events rung on it, read the newest world, send a state
//!   sample. [`IpcPorts`] is the channel over iceoryx2.
//! - [`IpcTransport`]: the protocol on top of a channel (the ready handshake, the echo,
//!   the prepare notice's look at the world, turns and moves), the [`Transport`] that
//!   [`serve`](crate::serve) talks to.
//!
//! The split lets a test build wrap the ports in a decorator that tampers with what goes
//! out and ignores what comes in (the `misbehave` feature); an agent built without it
//! runs [`IpcTransport`] over [`IpcPorts`] and nothing else.

use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use iceoryx2::node::NodeWaitFailure;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2_bb_posix::signal::SignalHandler;
use nix::unistd::{Pid, getppid};
use shared::geometry::Point;
use wire::{
    AgentServiceNames, AgentState, EVENT_ECHO, EVENT_PREPARE, EVENT_QUIT, EVENT_TURN, PREPARE_SPIN,
    Role, StateKind, World,
};

use crate::transport::{Command, MissionView, Reply, Transport, TurnInput};

/// The events one wait on the turn listener heard, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Events {
    /// [`EVENT_TURN`]: this agent's world is published.
    pub turn: bool,
    /// [`EVENT_ECHO`]: answer an empty turn (the bench's echo).
    pub echo: bool,
    /// [`EVENT_QUIT`]: leave.
    pub quit: bool,
    /// [`EVENT_PREPARE`]: this agent's turn comes next.
    pub prepare: bool,
}

/// An agent's ports on its own channel, as primitives.
pub trait Channel {
    /// Block until an event is rung or `timeout` passes (it may also return early with
    /// nothing): the events heard, by kind, and how the wait ended (an error, e.g. a
    /// signal, may come with events heard before it).
    fn wait(&mut self, timeout: Duration) -> (Events, Result<(), ListenerWaitError>);
    /// The newest world sample as a turn, if it is this agent's turn.
    fn read_world(&mut self) -> anyhow::Result<Option<TurnInput>>;
    /// Loan a state sample with this agent's index and process id, let `fill` write the
    /// rest in place, stamp it, send it and ring the run's done event.
    fn send_state(
        &mut self,
        fill: impl FnOnce(&mut AgentState) -> anyhow::Result<()>,
    ) -> anyhow::Result<()>;
    /// Whether a signal noted while waiting asks this process to terminate.
    fn termination_requested(&self) -> bool;
}

/// The agent's iceoryx2 ports: its own channel ([`AgentServiceNames`]).
pub struct IpcPorts {
    agent: usize,
    /// This process's id, stamped on every state (read once: a system call each time).
    pid: u32,
    node: Node<ipc::Service>,
    world_sub: Subscriber<ipc::Service, World, ()>,
    state_pub: Publisher<ipc::Service, AgentState, ()>,
    rings: Rings,
}

/// How this agent and its coordinator ring each other, as the run's doorbells file says
/// ([`wire::Doorbells`]): by the doorbells, or by iceoryx2 events.
enum Rings {
    /// This agent's doorbell, and the coordinator's answer counter.
    Doorbells(wire::Doorbells),
    /// The turn service's listener, and a notifier on the run's done service.
    Events(Box<EventPorts>),
}

/// The ports of [`Rings::Events`].
struct EventPorts {
    turn_listener: Listener<ipc::Service>,
    done_notifier: Notifier<ipc::Service>,
}

impl Channel for IpcPorts {
    fn wait(&mut self, timeout: Duration) -> (Events, Result<(), ListenerWaitError>) {
        let mut events = Events::default();
        let mut heard = |event: usize| match event {
            EVENT_TURN => events.turn = true,
            EVENT_ECHO => events.echo = true,
            EVENT_QUIT => events.quit = true,
            EVENT_PREPARE => events.prepare = true,
            _ => {}
        };
        let woke = match &self.rings {
            Rings::Doorbells(doorbells) => match doorbells.wait(self.agent, timeout) {
                Ok((rung, woken)) => {
                    (0..u32::BITS as usize)
                        .filter(|e| rung & (1 << e) != 0)
                        .for_each(&mut heard);
                    // Rings taken are acted on even if a signal ended the wait (the signal
                    // is noted by its handler and looked at before the next wait).
                    match woken {
                        wire::Woken::Interrupted if rung == 0 => {
                            Err(ListenerWaitError::InterruptSignal)
                        }
                        _ => Ok(()),
                    }
                }
                // Not for an agent the file was opened for (its word was checked then).
                Err(_) => Err(ListenerWaitError::InternalFailure),
            },
            Rings::Events(ports) => ports
                .turn_listener
                .timed_wait(|event| heard(event.id.as_value()), timeout)
                .map(|_| ()),
        };
        (events, woke)
    }

    fn read_world(&mut self) -> anyhow::Result<Option<TurnInput>> {
        let mut turn = None;
        while let Some(w) = self.world_sub.receive().context("receiving the world")? {
            if w.turn_agent as usize != self.agent {
                continue;
            }
            // Only the coordinator publishes here, but a count beyond the capacity would
            // make the slice below panic: refuse it instead.
            if w.bodies.len() > shared::control::vocabulary::MAX_AGENTS {
                bail!(
                    "a world with {} bodies, beyond the capacity",
                    w.bodies.len()
                );
            }
            let heading_rad = w.heading();
            if heading_rad.is_some_and(|h| !h.is_finite()) {
                bail!("a world whose heading is not a finite number");
            }
            if w.ahead.len() > shared::control::tracking::MAX_HORIZON_STEPS {
                bail!(
                    "a world with {} poses ahead, beyond the capacity",
                    w.ahead.len()
                );
            }
            let ahead: Vec<shared::geometry::Pose> = w.ahead.iter().map(|p| (*p).into()).collect();
            if !ahead
                .iter()
                .all(|p| p.x_m.is_finite() && p.y_m.is_finite() && p.heading_rad.is_finite())
            {
                bail!("a world with a pose ahead that is not finite");
            }
            turn = Some(TurnInput {
                seq: w.seq,
                step: w.step,
                token: w.token,
                centre: w.centre.into(),
                heading_rad,
                ahead,
                bodies: w
                    .bodies
                    .iter()
                    .map(|b| (b.agent as usize, Point::from(b.position)))
                    .collect(),
                velocities: w
                    .bodies
                    .iter()
                    .map(|b| shared::geometry::Vector::new(b.velocity.x_m, b.velocity.y_m))
                    .collect(),
                frozen: w
                    .bodies
                    .iter()
                    .filter(|b| b.alive == 0)
                    .map(|b| b.agent as usize)
                    .collect(),
            });
        }
        Ok(turn)
    }

    fn send_state(
        &mut self,
        fill: impl FnOnce(&mut AgentState) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        // The ~8 kB state is initialised in place in shared memory (the waypoint array
        // stays uninitialised behind its length), not on the stack and then copied.
        let mut sample = wire::loan_default(&self.state_pub).context("loaning a state sample")?;
        let state = sample.payload_mut();
        state.agent = self.agent as u32;
        state.pid = self.pid;
        fill(state)?;
        state.sent_ns = wire::monotonic_ns();
        sample.send().context("sending the state")?;
        match &self.rings {
            Rings::Doorbells(doorbells) => doorbells.answer(),
            Rings::Events(ports) => {
                ports.done_notifier.notify().context("notifying done")?;
            }
        }
        Ok(())
    }

    fn termination_requested(&self) -> bool {
        matches!(
            self.node.wait(Duration::ZERO),
            Err(NodeWaitFailure::TerminationRequest)
        )
    }
}

/// The agent's side of the iceoryx2 protocol over the channel `C` (normally
/// [`IpcPorts`]).
pub struct IpcTransport<C = IpcPorts> {
    agent: usize,
    liveness: Duration,
    parent: Pid,
    channel: C,
    /// The scenario as run, read from the run's mission file when the channel opens.
    mission: MissionView,
    /// When the current turn's event woke the agent ([`wire::monotonic_ns`]).
    woke_ns: u64,
}

/// The run's mission as an agent holds it: the file's text (a relay passes it on as it
/// is) and what the agent sees of the scenario.
#[derive(Clone, Debug)]
pub struct Mission {
    /// The mission file's text.
    pub text: String,
    /// The scenario as the agent sees it.
    pub view: MissionView,
}

impl Mission {
    /// Read run `prefix`'s mission file, refused unless its digest is `digest` (when
    /// given; then its values alone are checked, see [`wire::read_mission`]).
    pub fn read(prefix: &str, digest: Option<wire::MissionDigest>) -> anyhow::Result<Self> {
        let text = wire::read_mission_text(prefix, digest).context("the mission file")?;
        let view = MissionView::of(text.parse().context("the mission file")?);
        Ok(Self {
            text: text.text,
            view,
        })
    }
}

impl IpcTransport {
    /// Open the channel of agent `agent`, process generation `generation`, in run
    /// `prefix`, with what the agent sees of the run's mission, read before ([`Mission`]).
    /// `liveness` is how often the agent checks, while it waits, that its coordinator is
    /// still there.
    pub fn open(
        prefix: &str,
        agent: usize,
        generation: u32,
        liveness: Duration,
        mission: MissionView,
    ) -> anyhow::Result<Self> {
        // Ask the kernel for SIGTERM if the coordinator dies: the blocking wait below is
        // then interrupted at once instead of at the next liveness check.
        #[cfg(target_os = "linux")]
        let _ = nix::sys::prctl::set_pdeathsig(nix::sys::signal::Signal::SIGTERM);
        let parent = getppid();
        let config = wire::ipc_config(prefix, Role::Agent)?;
        let node = NodeBuilder::new()
            .name(&NodeName::new(&format!("agent-{agent}")).context("the node's name")?)
            .config(&config)
            .create::<ipc::Service>()
            .context("creating the node")?;
        // The first wait installs iceoryx2's signal handlers: from now on SIGTERM and
        // SIGINT interrupt a blocking wait instead of killing the process mid-write.
        let _ = node.wait(Duration::ZERO);

        let names = AgentServiceNames::new(agent, generation);
        let name = |s: &str| ServiceName::new(s).with_context(|| format!("service name {s}"));
        let world = node
            .service_builder(&name(&names.world)?)
            .publish_subscribe::<World>()
            .open()
            .with_context(|| format!("opening {}", names.world))?;
        let state = node
            .service_builder(&name(&names.state)?)
            .publish_subscribe::<AgentState>()
            .open()
            .with_context(|| format!("opening {}", names.state))?;
        // The run's doorbells say how the run rings; rung by events, the agent opens the
        // event services.
        let doorbells = wire::Doorbells::open(prefix, agent).context("the run's doorbells")?;
        let rings = match doorbells.wake_by() {
            Some(wire::WakeBy::Doorbells) => Rings::Doorbells(doorbells),
            Some(wire::WakeBy::Events) => {
                let turn = node
                    .service_builder(&name(&names.turn)?)
                    .event()
                    .open()
                    .with_context(|| format!("opening {}", names.turn))?;
                let done = node
                    .service_builder(&name(wire::DONE_SERVICE)?)
                    .event()
                    .open()
                    .with_context(|| format!("opening {}", wire::DONE_SERVICE))?;
                Rings::Events(Box::new(EventPorts {
                    turn_listener: turn.listener_builder().create().context("turn listener")?,
                    // The run's one done service, rung with this agent's index.
                    done_notifier: done
                        .notifier_builder()
                        .default_event_id(EventId::new(agent))
                        .create()
                        .context("done notifier")?,
                }))
            }
            None => bail!("the run's doorbells say neither how to ring nor how to be rung"),
        };
        let channel = IpcPorts {
            rings,
            agent,
            pid: std::process::id(),
            world_sub: world
                .subscriber_builder()
                .create()
                .context("world subscriber")?,
            // The coordinator's buffer refuses samples once full (no overflow), so the
            // first answer to a turn is the one it reads; an honest agent never fills it.
            state_pub: state
                .publisher_builder()
                .max_loaned_samples(1)
                .backpressure_strategy(BackpressureStrategy::DiscardData)
                .create()
                .context("state publisher")?,
            node,
        };
        let transport = Self {
            agent,
            liveness,
            parent,
            channel,
            mission,
            woke_ns: 0,
        };
        Ok(transport)
    }
}

impl<C: Channel> IpcTransport<C> {
    /// The same transport over `wrap(channel)`: a decorator of the ports.
    pub fn map_channel<D: Channel>(self, wrap: impl FnOnce(C) -> D) -> IpcTransport<D> {
        IpcTransport {
            agent: self.agent,
            liveness: self.liveness,
            parent: self.parent,
            channel: wrap(self.channel),
            mission: self.mission,
            woke_ns: self.woke_ns,
        }
    }

    fn coordinator_gone(&self) -> bool {
        getppid() != self.parent
    }

    /// Whether this process should leave now: asked to (SIGTERM, SIGINT: noted by
    /// iceoryx2's handler), or its coordinator is gone. For loops that wait on something
    /// else than this channel (the relay's).
    pub fn should_leave(&self) -> bool {
        SignalHandler::termination_requested() || self.coordinator_gone()
    }
}

impl<C: Channel> Transport for IpcTransport<C> {
    fn announce_ready(&mut self) -> anyhow::Result<()> {
        self.channel.send_state(|s| {
            s.kind = StateKind::Ready as u32;
            Ok(())
        })
    }

    fn next_command(&mut self) -> anyhow::Result<Command> {
        loop {
            // A SIGTERM that came while the agent was busy was only noted by iceoryx2's
            // handler: look before blocking (an atomic read, no system call).
            if SignalHandler::termination_requested() {
                return Ok(Command::Quit);
            }
            let waited = Instant::now();
            let (events, woke) = self.channel.wait(self.liveness);
            if events.echo {
                self.woke_ns = wire::monotonic_ns();
                let woke_ns = self.woke_ns;
                self.channel.send_state(|s| {
                    s.kind = StateKind::Echo as u32;
                    s.woke_ns = woke_ns;
                    Ok(())
                })?;
            }
            if events.prepare && !events.quit {
                // Next in line: look at the world without sleeping for a while, so the
                // grant costs no wake-up (the coordinator then publishes the world without
                // ringing the turn); then back to the blocking wait. A turn rung with it
                // (late, its world maybe taken already) is served by the same look.
                let until = Instant::now() + PREPARE_SPIN;
                while Instant::now() < until {
                    if let Some(t) = self.channel.read_world()? {
                        self.woke_ns = wire::monotonic_ns();
                        return Ok(Command::Turn(t));
                    }
                    std::thread::yield_now();
                }
                continue;
            }
            match woke {
                Ok(()) if events.quit => return Ok(Command::Quit),
                Ok(()) if events.turn => {
                    self.woke_ns = wire::monotonic_ns();
                    if let Some(t) = self.channel.read_world()? {
                        return Ok(Command::Turn(t));
                    }
                    // A turn event without a world for us: a stale wake-up; wait again.
                }
                Ok(()) => {
                    // Timed out (or woke early with nothing, which iceoryx2 may do):
                    // check the coordinator on the clock, not on the return value.
                    if waited.elapsed() >= self.liveness && self.coordinator_gone() {
                        tracing::warn!("agent {}: coordinator gone, leaving", self.agent);
                        return Ok(Command::Quit);
                    }
                }
                Err(ListenerWaitError::InterruptSignal) => {
                    if self.channel.termination_requested() {
                        return Ok(Command::Quit);
                    }
                }
                Err(e) => return Err(e).context("waiting for a turn"),
            }
        }
    }

    fn mission(&mut self) -> anyhow::Result<MissionView> {
        Ok(self.mission.clone())
    }

    fn publish_move(&mut self, reply: Reply<'_>) -> anyhow::Result<()> {
        let Reply {
            turn,
            mv,
            status,
            compute,
        } = reply;
        let woke_ns = self.woke_ns;
        self.channel.send_state(|s| {
            s.kind = StateKind::Move as u32;
            s.seq = turn.seq;
            s.step = turn.step;
            s.token = turn.token;
            s.compute_ns = u64::try_from(compute.as_nanos()).unwrap_or(u64::MAX);
            s.woke_ns = woke_ns;
            s.status = status;
            s.slot = mv.slot.into();
            s.best = mv.best.into();
            s.set_end_heading(mv.end_heading_rad);
            s.set_waypoints(&mv.waypoints)?;
            Ok(())
        })
    }
}
