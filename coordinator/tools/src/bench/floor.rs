//! The latency floor and the socket comparison, measured between the coordinator and one
//! process of the bench's own ping-pong program, [`PEER_BIN`] (see
//! `coordinator/cli/src/bin/bench-peer.rs`), in blocks that alternate between the mechanisms
//! and can be spread over the run:
//!
//! - iceoryx2 floor: a small sample published, the ping rung, then the same wait a turn
//!   uses until the pong sample is in, rung as the run's turns are: by the session's
//!   doorbells (`--wake doorbell`: a futex word rung, the answer counted, sleeping on the
//!   counter while the pong is not in) or by iceoryx2 events (`--wake event`: take what
//!   arrived, else block in `Listener::timed_wait`). The clock runs from just before the
//!   ring to the pong received, the same span as a turn's latency (a turn's world is
//!   published before its clock starts too).
//! - Unix domain socket: the same process pair; a request the size of a serialized world
//!   is written, a reply the size of a serialized move is read (blocking calls). The
//!   clock runs from before the write to the whole reply read. No serialization cost is
//!   counted: this is the socket's floor, a lower bound of what a socket design costs.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use wire::{
    BENCH_EVENT_DOORBELL, BENCH_EVENT_SOCKET, BENCH_EVENT_SPIN, BENCH_PING_EVENT,
    BENCH_PING_SERVICE, BENCH_PONG_EVENT, BENCH_PONG_SERVICE, BENCH_SOCKET_DONE, BENCH_SPIN_DONE,
    BenchPing, EVENT_QUIT, EVENT_TURN, Role,
};

use runner::agents::{AgentProcesses, Exit};
use runner::turns::WakeMode;

/// The bench's ping-pong program, beside the coordinator's executable.
pub const PEER_BIN: &str = "bench-peer";

/// The bench's ping-pong program: [`PEER_BIN`] beside the running coordinator.
pub fn locate_peer_binary() -> anyhow::Result<PathBuf> {
    let path = std::env::current_exe()
        .context("locating the coordinator executable")?
        .with_file_name(PEER_BIN);
    if !path.is_file() {
        bail!(
            "the bench's ping-pong program {} not found (build it with `cargo build --release -p coordinator`)",
            path.display()
        );
    }
    Ok(path)
}

/// Longest a single round trip may take before the measurement is abandoned.
const ROUND_TRIP_DEADLINE: Duration = Duration::from_secs(2);
/// Longest the ping-pong process may take to start.
const STARTUP_DEADLINE: Duration = Duration::from_secs(10);

/// The coordinator's ports of the floor measurement.
struct Ports {
    ping_pub: Publisher<ipc::Service, BenchPing, ()>,
    pong_sub: Subscriber<ipc::Service, BenchPing, ()>,
    ping: Notifier<ipc::Service>,
    pong: Listener<ipc::Service>,
}

fn service_name(s: &str) -> anyhow::Result<ServiceName> {
    ServiceName::new(s).with_context(|| format!("service name {s}"))
}

impl Ports {
    fn create(node: &Node<ipc::Service>) -> anyhow::Result<Self> {
        let pubsub = |name: &str, buffer: usize| {
            node.service_builder(&service_name(name)?)
                .publish_subscribe::<BenchPing>()
                .max_publishers(1)
                .max_subscribers(1)
                .max_nodes(2)
                .subscriber_max_buffer_size(buffer)
                .subscriber_max_borrowed_samples(1)
                .create()
                .with_context(|| format!("creating {name}"))
        };
        let event = |name: &str| {
            node.service_builder(&service_name(name)?)
                .event()
                .max_notifiers(1)
                .max_listeners(1)
                .max_nodes(2)
                .create()
                .with_context(|| format!("creating {name}"))
        };
        Ok(Self {
            ping_pub: pubsub(BENCH_PING_SERVICE, 1)?
                .publisher_builder()
                .max_loaned_samples(1)
                .create()
                .context("ping publisher")?,
            // The ready handshake and one pong.
            pong_sub: pubsub(BENCH_PONG_SERVICE, 2)?
                .subscriber_builder()
                .create()
                .context("pong subscriber")?,
            ping: event(BENCH_PING_EVENT)?
                .notifier_builder()
                .default_event_id(EventId::new(EVENT_TURN))
                .create()
                .context("ping notifier")?,
            pong: event(BENCH_PONG_EVENT)?
                .listener_builder()
                .create()
                .context("pong listener")?,
        })
    }

    /// Take every pong that arrived: whether pong `seq` was among them.
    fn pong_arrived(&self, seq: u64) -> anyhow::Result<bool> {
        let mut arrived = false;
        while let Some(s) = self.pong_sub.receive().context("receiving a pong")? {
            arrived |= s.seq == seq;
        }
        Ok(arrived)
    }

    /// Busy-poll the pong subscriber for the pong `seq`.
    fn spin_pong(&self, seq: u64, deadline: Instant) -> anyhow::Result<()> {
        loop {
            if self.pong_arrived(seq)? {
                return Ok(());
            }
            if Instant::now() >= deadline {
                bail!("no pong {seq} from the ping-pong process in time");
            }
            std::hint::spin_loop();
        }
    }

    /// Wait, as a turn rung by doorbells does, until pong `seq` has arrived or `deadline`
    /// passes: the answer counter read before each look, then a sleep while it holds.
    fn wait_pong_rung(
        &self,
        doorbells: &wire::Doorbells,
        seq: u64,
        deadline: Instant,
    ) -> anyhow::Result<()> {
        loop {
            let seen = doorbells.answers();
            if self.pong_arrived(seq)? {
                return Ok(());
            }
            let now = Instant::now();
            if now >= deadline {
                bail!("no pong {seq} from the ping-pong process in time");
            }
            if doorbells.wait_answer(seen, deadline - now) == wire::Woken::Interrupted {
                bail!("interrupted");
            }
        }
    }

    /// Wait, as a turn rung by events does, until pong `seq` has arrived or `deadline`
    /// passes.
    fn wait_pong(&self, seq: u64, deadline: Instant) -> anyhow::Result<()> {
        loop {
            if self.pong_arrived(seq)? {
                return Ok(());
            }
            let now = Instant::now();
            if now >= deadline {
                bail!("no pong {seq} from the ping-pong process in time");
            }
            match self.pong.timed_wait(|_| {}, deadline - now) {
                Ok(_) => {}
                Err(ListenerWaitError::InterruptSignal) => bail!("interrupted"),
                Err(e) => return Err(e).context("waiting for a pong"),
            }
        }
    }
}

/// One [`PEER_BIN`] process and the coordinator's end of the ping-pongs. Blocks
/// of either kind can be run at any time, e.g. before and after the turns, so the floor
/// sees the same machine as the turns. Dropping the session (or [`Self::finish`]) stops
/// and reaps the process and removes the socket file and every iceoryx2 file it made.
pub struct PingPongSession {
    prefix: String,
    config: Config,
    socket_path: PathBuf,
    procs: AgentProcesses,
    stream: Option<UnixStream>,
    ports: Option<Ports>,
    node: Option<Node<ipc::Service>>,
    /// The session's doorbells: one word, the ping-pong process's.
    doorbells: wire::Doorbells,
    seq: u64,
    closed: bool,
    /// The session's private folder (last: removed after everything else).
    _root: wire::RunRoot,
}

impl PingPongSession {
    /// Start the ping-pong process ([`locate_peer_binary`]) and shake hands over both
    /// channels.
    pub fn start() -> anyhow::Result<Self> {
        let bin = locate_peer_binary()?;
        let prefix = wire::RunPrefix::new_random()?.to_string();
        let config = wire::ipc_config(&prefix, Role::Coordinator)?;
        let root = wire::RunRoot::create(&prefix)?;
        // In the private folder: no other user can connect to the socket.
        let socket_path = match root.path() {
            Some(folder) => folder.join("pingpong.sock"),
            None => std::env::temp_dir().join(format!("{prefix}pingpong.sock")),
        };
        let doorbells = wire::Doorbells::create(&prefix, 1, wire::WakeBy::Doorbells)
            .context("the ping-pong's doorbells")?;
        let mut session = Self {
            procs: AgentProcesses::new(bin, &prefix, 1),
            doorbells,
            prefix,
            config,
            socket_path,
            stream: None,
            ports: None,
            node: None,
            seq: 0,
            closed: false,
            _root: root,
        };
        session.connect()?;
        Ok(session)
    }

    /// The iceoryx2 prefix of the session (every resource it made starts with it).
    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    fn connect(&mut self) -> anyhow::Result<()> {
        let node = NodeBuilder::new()
            .name(&NodeName::new("coordinator").context("the node's name")?)
            .config(&self.config)
            .create::<ipc::Service>()
            .context("creating the floor's node")?;
        // The management segment it made in /dev/shm is open to everyone: make it private.
        wire::make_run_files_private(&self.prefix)?;
        // iceoryx2's signal handlers: Ctrl-C interrupts the waits below.
        let _ = node.wait(Duration::ZERO);
        let ports = Ports::create(&node)?;
        self.node = Some(node);
        let _ = std::fs::remove_file(&self.socket_path);
        let listener = UnixListener::bind(&self.socket_path)
            .with_context(|| format!("binding {}", self.socket_path.display()))?;
        let uds = self.socket_path.display().to_string();
        self.procs.spawn(0, &["--uds".into(), uds])?;
        let deadline = Instant::now() + STARTUP_DEADLINE;
        let stream = accept(&listener, &mut self.procs, deadline)?;
        stream.set_read_timeout(Some(ROUND_TRIP_DEADLINE))?;
        self.stream = Some(stream);
        ports
            .wait_pong(0, deadline)
            .context("the ping-pong process's ready handshake")?;
        self.ports = Some(ports);
        Ok(())
    }

    /// `count` iceoryx2 round trips rung as `wake` says after `warmup` unrecorded ones,
    /// microseconds: the floor of a turn rung that way (the ping-pong process is
    /// switched to its doorbell and back for `WakeMode::Doorbell`).
    pub fn rung(
        &mut self,
        wake: WakeMode,
        warmup: usize,
        count: usize,
    ) -> anyhow::Result<Vec<f64>> {
        let ports = self.ports.as_ref().context("the session is closed")?;
        if wake == WakeMode::Doorbell {
            ports
                .ping
                .notify_with_custom_event_id(EventId::new(BENCH_EVENT_DOORBELL))
                .context("switching the ping-pong to its doorbell")?;
        }
        let mut out = Vec::with_capacity(count);
        for k in 0..warmup + count {
            self.seq += 1;
            let seq = self.seq;
            ports
                .ping_pub
                .send_copy(BenchPing {
                    seq,
                    payload: [seq; 3],
                })
                .context("sending a ping")?;
            let t0 = Instant::now();
            let deadline = t0 + ROUND_TRIP_DEADLINE;
            match wake {
                WakeMode::Doorbell => {
                    self.doorbells
                        .ring(0, EVENT_TURN)
                        .context("ringing the ping")?;
                    ports.wait_pong_rung(&self.doorbells, seq, deadline)?;
                }
                WakeMode::Event => {
                    ports.ping.notify().context("ringing the ping")?;
                    ports.wait_pong(seq, deadline)?;
                }
            }
            let us = t0.elapsed().as_secs_f64() * 1e6;
            if k >= warmup {
                out.push(us);
            }
        }
        if wake == WakeMode::Doorbell {
            self.doorbells
                .ring(0, BENCH_EVENT_DOORBELL)
                .context("switching the ping-pong back to events")?;
        }
        Ok(out)
    }

    /// `count` busy-polled iceoryx2 round trips (no event either way: the ping-pong
    /// process spins on its subscriber, this one on the pong) after `warmup` unrecorded
    /// ones, microseconds: the floor of publish-subscribe between two processes.
    pub fn iceoryx2_spin(&mut self, warmup: usize, count: usize) -> anyhow::Result<Vec<f64>> {
        let ports = self.ports.as_ref().context("the session is closed")?;
        ports
            .ping
            .notify_with_custom_event_id(EventId::new(BENCH_EVENT_SPIN))
            .context("switching to the busy-poll ping-pong")?;
        let mut out = Vec::with_capacity(count);
        for k in 0..=warmup + count {
            // The last ping closes the busy-poll ping-pong.
            let seq = if k == warmup + count {
                BENCH_SPIN_DONE
            } else {
                self.seq += 1;
                self.seq
            };
            let t0 = Instant::now();
            ports
                .ping_pub
                .send_copy(BenchPing {
                    seq,
                    payload: [seq; 3],
                })
                .context("sending a ping")?;
            ports.spin_pong(seq, t0 + ROUND_TRIP_DEADLINE)?;
            let us = t0.elapsed().as_secs_f64() * 1e6;
            if k >= warmup && seq != BENCH_SPIN_DONE {
                out.push(us);
            }
        }
        Ok(out)
    }

    /// `count` socket round trips (a request of `request_bytes`, a reply of
    /// `reply_bytes`) after `warmup` unrecorded ones, microseconds.
    pub fn socket(
        &mut self,
        warmup: usize,
        count: usize,
        request_bytes: usize,
        reply_bytes: usize,
    ) -> anyhow::Result<Vec<f64>> {
        let ports = self.ports.as_ref().context("the session is closed")?;
        let stream = self.stream.as_mut().context("the session is closed")?;
        let request_len = u32::try_from(request_bytes)
            .ok()
            .filter(|&l| l != BENCH_SOCKET_DONE)
            .context("request too large")?;
        let reply_len = u32::try_from(reply_bytes).context("reply too large")?;
        let mut request = vec![0u8; 8 + request_bytes];
        request[..4].copy_from_slice(&request_len.to_le_bytes());
        request[4..8].copy_from_slice(&reply_len.to_le_bytes());
        for (k, b) in request[8..].iter_mut().enumerate() {
            *b = k as u8;
        }
        let mut reply = vec![0u8; reply_bytes];
        ports
            .ping
            .notify_with_custom_event_id(EventId::new(BENCH_EVENT_SOCKET))
            .context("switching to the socket")?;
        let mut out = Vec::with_capacity(count);
        for k in 0..warmup + count {
            let t0 = Instant::now();
            stream.write_all(&request).context("writing a request")?;
            stream.read_exact(&mut reply).context("reading a reply")?;
            let us = t0.elapsed().as_secs_f64() * 1e6;
            if k >= warmup {
                out.push(us);
            }
        }
        let mut back = [0u8; 8];
        back[..4].copy_from_slice(&BENCH_SOCKET_DONE.to_le_bytes());
        stream
            .write_all(&back)
            .context("switching back to iceoryx2")?;
        Ok(out)
    }

    /// Stop the process and clean up; errors of the cleanup are reported.
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.close()
    }

    fn close(&mut self) -> anyhow::Result<()> {
        if std::mem::replace(&mut self.closed, true) {
            return Ok(());
        }
        if let Some(ports) = &self.ports {
            let _ = ports
                .ping
                .notify_with_custom_event_id(EventId::new(EVENT_QUIT));
        }
        // A closed socket ends the process too, wherever it waits.
        drop(self.stream.take());
        self.procs.stop_all(Duration::from_secs(2));
        drop(self.ports.take());
        if let Some(node) = self.node.take() {
            runner::dead_nodes::cleanup_dead_nodes(&node, &self.prefix);
        }
        let _ = std::fs::remove_file(&self.socket_path);
        // SAFETY: the only other process of this prefix has exited and been reaped, and
        // the coordinator's node is dropped.
        unsafe { iceoryx2::testing::remove_global_mgmt_segment::<ipc::Service>(&self.config) }
            .context("removing the floor's management segment")?;
        wire::remove_run_root(&self.prefix).with_context(|| {
            format!(
                "removing the floor's folder {:?}",
                wire::run_root(&self.prefix)
            )
        })?;
        Ok(())
    }
}

impl Drop for PingPongSession {
    fn drop(&mut self) {
        if let Err(e) = self.close() {
            tracing::warn!("cleaning up the ping-pong: {e:#}");
        }
    }
}

/// Accept the ping-pong process's connection, watching the process while waiting.
fn accept(
    listener: &UnixListener,
    procs: &mut AgentProcesses,
    deadline: Instant,
) -> anyhow::Result<UnixStream> {
    listener.set_nonblocking(true)?;
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream.set_nonblocking(false)?;
                return Ok(stream);
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => {}
            Err(e) => return Err(e).context("accepting the ping-pong process"),
        }
        if procs.poll(0) == Exit::Exited {
            bail!("the ping-pong process exited before it connected (see its error above)");
        }
        if Instant::now() >= deadline {
            bail!("the ping-pong process did not connect in time");
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}
