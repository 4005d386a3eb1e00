//! One formation agent: it waits for its turn, reads the world, computes its slot, best
//! point and path with [`shared::control::turn::BestPointController`], and publishes its move.
//!
//! The turn loop, [`serve`] (in `serve.rs`), talks to the world only through the [`Transport`] trait, so
//! it runs the same over iceoryx2 ([`ipc::IpcTransport`]) and in-process in tests.
//!
//! Features: `zenoh`, agents on other machines; `misbehave`, the test modes
//! (`--misbehave MODE`, [`misbehave`]), which a shipping agent is built without. A role
//! meets its test mode as one value (`test_mode.rs`) that opens its transport and serves
//! turns as the mode has it, so [`run`] reads the same with the feature on or off.

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
mod test_mode;
pub mod transport;

use std::time::Duration;

use anyhow::{Context, bail};

pub use args::Args;
pub use serve::serve;
#[cfg(not(feature = "misbehave"))]
pub use test_mode::NO_MISBEHAVE;
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

/// Open the run's services and serve turns until told to stop or the coordinator is gone.
pub fn run(args: &Args) -> anyhow::Result<()> {
    launch::die_with_the_coordinator()?;
    let mode = test_mode::TestMode::asked(args)?;
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
            return mode.serve(transport);
        }
        #[cfg(not(feature = "zenoh"))]
        bail!("{NO_ZENOH}");
    }
    let Some(prefix) = args.prefix.as_deref() else {
        bail!("either --prefix (started by the coordinator) or --connect ENDPOINT");
    };
    if let Some(fd) = args.socket_fd {
        return socket_transport::serve_sandboxed_agent(args, prefix, fd, mode);
    }
    // Join only a run that exists (a node opened for no run would leave files behind),
    // and only through a folder no other user can reach (ours, 0700, not a link).
    if let Some(root) = wire::run_root(prefix) {
        wire::check_run_root(&root).with_context(|| format!("opening run {prefix}"))?;
    }
    // The mission is read before the gate, while the coordinator makes the channels. A
    // relay has no test mode of its own: it passes its agent's on.
    let is_relay = args.sandbox_uid.is_some() || args.relay.is_some();
    let mode = if is_relay { mode.none() } else { mode };
    let mission = mode
        .read_mission(prefix, args.mission_sha256)
        .with_context(|| format!("opening run {prefix}"))?;
    if args.gate_stdin {
        launch::pass_the_gate()?;
    }
    if let Some(uid) = args.sandbox_uid {
        return sandbox_relay::run_sandbox_relay(args, prefix, uid, liveness, &mission);
    }
    if let Some(connect) = &args.relay {
        net::check_security(connect, &security, args.allow_plain_tcp)?;
        #[cfg(feature = "zenoh")]
        return relay::run_relay(args, prefix, connect, &security, liveness, &mission);
        #[cfg(not(feature = "zenoh"))]
        bail!("{NO_ZENOH}");
    }
    // The agent keeps what it sees of the mission, not the file's text.
    let ipc::Mission { view, text } = mission;
    drop(text);
    mode.serve_ipc(prefix, || {
        ipc::IpcTransport::open(prefix, args.agent, args.generation, liveness, view)
            .with_context(|| format!("opening run {prefix}"))
    })
}
