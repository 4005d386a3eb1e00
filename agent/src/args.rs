//! The agent's command line.

use clap::Parser;
use wire::cgroup::Limits;
use wire::misbehave::Misbehave;

/// Command line of the agent process (normally started by the coordinator).
#[derive(Debug, Parser)]
#[command(name = "agent", version, about = "One formation agent process")]
pub struct Args {
    /// The run's iceoryx2 prefix (given by the coordinator); not with `--connect`.
    /// `--run` is its older name.
    #[arg(
        long,
        alias = "run",
        required_unless_present = "connect",
        conflicts_with = "connect"
    )]
    pub prefix: Option<String>,
    /// Take turns over Zenoh from the coordinator's router at this endpoint
    /// (`tcp/HOST:PORT` or `tls/HOST:PORT`): an agent on another machine, started by the
    /// user.
    #[arg(long, value_name = "ENDPOINT")]
    pub connect: Option<net::Endpoint>,
    /// Relay mode (started by the coordinator): stand for an agent that takes its turns
    /// over Zenoh from the router at this endpoint.
    #[arg(long, value_name = "ENDPOINT", requires = "prefix")]
    pub relay: Option<net::Endpoint>,
    /// Relay mode: start the agent itself, on this host.
    #[arg(long, requires = "relay")]
    pub spawn_agent: bool,
    /// The folder of TLS files for a `tls/` endpoint: `ca.pem`, and this agent's
    /// `agent-I.pem` and `agent-I-key.pem` (a relay: `relay.pem`, `relay-key.pem`).
    #[arg(long, value_name = "DIR")]
    pub tls_dir: Option<std::path::PathBuf>,
    /// Allow plain TCP to a host beyond the loopback (anyone on the network could join
    /// or listen).
    #[arg(long)]
    pub allow_plain_tcp: bool,
    /// Leave when the parent process dies (set by a relay for the agent it starts).
    #[arg(long, hide = true)]
    pub die_with_parent: bool,
    /// Having read the mission, wait until standard input ends before opening anything
    /// (set by the coordinator, which starts its agents before it makes the run's
    /// channels, while it has few open files for every start to copy, and closes the
    /// other end once they exist).
    #[arg(long, hide = true)]
    pub gate_stdin: bool,
    /// This agent's index in the formation.
    #[arg(long)]
    pub agent: usize,
    /// The SHA-256 digest of the run's mission file (given by the coordinator): a file
    /// that does not match is refused.
    #[arg(long, value_name = "HEX")]
    pub mission_sha256: Option<wire::MissionDigest>,
    /// Which process of this agent this is: 0 for the first, one more for every
    /// replacement; each generation has services of its own (given by the coordinator).
    #[arg(long, default_value_t = 0)]
    pub generation: u32,
    /// How often to check that the coordinator is still there while waiting, in ms. Only
    /// a backstop: on Linux the kernel sends SIGTERM the moment the coordinator dies, so
    /// an idle agent sleeps without waking (zero CPU). Over Zenoh an agent looks at the
    /// coordinator's token at least every 250 ms (a local look) and leaves once it has
    /// been gone for a lease.
    #[arg(long, default_value_t = 10_000)]
    pub liveness_ms: u64,
    /// Test mode, only in an agent built with `--features misbehave`: misbehave or
    /// attack on purpose (the coordinator must survive it): nan, teleport,
    /// through-obstacle, silent, garbage, overspeed, raw-length, raw-length-ready, replay,
    /// early, flood, impersonate=AGENT, spoof-ready=AGENT, hoard, fork, exit-before-ready,
    /// killed-connecting, deaf-to-prepare, late-some, sluggish, log-flood; against a
    /// sandbox only: scribble, stop-others, rewrite-mission, fork-bomb, fill-tmp,
    /// tty-push, kill-twin. A shipping agent (built without the feature) does not list it
    /// and refuses it in one line saying how to build one with it.
    #[arg(long, hide = cfg!(not(feature = "misbehave")))]
    pub misbehave: Option<Misbehave>,
    /// Sandbox relay mode (started by the coordinator as root): start this agent as user
    /// and group UID, in a sandbox, and stand for it on the run's channels.
    #[arg(long, value_name = "UID", requires = "prefix", conflicts_with_all = ["connect", "relay"])]
    pub sandbox_uid: Option<u32>,
    /// With `--sandbox-uid`: put the agent in a control group of its own below the run's
    /// (`formation-PREFIX`, which the coordinator made), with the limits below; without
    /// it, only the per-user process limit holds.
    #[arg(long, requires = "sandbox_uid")]
    pub cgroup: bool,
    /// With `--sandbox-uid`: processes and threads the agent may have at most.
    #[arg(long, default_value_t = Limits::default().pids_max)]
    pub pids_max: u32,
    /// With `--sandbox-uid --cgroup`: memory the agent may use at most, in MiB.
    #[arg(long, default_value_t = Limits::default().memory_mib)]
    pub memory_mib: u64,
    /// With `--sandbox-uid --cgroup`: CPU the agent may use at most, in percent of one
    /// core.
    #[arg(long, default_value_t = Limits::default().cpu_percent)]
    pub cpu_percent: u32,
    /// A sandboxed agent (started by its sandbox relay): take turns over the socket
    /// inherited as this descriptor.
    #[arg(long, value_name = "FD", hide = true, conflicts_with_all = ["connect", "relay", "sandbox_uid"])]
    pub socket_fd: Option<i32>,
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// The help reads as text: no rustdoc link markup from the doc comments.
    #[test]
    fn the_help_shows_no_rustdoc_markup() {
        let mut command = super::Args::command();
        let text = command.render_long_help().to_string();
        for markup in ["[`", "`]", "]("] {
            assert!(
                !text.contains(markup),
                "`agent --help` shows {markup}:\n{text}"
            );
        }
    }
}
