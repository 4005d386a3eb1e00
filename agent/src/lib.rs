//! One formation agent: it waits for its turn, reads the world, computes its slot, best
//! point and path with [`shared::turn::BestPointController`], and publishes its move.
//!
//! The turn loop, [`serve`] (in `serve.rs`), talks to the world only through the [`Transport`] trait, so
//! it runs the same over iceoryx2 ([`ipc::IpcTransport`]) and in-process in tests.
//!
//! Features: `zenoh`, agents on other machines; `misbehave`, the test modes
//! (`--misbehave MODE`, [`misbehave`]), which a shipping agent is built without.

mod args;
pub mod forward;
pub mod ipc;
mod launch;
pub mod link;
#[cfg(feature = "misbehave")]
pub mod misbehave;
#[cfg(feature = "zenoh")]
pub mod net_transport;
#[cfg(feature = "zenoh")]
pub mod relay;
pub mod sandbox;
pub mod sandbox_relay;
mod serve;
pub mod socket_link;
pub mod socket_transport;
pub mod transport;

use std::time::Duration;

use anyhow::{Context, bail};
use wire::cgroup::Limits;
use wire::misbehave::Misbehave;

pub use args::Args;
pub use serve::serve;
pub use transport::{Command, Reply, Transport, TurnInput};

/// Install the stderr logger (`RUST_LOG`, default `warn`; other crates' lines within a
/// budget, [`wire::logging`]) and set iceoryx2's own log level.
pub fn init_logging() {
    use iceoryx2::prelude::{LogLevel, set_log_level_from_env_or};
    set_log_level_from_env_or(LogLevel::Warn);
    wire::logging::init("warn");
}

/// What an agent built without Zenoh says when asked to use it.
#[cfg(not(feature = "zenoh"))]
const NO_ZENOH: &str = "this agent was built without Zenoh: build it with `cargo build --release --features zenoh -p agent -p coordinator`";

/// What an agent built without its test modes says when asked for one.
#[cfg(not(feature = "misbehave"))]
pub const NO_MISBEHAVE: &str = "this agent was built without its test modes: build it with `cargo build --release --features misbehave -p agent`";

/// The test mode asked for; an agent built without the test modes refuses any.
fn test_mode(args: &Args) -> anyhow::Result<Option<Misbehave>> {
    #[cfg(not(feature = "misbehave"))]
    if let Some(mode) = args.misbehave {
        bail!("--misbehave {mode}: {NO_MISBEHAVE}");
    }
    Ok(args.misbehave)
}

/// Serve turns over `transport`, as test mode `mode` has it if one is given.
fn serve_as<T: Transport>(
    transport: T,
    agent: usize,
    mode: Option<Misbehave>,
) -> anyhow::Result<()> {
    #[cfg(feature = "misbehave")]
    if let Some(mode) = mode {
        return serve(
            &mut misbehave::Misbehaving::new(transport, agent, mode),
            agent,
        );
    }
    #[cfg(not(feature = "misbehave"))]
    let _ = mode;
    let mut transport = transport;
    serve(&mut transport, agent)
}

/// Open the run's services and serve turns until told to stop or the coordinator is gone.
pub fn run(args: &Args) -> anyhow::Result<()> {
    launch::die_with_the_coordinator()?;
    let mode = test_mode(args)?;
    let liveness = Duration::from_millis(args.liveness_ms.max(1));
    if args.die_with_parent {
        #[cfg(target_os = "linux")]
        let _ = nix::sys::prctl::set_pdeathsig(nix::sys::signal::Signal::SIGKILL);
    }
    // An agent shows its own certificate; a relay, the relays'.
    let role = if args.relay.is_some() {
        net::Role::Relay
    } else {
        net::Role::Agent(args.agent)
    };
    let security = match &args.tls_dir {
        Some(dir) => net::Security::Tls(net::TlsFiles::in_dir(dir, role)),
        None => net::Security::Plain,
    };
    if let Some(connect) = &args.connect {
        net::check_security(connect, &security, args.allow_plain_tcp)?;
        #[cfg(feature = "zenoh")]
        {
            let transport =
                net_transport::NetTransport::connect(connect, &security, args.agent, liveness)?;
            return serve_as(transport, args.agent, mode);
        }
        #[cfg(not(feature = "zenoh"))]
        bail!("{NO_ZENOH}");
    }
    let Some(prefix) = args.prefix.as_deref() else {
        bail!("either --prefix (started by the coordinator) or --connect ENDPOINT");
    };
    if let Some(fd) = args.socket_fd {
        return serve_sandboxed_agent(args, prefix, fd, mode);
    }
    // Join only a run that exists (a node opened for no run would leave files behind),
    // and only through a folder no other user can reach (ours, 0700, not a link).
    if let Some(root) = wire::run_root(prefix) {
        wire::check_run_root(&root).with_context(|| format!("opening run {prefix}"))?;
    }
    // The mission is read before the gate, while the coordinator makes the channels (a
    // trusted agent's test-mode attack on the file comes first; a relay attacks nothing).
    #[cfg(feature = "misbehave")]
    if args.sandbox_uid.is_none()
        && args.relay.is_none()
        && let Some(mode) = mode
    {
        misbehave::before_reading(prefix, args.agent, mode);
    }
    let mission = ipc::Mission::read(prefix, args.mission_sha256)
        .with_context(|| format!("opening run {prefix}"))?;
    if args.gate_stdin {
        launch::pass_the_gate()?;
    }
    if let Some(uid) = args.sandbox_uid {
        return run_sandbox_relay(args, prefix, uid, liveness, &mission);
    }
    if let Some(connect) = &args.relay {
        net::check_security(connect, &security, args.allow_plain_tcp)?;
        #[cfg(feature = "zenoh")]
        return run_relay(args, prefix, connect, &security, liveness, &mission);
        #[cfg(not(feature = "zenoh"))]
        bail!("{NO_ZENOH}");
    }
    // A test mode's attacks on other agents' channels come first, to race their owners.
    #[cfg(feature = "misbehave")]
    let _held = match mode {
        Some(mode) => misbehave::before_opening(prefix, args.agent, mode)?,
        None => Vec::new(),
    };
    // The agent keeps what it sees of the mission, not the file's text.
    let ipc::Mission { view, text } = mission;
    drop(text);
    let transport = ipc::IpcTransport::open(prefix, args.agent, args.generation, liveness, view)
        .with_context(|| format!("opening run {prefix}"))?;
    #[cfg(feature = "misbehave")]
    if let Some(mode) = mode {
        return misbehave::serve_ipc(transport, args.agent, mode);
    }
    serve_as(transport, args.agent, mode)
}

/// The channel of agent `args.agent` in run `prefix`, as a relay opens it.
fn relayed_channel<'a>(
    args: &Args,
    prefix: &'a str,
    liveness: Duration,
    mission: &'a ipc::Mission,
) -> forward::RelayedChannel<'a> {
    forward::RelayedChannel {
        prefix,
        agent: args.agent,
        generation: args.generation,
        mission,
        liveness,
    }
}

/// Serve as the sandbox relay of agent `args.agent` ([`sandbox_relay::serve_sandboxed`]):
/// the agent is started here as user `uid`, with this agent's test mode.
fn run_sandbox_relay(
    args: &Args,
    prefix: &str,
    uid: u32,
    liveness: Duration,
    mission: &ipc::Mission,
) -> anyhow::Result<()> {
    let limits = Limits {
        pids_max: args.pids_max,
        memory_mib: args.memory_mib,
        cpu_percent: args.cpu_percent,
    };
    let cgroup = if args.cgroup {
        let run = wire::cgroup::CgroupDirs::for_run(prefix).context("the run's control group")?;
        Some(run.child(&format!("agent-{}-{}", args.agent, args.generation)))
    } else {
        None
    };
    let agent_args = match args.misbehave {
        Some(mode) => vec!["--misbehave".to_string(), mode.to_string()],
        None => Vec::new(),
    };
    sandbox_relay::serve_sandboxed(&sandbox_relay::SandboxRelaySettings {
        channel: relayed_channel(args, prefix, liveness, mission),
        sandbox: sandbox::Sandbox {
            uid,
            cgroup,
            limits,
        },
        agent_args,
    })
}

/// Serve as a sandboxed agent over the socket `fd` its relay handed it. Its test mode's
/// attacks on the run's shared memory are tried as they would be by any agent (its user
/// can open none of it); its moves misbehave as asked.
fn serve_sandboxed_agent(
    args: &Args,
    prefix: &str,
    fd: i32,
    mode: Option<Misbehave>,
) -> anyhow::Result<()> {
    #[cfg(feature = "misbehave")]
    let _held = match mode {
        Some(mode) => misbehave::before_opening(prefix, args.agent, mode)?,
        None => Vec::new(),
    };
    #[cfg(not(feature = "misbehave"))]
    let _ = prefix;
    if mode == Some(Misbehave::ExitBeforeReady) {
        std::process::exit(3);
    }
    // SAFETY: the relay handed this descriptor over; nothing else in this process owns it.
    let transport = unsafe { socket_transport::SocketTransport::from_fd(fd, args.agent) };
    serve_as(transport, args.agent, mode)
}

/// Serve as the relay of agent `args.agent` ([`relay::serve_relay`]); with `--spawn-agent`, the
/// agent is started here, with this agent's test mode and settings.
#[cfg(feature = "zenoh")]
fn run_relay(
    args: &Args,
    prefix: &str,
    connect: &net::Endpoint,
    security: &net::Security,
    liveness: Duration,
    mission: &ipc::Mission,
) -> anyhow::Result<()> {
    let mut extra = vec!["--die-with-parent".to_string()];
    if let Some(mode) = args.misbehave {
        extra.extend(["--misbehave".to_string(), mode.to_string()]);
    }
    if args.allow_plain_tcp {
        extra.push("--allow-plain-tcp".to_string());
    }
    relay::serve_relay(&relay::RelaySettings {
        channel: relayed_channel(args, prefix, liveness, mission),
        connect,
        security,
        tls_dir: args.tls_dir.as_deref(),
        spawn_agent: args.spawn_agent.then_some(extra),
    })
}
