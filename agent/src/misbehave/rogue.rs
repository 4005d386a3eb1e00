//! The test modes that attack other agents' channels, as a compromised agent process
//! could: [`Misbehave::Impersonate`] publishes in another agent's name on its channel,
//! [`Misbehave::Hoard`] grabs every port it can on every other agent's services. Both act
//! before the agent opens its own channel, to race their victims; whatever they manage to
//! open is held for the life of the process.

use std::any::Any;

use anyhow::Context;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use wire::{AgentServiceNames, AgentState, Role, StateKind, World};

use wire::misbehave::Misbehave;

/// Most ports of one kind a hoarding agent opens on one service.
const HOARD_PER_SERVICE: usize = 4;

/// Carry out the attacks of `mode` that come before this agent opens its own channel;
/// returns what must stay open (ports, services, the node) for the life of the process.
pub fn before_opening(prefix: &str, me: usize, mode: Misbehave) -> Vec<Box<dyn Any>> {
    let mut held: Vec<Box<dyn Any>> = Vec::new();
    let result = match mode {
        Misbehave::Impersonate { victim } => impersonate(prefix, victim, &mut held),
        Misbehave::Hoard => hoard(prefix, me, &mut held),
        Misbehave::KilledConnecting => killed_connecting(prefix, me, &mut held),
        _ => Ok(()),
    };
    if let Err(e) = result {
        tracing::warn!("agent {me}: attack ({mode}) stopped: {e:#}");
    }
    held
}

fn rogue_node(prefix: &str, held: &mut Vec<Box<dyn Any>>) -> anyhow::Result<Node<ipc::Service>> {
    let config = wire::ipc_config(prefix, Role::Agent)?;
    let node = NodeBuilder::new()
        .name(&NodeName::new("intruder").context("the node's name")?)
        .config(&config)
        .create::<ipc::Service>()
        .context("creating the intruder node")?;
    held.push(Box::new(config));
    Ok(node)
}

fn service_name(s: &str) -> anyhow::Result<ServiceName> {
    ServiceName::new(s).with_context(|| format!("service name {s}"))
}

/// Open the state service of agent `agent`'s first process from `node`; with its names.
fn open_state(
    node: &Node<ipc::Service>,
    agent: usize,
) -> anyhow::Result<(
    AgentServiceNames,
    PubSubFactory<ipc::Service, AgentState, ()>,
)> {
    let names = AgentServiceNames::new(agent, 0);
    let state = node
        .service_builder(&service_name(&names.state)?)
        .publish_subscribe::<AgentState>()
        .open()
        .with_context(|| format!("opening {}", names.state))?;
    Ok((names, state))
}

/// The process id of agent `victim` of run `prefix`, found the way any local process
/// can: its command line.
fn victim_pid(prefix: &str, victim: usize) -> Option<u32> {
    let needle = format!("--prefix\0{prefix}\0--agent\0{victim}\0");
    std::fs::read_dir("/proc").ok()?.flatten().find_map(|e| {
        let pid: u32 = e.file_name().to_str()?.parse().ok()?;
        let cmdline = std::fs::read(e.path().join("cmdline")).ok()?;
        String::from_utf8_lossy(&cmdline)
            .contains(&needle)
            .then_some(pid)
    })
}

/// Open agent `victim`'s state service and publish a forged handshake and a forged move
/// in its name, claiming its process id.
fn impersonate(prefix: &str, victim: usize, held: &mut Vec<Box<dyn Any>>) -> anyhow::Result<()> {
    let node = rogue_node(prefix, held)?;
    let (names, state) = open_state(&node, victim)?;
    let done = node
        .service_builder(&service_name(wire::DONE_SERVICE)?)
        .event()
        .open()
        .with_context(|| format!("opening {}", wire::DONE_SERVICE))?;
    let publisher = state.publisher_builder().create();
    let notifier = done
        .notifier_builder()
        .default_event_id(iceoryx2::prelude::EventId::new(victim))
        .create();
    // Keep the services open even if no port could be had: the victim got there first.
    held.push(Box::new(state));
    held.push(Box::new(done));
    let publisher = publisher.with_context(|| format!("publisher on {}", names.state))?;
    let claimed_pid = victim_pid(prefix, victim).unwrap_or(0);
    for kind in [StateKind::Ready, StateKind::Move] {
        let mut sample = publisher.loan().context("loaning a forged state")?;
        let s = sample.payload_mut();
        s.kind = kind as u32;
        s.agent = victim as u32;
        s.pid = claimed_pid;
        sample.send().context("sending a forged state")?;
    }
    if let Ok(n) = &notifier {
        let _ = n.notify();
    }
    held.push(Box::new(publisher));
    if let Ok(n) = notifier {
        held.push(Box::new(n));
    }
    held.push(Box::new(node));
    Ok(())
}

/// Make a publisher on this agent's own state service, leave an empty segment for a
/// connection of it (as a process killed between iceoryx2's `shm_open` and its sizing of
/// the segment does), then die by SIGKILL: the coordinator's cleanup of this dead node
/// must not wait on the segment forever.
fn killed_connecting(prefix: &str, me: usize, held: &mut Vec<Box<dyn Any>>) -> anyhow::Result<()> {
    let node = rogue_node(prefix, held)?;
    let (names, state) = open_state(&node, me)?;
    let publisher = state
        .publisher_builder()
        .create()
        .with_context(|| format!("publisher on {}", names.state))?;
    // iceoryx2 names a connection's segment after its sender and receiver ports; this
    // one's receiver no one has (the name is all the cleanup goes by). The name's other
    // parts are those of the publisher's connection to the coordinator, made just now.
    let sender = format!("_{}_", publisher.id().value());
    let made = std::fs::read_dir("/dev/shm")
        .context("listing /dev/shm")?
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .find(|name| name.starts_with(prefix) && name.contains(&sender))
        .context("the publisher has no connection")?;
    let (head, _) = made.split_once(&sender).context("the connection's name")?;
    let segment = format!("/dev/shm/{head}{sender}{}.connection", u128::MAX / 3);
    std::fs::File::create(&segment).with_context(|| format!("creating {segment}"))?;
    tracing::warn!("agent {me} (killed-connecting): left {segment} empty; killing itself");
    nix::sys::signal::raise(nix::sys::signal::Signal::SIGKILL).context("SIGKILL")?;
    unreachable!("a process survived its own SIGKILL")
}

/// Create ports with `make` until it fails or [`HOARD_PER_SERVICE`] are held; returns
/// how many were had.
fn grab<P: 'static, E>(
    held: &mut Vec<Box<dyn Any>>,
    mut make: impl FnMut() -> Result<P, E>,
) -> usize {
    let mut count = 0;
    while count < HOARD_PER_SERVICE {
        let Ok(port) = make() else {
            break;
        };
        held.push(Box::new(port));
        count += 1;
    }
    count
}

/// Open every other agent's services and as many ports on each as the run allows.
fn hoard(prefix: &str, me: usize, held: &mut Vec<Box<dyn Any>>) -> anyhow::Result<()> {
    let node = rogue_node(prefix, held)?;
    let mut ports = 0usize;
    for victim in (0..shared::control::vocabulary::MAX_AGENTS).filter(|&v| v != me) {
        let names = AgentServiceNames::new(victim, 0);
        let Ok(world) = node
            .service_builder(&service_name(&names.world)?)
            .publish_subscribe::<World>()
            .open()
        else {
            // The first agent without a channel: past the last agent.
            break;
        };
        ports += grab(held, || world.subscriber_builder().create());
        held.push(Box::new(world));
        if let Ok(state) = node
            .service_builder(&service_name(&names.state)?)
            .publish_subscribe::<AgentState>()
            .open()
        {
            ports += grab(held, || state.publisher_builder().create());
            held.push(Box::new(state));
        }
        for name in [&names.turn] {
            let Ok(event) = node.service_builder(&service_name(name)?).event().open() else {
                continue;
            };
            ports += grab(held, || event.notifier_builder().create());
            ports += grab(held, || event.listener_builder().create());
            held.push(Box::new(event));
        }
    }
    if let Ok(done) = node
        .service_builder(&service_name(wire::DONE_SERVICE)?)
        .event()
        .open()
    {
        ports += grab(held, || done.notifier_builder().create());
        held.push(Box::new(done));
    }
    tracing::warn!("agent {me}: hoarding {ports} ports on other agents' services");
    held.push(Box::new(node));
    Ok(())
}
