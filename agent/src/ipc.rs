//! The agent's side of the iceoryx2 protocol (see [`shared::wire`]).

use std::time::{Duration, Instant};

use anyhow::{Context, anyhow, bail};
use iceoryx2::node::NodeWaitFailure;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2_bb_posix::signal::SignalHandler;
use nix::unistd::{Pid, getppid};
use shared::geometry::Point;
use shared::turn::Move;
use shared::wire::{
    self, AgentState, DONE_SERVICE, EVENT_ECHO, EVENT_QUIT, EVENT_TURN, MISSION_SERVICE, Mission,
    Role, StateKind, WORLD_SERVICE, World,
};

use crate::transport::{Command, MissionView, Transport, TurnInput};

/// The agent's iceoryx2 ports.
pub struct IpcTransport {
    agent: usize,
    liveness: Duration,
    parent: Pid,
    node: Node<ipc::Service>,
    mission_sub: Subscriber<ipc::Service, Mission, ()>,
    world_sub: Subscriber<ipc::Service, World, ()>,
    state_pub: Publisher<ipc::Service, AgentState, ()>,
    turn_listener: Listener<ipc::Service>,
    done_notifier: Notifier<ipc::Service>,
    mission: Option<MissionView>,
    /// When the current turn's event woke the agent ([`wire::monotonic_ns`]).
    woke_ns: u64,
}

impl IpcTransport {
    /// Open the services of run `prefix` as agent `agent`. `liveness` is how often the
    /// agent checks, while it waits, that its coordinator is still there.
    pub fn open(prefix: &str, agent: usize, liveness: Duration) -> anyhow::Result<Self> {
        // Ask the kernel for SIGTERM if the coordinator dies: the blocking wait below is
        // then interrupted at once instead of at the next liveness check.
        #[cfg(target_os = "linux")]
        let _ = nix::sys::prctl::set_pdeathsig(nix::sys::signal::Signal::SIGTERM);
        let parent = getppid();
        let config = wire::ipc_config(prefix, Role::Agent)?;
        let node = NodeBuilder::new()
            .name(&NodeName::new(&format!("agent-{agent}")).map_err(|e| anyhow!("{e:?}"))?)
            .config(&config)
            .create::<ipc::Service>()
            .map_err(|e| anyhow!("creating the node: {e:?}"))?;
        // The first wait installs iceoryx2's signal handlers: from now on SIGTERM and
        // SIGINT interrupt a blocking wait instead of killing the process mid-write.
        let _ = node.wait(Duration::ZERO);

        let name = |s: &str| ServiceName::new(s).map_err(|e| anyhow!("service name {s}: {e:?}"));
        let mission = node
            .service_builder(&name(MISSION_SERVICE)?)
            .publish_subscribe::<Mission>()
            .open()
            .map_err(|e| anyhow!("opening {MISSION_SERVICE}: {e:?}"))?;
        let world = node
            .service_builder(&name(WORLD_SERVICE)?)
            .publish_subscribe::<World>()
            .open()
            .map_err(|e| anyhow!("opening {WORLD_SERVICE}: {e:?}"))?;
        let state = node
            .service_builder(&name(&wire::state_service_name(agent))?)
            .publish_subscribe::<AgentState>()
            .open()
            .map_err(|e| anyhow!("opening the state service of agent {agent}: {e:?}"))?;
        let turn = node
            .service_builder(&name(&wire::turn_service_name(agent))?)
            .event()
            .open()
            .map_err(|e| anyhow!("opening the turn service of agent {agent}: {e:?}"))?;
        let done = node
            .service_builder(&name(DONE_SERVICE)?)
            .event()
            .open()
            .map_err(|e| anyhow!("opening {DONE_SERVICE}: {e:?}"))?;

        Ok(Self {
            agent,
            liveness,
            parent,
            mission_sub: mission
                .subscriber_builder()
                .create()
                .map_err(|e| anyhow!("mission subscriber: {e:?}"))?,
            world_sub: world
                .subscriber_builder()
                .create()
                .map_err(|e| anyhow!("world subscriber: {e:?}"))?,
            state_pub: state
                .publisher_builder()
                .max_loaned_samples(1)
                .create()
                .map_err(|e| anyhow!("state publisher: {e:?}"))?,
            turn_listener: turn
                .listener_builder()
                .create()
                .map_err(|e| anyhow!("turn listener: {e:?}"))?,
            done_notifier: done
                .notifier_builder()
                .create()
                .map_err(|e| anyhow!("done notifier: {e:?}"))?,
            node,
            mission: None,
            woke_ns: 0,
        })
    }

    /// Loan a state sample, let `fill` write it in place, send it and ring `done`.
    fn send_state(
        &self,
        fill: impl FnOnce(&mut AgentState) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        let mut sample = self
            .state_pub
            .loan_uninit()
            .map_err(|e| anyhow!("loaning a state sample: {e:?}"))?;
        // Initialise the ~8 kB state in place in shared memory (the waypoint array stays
        // uninitialised behind its length), not on the stack and then copied.
        // SAFETY: the pointer is the sample's own payload slot, valid and exclusive.
        unsafe { AgentState::placement_default(sample.payload_mut().as_mut_ptr()) };
        // SAFETY: placement_default initialised the payload.
        let mut sample = unsafe { sample.assume_init() };
        let state = sample.payload_mut();
        state.agent = self.agent as u32;
        state.pid = std::process::id();
        fill(state)?;
        state.sent_ns = wire::monotonic_ns();
        sample
            .send()
            .map_err(|e| anyhow!("sending the state: {e:?}"))?;
        self.done_notifier
            .notify()
            .map_err(|e| anyhow!("notifying done: {e:?}"))?;
        Ok(())
    }

    fn coordinator_gone(&self) -> bool {
        getppid() != self.parent
    }

    /// The newest world sample as a turn, if it is this agent's turn.
    fn read_world(&mut self) -> anyhow::Result<Option<TurnInput>> {
        let mut turn = None;
        while let Some(w) = self
            .world_sub
            .receive()
            .map_err(|e| anyhow!("receiving the world: {e:?}"))?
        {
            if w.turn_agent as usize != self.agent {
                continue;
            }
            turn = Some(TurnInput {
                seq: w.seq,
                step: w.step,
                centre: w.centre.into(),
                positions: w.bodies.iter().map(|b| Point::from(b.position)).collect(),
            });
        }
        Ok(turn)
    }
}

impl Transport for IpcTransport {
    fn announce_ready(&mut self) -> anyhow::Result<()> {
        self.send_state(|s| {
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
            let (mut turn, mut echo, mut quit) = (false, false, false);
            let woke = self.turn_listener.timed_wait(
                |event| match event.id.as_value() {
                    EVENT_TURN => turn = true,
                    EVENT_ECHO => echo = true,
                    EVENT_QUIT => quit = true,
                    _ => {}
                },
                self.liveness,
            );
            if echo {
                self.woke_ns = wire::monotonic_ns();
                self.send_state(|s| {
                    s.kind = StateKind::Echo as u32;
                    s.woke_ns = self.woke_ns;
                    Ok(())
                })?;
            }
            match woke {
                Ok(_) if quit => return Ok(Command::Quit),
                Ok(_) if turn => {
                    self.woke_ns = wire::monotonic_ns();
                    if let Some(t) = self.read_world()? {
                        return Ok(Command::Turn(t));
                    }
                    // A turn event without a world for us: a stale wake-up; wait again.
                }
                Ok(_) => {
                    // Timed out (or woke early with nothing, which iceoryx2 may do):
                    // check the coordinator on the clock, not on the return value.
                    if waited.elapsed() >= self.liveness && self.coordinator_gone() {
                        tracing::warn!("agent {}: coordinator gone, leaving", self.agent);
                        return Ok(Command::Quit);
                    }
                }
                Err(ListenerWaitError::InterruptSignal) => {
                    if let Err(NodeWaitFailure::TerminationRequest) = self.node.wait(Duration::ZERO)
                    {
                        return Ok(Command::Quit);
                    }
                }
                Err(e) => bail!("waiting for a turn: {e:?}"),
            }
        }
    }

    fn mission(&mut self) -> anyhow::Result<MissionView> {
        while let Some(m) = self
            .mission_sub
            .receive()
            .map_err(|e| anyhow!("receiving the mission: {e:?}"))?
        {
            let planner = m
                .planner()
                .with_context(|| format!("unknown planner code {} in the mission", m.planner))?;
            self.mission = Some(MissionView {
                field: m.field(),
                obstacles: m.obstacles(),
                agents: m.agents(),
                planner,
            });
        }
        self.mission
            .clone()
            .context("no mission was published before the first turn")
    }

    fn publish_move(
        &mut self,
        turn: &TurnInput,
        mv: &Move,
        status: u32,
        compute: Duration,
    ) -> anyhow::Result<()> {
        self.send_state(|s| {
            s.kind = StateKind::Move as u32;
            s.seq = turn.seq;
            s.step = turn.step;
            s.compute_ns = u64::try_from(compute.as_nanos()).unwrap_or(u64::MAX);
            s.woke_ns = self.woke_ns;
            s.status = status;
            s.slot = mv.slot.into();
            s.best = mv.best.into();
            s.set_waypoints(&mv.waypoints)?;
            Ok(())
        })
    }
}
