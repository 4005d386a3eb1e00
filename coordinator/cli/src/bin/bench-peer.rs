//! `bench-peer --prefix PREFIX --agent 0 [--uds PATH]`: the other end of the latency floor
//! that `coordinator bench` measures in the same run as the turns (see the bench's
//! `floor` module). A program of the bench's own, started by `coordinator bench` from
//! beside its executable; the shipping agent knows nothing of it.
//!
//! - iceoryx2: the same wake-up as a turn. The process blocks in
//!   `Listener::timed_wait` on [`BENCH_PING_EVENT`]; on a ping it takes the small
//!   [`BenchPing`] sample, publishes one back on [`BENCH_PONG_SERVICE`] and rings
//!   [`BENCH_PONG_EVENT`].
//! - Unix domain socket (with `--uds`), what a user would otherwise pick: the process
//!   connects to the coordinator's socket at start-up. On [`BENCH_EVENT_SOCKET`] it
//!   reads framed requests (`u32` request length, `u32` reply length, request bytes)
//!   with blocking reads and writes a reply of the asked length, until the header
//!   [`BENCH_SOCKET_DONE`] sends it back to the iceoryx2 ping-pong.
//! - iceoryx2 busy-polled (on [`BENCH_EVENT_SPIN`]): the process spins on the ping
//!   subscriber and publishes each pong at once, no event either way, until the ping
//!   [`BENCH_SPIN_DONE`]: the floor of publish-subscribe without any wake-up.
//! - iceoryx2 rung by doorbells (on [`BENCH_EVENT_DOORBELL`]): the process sleeps on its
//!   word of the session's doorbells, answers each ping rung there with a pong counted
//!   on the answer counter, and goes back to events when its word rings
//!   [`BENCH_EVENT_DOORBELL`]: the floor of a turn rung by doorbells.
//!
//! The coordinator alternates them in blocks, so all see the same machine.
//! [`EVENT_QUIT`], a closed socket, SIGTERM or the coordinator's death end the process.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Parser;
use iceoryx2::node::NodeWaitFailure;
use iceoryx2::port::listener::ListenerWaitError;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2_bb_posix::signal::SignalHandler;
use nix::unistd::getppid;
use wire::{
    BENCH_EVENT_DOORBELL, BENCH_EVENT_SOCKET, BENCH_EVENT_SPIN, BENCH_PING_EVENT,
    BENCH_PING_SERVICE, BENCH_PONG_EVENT, BENCH_PONG_SERVICE, BENCH_SOCKET_DONE, BENCH_SPIN_DONE,
    BenchPing, EVENT_QUIT, EVENT_TURN, Role,
};

/// Command line of the ping-pong process (started by `coordinator bench` as it starts an
/// agent: `--prefix PREFIX --agent 0` first).
#[derive(Debug, Parser)]
#[command(
    name = "bench-peer",
    version,
    about = "The other end of `coordinator bench`'s latency floor"
)]
struct Args {
    /// The bench session's iceoryx2 prefix.
    #[arg(long)]
    prefix: String,
    /// The index the session starts it as (always 0; unused).
    #[arg(long, default_value_t = 0)]
    agent: usize,
    /// The coordinator's Unix socket for the socket ping-pong.
    #[arg(long)]
    uds: Option<PathBuf>,
    /// How often to check that the coordinator is still there while waiting, in ms.
    #[arg(long, default_value_t = 10_000)]
    liveness_ms: u64,
}

fn main() -> ExitCode {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Warn);
    runner::logging::init();
    let args = Args::parse();
    let liveness = Duration::from_millis(args.liveness_ms.max(1));
    match serve(&args.prefix, args.uds.as_deref(), liveness) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!("bench-peer: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Serve the ping-pong of run `prefix` (and the socket at `uds`, if given).
/// `liveness` is how often the process checks that the coordinator is still there.
fn serve(prefix: &str, uds: Option<&Path>, liveness: Duration) -> anyhow::Result<()> {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_pdeathsig(nix::sys::signal::Signal::SIGTERM);
    let parent = getppid();
    // Join only a session that exists, through a folder no other user can reach.
    if let Some(root) = wire::run_root(prefix) {
        wire::check_run_root(&root).with_context(|| format!("opening run {prefix}"))?;
    }
    // Connect first: the coordinator accepts while it waits for the handshake below.
    let mut stream = uds
        .map(|p| UnixStream::connect(p).with_context(|| format!("connecting to {}", p.display())))
        .transpose()?;

    let config = wire::ipc_config(prefix, Role::Agent)?;
    let node = NodeBuilder::new()
        .name(&NodeName::new("pingpong").context("the node's name")?)
        .config(&config)
        .create::<ipc::Service>()
        .context("creating the node")?;
    // Install iceoryx2's signal handlers: SIGTERM interrupts the waits below.
    let _ = node.wait(Duration::ZERO);
    let name = |s: &str| ServiceName::new(s).with_context(|| format!("service name {s}"));
    let ping_sub = node
        .service_builder(&name(BENCH_PING_SERVICE)?)
        .publish_subscribe::<BenchPing>()
        .open()
        .with_context(|| format!("opening {BENCH_PING_SERVICE}"))?
        .subscriber_builder()
        .create()
        .context("ping subscriber")?;
    let pong_pub = node
        .service_builder(&name(BENCH_PONG_SERVICE)?)
        .publish_subscribe::<BenchPing>()
        .open()
        .with_context(|| format!("opening {BENCH_PONG_SERVICE}"))?
        .publisher_builder()
        .max_loaned_samples(1)
        .create()
        .context("pong publisher")?;
    let ping_listener = node
        .service_builder(&name(BENCH_PING_EVENT)?)
        .event()
        .open()
        .with_context(|| format!("opening {BENCH_PING_EVENT}"))?
        .listener_builder()
        .create()
        .context("ping listener")?;
    let pong_notifier = node
        .service_builder(&name(BENCH_PONG_EVENT)?)
        .event()
        .open()
        .with_context(|| format!("opening {BENCH_PONG_EVENT}"))?
        .notifier_builder()
        .create()
        .context("pong notifier")?;

    let pong = |seq: u64| -> anyhow::Result<()> {
        pong_pub
            .send_copy(BenchPing {
                seq,
                payload: [seq; 3],
            })
            .context("sending a pong")?;
        pong_notifier.notify().context("notifying the pong")?;
        Ok(())
    };
    pong(0)?; // ready
    // Opened when first asked for the doorbell ping-pong.
    let mut doorbells: Option<wire::Doorbells> = None;

    loop {
        if SignalHandler::termination_requested() {
            return Ok(());
        }
        let waited = Instant::now();
        let (mut ping, mut socket, mut quit, mut spin, mut doorbell) =
            (false, false, false, false, false);
        let woke = ping_listener.timed_wait(
            |event| match event.id.as_value() {
                EVENT_TURN => ping = true,
                BENCH_EVENT_SOCKET => socket = true,
                BENCH_EVENT_SPIN => spin = true,
                BENCH_EVENT_DOORBELL => doorbell = true,
                EVENT_QUIT => quit = true,
                _ => {}
            },
            liveness,
        );
        match woke {
            Ok(_) if quit => return Ok(()),
            Ok(_) if spin => {
                // Busy-poll until the closing ping, or for at most a liveness period of
                // silence (the coordinator gone or stuck).
                let mut heard = Instant::now();
                loop {
                    if let Some(s) = ping_sub.receive().context("receiving a ping")? {
                        let seq = s.seq;
                        drop(s);
                        pong_pub
                            .send_copy(BenchPing {
                                seq,
                                payload: [seq; 3],
                            })
                            .context("sending a pong")?;
                        if seq == BENCH_SPIN_DONE {
                            break;
                        }
                        heard = Instant::now();
                    } else if heard.elapsed() >= liveness {
                        break;
                    } else {
                        std::hint::spin_loop();
                    }
                }
            }
            Ok(_) if doorbell => {
                let bells = match &doorbells {
                    Some(bells) => bells,
                    None => doorbells
                        .insert(wire::Doorbells::open(prefix, 0).context("opening the doorbells")?),
                };
                if !serve_doorbell(bells, &ping_sub, &pong_pub, liveness)? {
                    return Ok(());
                }
            }
            Ok(_) if socket => {
                let stream = stream
                    .as_mut()
                    .context("asked for the socket ping-pong without --uds")?;
                if !serve_socket(stream, &node)? {
                    return Ok(());
                }
            }
            Ok(_) if ping => {
                let mut last = None;
                while let Some(s) = ping_sub.receive().context("receiving a ping")? {
                    last = Some(s.seq);
                }
                if let Some(seq) = last {
                    pong(seq)?;
                }
            }
            // Timed out, or woke early with nothing: check the coordinator on the clock.
            Ok(_) => {
                if waited.elapsed() >= liveness && getppid() != parent {
                    return Ok(());
                }
            }
            Err(ListenerWaitError::InterruptSignal) => {
                if let Err(NodeWaitFailure::TerminationRequest) = node.wait(Duration::ZERO) {
                    return Ok(());
                }
            }
            Err(e) => return Err(e).context("waiting for a ping"),
        }
    }
}

/// Answer the pings rung on `bells` (agent 0's word) with a pong each, counted on the
/// answer counter: true when rung back to the event ping-pong (or silent for `liveness`:
/// the event loop then looks at the coordinator), false when SIGTERM came.
fn serve_doorbell(
    bells: &wire::Doorbells,
    ping_sub: &Subscriber<ipc::Service, BenchPing, ()>,
    pong_pub: &Publisher<ipc::Service, BenchPing, ()>,
    liveness: Duration,
) -> anyhow::Result<bool> {
    let mut heard = Instant::now();
    loop {
        let (rung, woken) = bells.wait(0, liveness).context("waiting on the doorbell")?;
        if rung & (1 << EVENT_TURN) != 0 {
            let mut last = None;
            while let Some(s) = ping_sub.receive().context("receiving a ping")? {
                last = Some(s.seq);
            }
            if let Some(seq) = last {
                pong_pub
                    .send_copy(BenchPing {
                        seq,
                        payload: [seq; 3],
                    })
                    .context("sending a pong")?;
                bells.answer();
            }
            heard = Instant::now();
        }
        if rung & (1 << BENCH_EVENT_DOORBELL) != 0 || heard.elapsed() >= liveness {
            return Ok(true);
        }
        if woken == wire::Woken::Interrupted && SignalHandler::termination_requested() {
            return Ok(false);
        }
    }
}

/// Answer framed requests on `stream`: true when sent back to the iceoryx2 ping-pong,
/// false when the coordinator closed the socket (or SIGTERM came).
fn serve_socket(stream: &mut UnixStream, node: &Node<ipc::Service>) -> anyhow::Result<bool> {
    let mut header = [0u8; 8];
    let mut request = Vec::new();
    let mut reply = Vec::new();
    loop {
        if !read_full(stream, &mut header, node)? {
            return Ok(false);
        }
        let [a, b, c, d, e, f, g, h] = header;
        let request_len = u32::from_le_bytes([a, b, c, d]);
        if request_len == BENCH_SOCKET_DONE {
            return Ok(true);
        }
        let request_len = request_len as usize;
        let reply_len = u32::from_le_bytes([e, f, g, h]) as usize;
        request.resize(request_len, 0);
        if !read_full(stream, &mut request, node)? {
            return Ok(false);
        }
        reply.resize(reply_len, 0);
        // Echo the head of the request, so the reply depends on what was read.
        let n = reply_len.min(request_len);
        reply[..n].copy_from_slice(&request[..n]);
        stream.write_all(&reply).context("writing a reply")?;
    }
}

/// Fill `buf` from `stream`; false on a clean end of stream (or a termination request).
fn read_full(
    stream: &mut UnixStream,
    buf: &mut [u8],
    node: &Node<ipc::Service>,
) -> anyhow::Result<bool> {
    let mut filled = 0;
    while filled < buf.len() {
        match stream.read(&mut buf[filled..]) {
            Ok(0) => return Ok(false),
            Ok(n) => filled += n,
            // iceoryx2's handlers are installed without SA_RESTART: a SIGTERM lands here.
            Err(e) if e.kind() == ErrorKind::Interrupted => {
                if let Err(NodeWaitFailure::TerminationRequest) = node.wait(Duration::ZERO) {
                    return Ok(false);
                }
            }
            Err(e) => return Err(e).context("reading a request"),
        }
    }
    Ok(true)
}
