//! The command line (clap).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use shared::control::vocabulary::ControllerKind;
use wire::cgroup::Limits;
use wire::misbehave::Misbehave;

use runner::names::{parse_controller, parse_misbehave};
use runner::network::TransportKind;
use runner::turns::{SandboxOptions, WaitMode, WakeMode};
use tools::bench::BenchArgs;
use tools::bound::BoundArgs;
use tools::compare::CompareArgs;
use tools::render::RenderArgs;

/// Decentralized formation control with collision avoidance: each agent its own process,
/// talking over iceoryx2 shared memory.
#[derive(Debug, Parser)]
#[command(name = "coordinator", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check a scenario file (including that the centre has a path), or a map's YAML file
    /// (ROS map_server: the YAML and its image); plan nothing else.
    Validate(ValidateArgs),
    /// Plan the formation centre's path with Hybrid A* and write it as CSV.
    Plan(PlanArgs),
    /// Run a scenario with one agent process per agent and write the outputs.
    Run(RunArgs),
    /// Run a scenario in this process with the reference simulation (no agent process)
    /// and time it: the yardstick of the multi-process run (JSON on stdout).
    Simulate(SimulateArgs),
    /// The least mean and largest deviation any controller can reach with the agents'
    /// top speeds (each agent alone, along its known slot track: a cone programme, and a
    /// grid round the obstacles its slot enters), and the reference simulation's against
    /// them (JSON on stdout)
    Bound(BoundArgs),
    /// Run every controller on every scenario and tabulate safety, deviation, deadlocks and
    /// compute time (CSV and Markdown).
    Compare(CompareArgs),
    /// Draw the plots (PNG and SVG) and the animation (GIF) of a run directory into
    /// RUN_DIR/plots/, from the files `run` wrote (nothing is re-planned).
    Render(RenderArgs),
    /// Measure turn latency over real agent processes against the iceoryx2 floor and a
    /// Unix socket (JSON on stdout, a table on stderr, a histogram SVG beside --out).
    Bench(BenchArgs),
}

/// Arguments of `run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The scenario file (TOML); the embedded paper example when omitted.
    pub scenario: Option<PathBuf>,
    /// Output folder (default `runs/<name>-<UTC time>`). One that exists and is not
    /// empty is refused unless `--force`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the `--out` folder whole when it exists and is not empty (the new run is
    /// written beside it and swapped in; no old file survives).
    #[arg(long)]
    pub force: bool,
    /// The agent executable (default: `agent` beside this program).
    #[arg(long)]
    pub agent_bin: Option<PathBuf>,
    /// Turn deadline in milliseconds: an agent that has not answered by then is checked
    /// on and, if dead, frozen as an obstacle.
    #[arg(long, default_value_t = 250)]
    pub turn_deadline_ms: u64,
    /// The slow bound in milliseconds (default: a fifth of the turn deadline, half for a
    /// car agent): an agent that answers 3 of its last 10 turns later than this is
    /// recorded `slow`, killed and frozen, as one that misses 3 of its last 10 is `hung`.
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..))]
    pub slow_turn_ms: Option<u64>,
    /// The controller, overriding the scenario's `controller` (best-point, cbf,
    /// zcbf-logsumexp, orca).
    #[arg(long, alias = "planner", value_parser = parse_controller)]
    pub controller: Option<ControllerKind>,
    /// Start a replacement process for every agent that dies; it re-joins from where the
    /// dead one stood and takes its slot again.
    #[arg(long)]
    pub respawn: bool,
    /// Fault injection: kill agent AGENT with SIGKILL during its turn at step STEP
    /// (repeatable), e.g. `--kill-agent 2@40`.
    #[arg(long = "kill-agent", value_name = "AGENT@STEP", value_parser = parse_kill)]
    pub kill_agent: Vec<(usize, usize)>,
    /// Deterministic fault injection: agent AGENT dies at step STEP, killed with SIGKILL
    /// just before its group's turns (repeatable), e.g. `--die-agent 2@40`: unlike
    /// `--kill-agent`, nothing races with its answer, so the run is the same every time.
    #[arg(long = "die-agent", value_name = "AGENT@STEP", value_parser = parse_kill)]
    pub die_agent: Vec<(usize, usize)>,
    /// Go on with the run killed in DIR from the last step its `run.mcap` holds: the
    /// scenario, the centre plan and the options that change the record (turn deadline,
    /// respawn, kills, deaths, misbehaviour) are the log's; the world at that step is
    /// rebuilt from it, the agents alive then are started, and the run goes on and
    /// writes its outputs into DIR. A SCENARIO given too must be the one logged.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "force", "controller", "respawn", "kill_agent", "die_agent", "misbehave", "slow_turn_ms"])]
    pub resume: Option<PathBuf>,
    /// Test mode: agent AGENT misbehaves or attacks on purpose: nan, teleport,
    /// through-obstacle, silent, garbage, overspeed (unsafe moves); raw-length,
    /// raw-length-ready, replay, early, flood, impersonate=J, spoof-ready=J, hoard, fork,
    /// exit-before-ready, killed-connecting (attacks on the protocol); deaf-to-prepare (an agent that ignores
    /// `--wait spin`'s notice); late-some, sluggish (late agents); log-flood, scribble, stop-others,
    /// rewrite-mission, fork-bomb (attacks a `--sandbox` must hold against); repeatable,
    /// e.g. `--misbehave 3=nan`.
    #[arg(long, value_name = "AGENT=MODE", value_parser = parse_misbehave)]
    pub misbehave: Vec<(usize, Misbehave)>,
    /// Do not draw the plots and the animation (`coordinator render DIR` draws them
    /// later).
    #[arg(long)]
    pub no_plots: bool,
    /// Sync the run log (`run.mcap`) to the disk every N steps; by default at most once a
    /// second. Every step is in the file when it ends either way: this bounds what a
    /// power cut, not a crash, can cost.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub sync_every_steps: Option<u32>,
    /// In the animation, draw each live agent's sensing radius as a faint circle (when
    /// the scenario has `formation.sensing_radius_m`).
    #[arg(long)]
    pub sensing_circles: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// How turns are handed over: `block` (both sides sleep between turns: no CPU spent
    /// waiting, two wake-ups per turn), `spin` (the coordinator spins on the state and the
    /// next agent on its world, for at most a millisecond or two: no wake-up on the
    /// turn's path, up to two busy cores while turns go on), `auto` (spin with two
    /// cores or more, block on one).
    #[arg(long, value_enum, default_value_t = WaitMode::Auto)]
    pub wait: WaitMode,
    /// How the coordinator and the agents wake each other: `doorbell` (a futex word per
    /// agent and an answer counter in the run's private folder: a ring is a store and at
    /// most one system call) or `event` (iceoryx2 events: a datagram socket per listener).
    #[arg(long, value_enum, default_value_t = WakeMode::Doorbell)]
    pub wake: WakeMode,
    /// How agents reach the coordinator: `--transport` and the Zenoh options.
    #[command(flatten)]
    pub network: NetworkArgs,
    /// How the agents are sandboxed: `--sandbox` and its limits.
    #[command(flatten)]
    pub sandbox: SandboxArgs,
}

/// How the agents are sandboxed.
#[derive(Clone, Debug, Args)]
pub struct SandboxArgs {
    /// Run each agent in a sandbox (the default as root; refused without): a user of its
    /// own (`--agent-uids`), a control group of its own with the limits below, no new
    /// privileges, no descriptor but its link, behind a relay of the coordinator's user
    /// that alone opens the run's shared memory. Over `--transport zenoh`, the agents
    /// this host starts (the remote ones are their hosts' to sandbox).
    #[arg(long, conflicts_with = "trusted_agents")]
    pub sandbox: bool,
    /// Trust the agents: each runs as the coordinator's user on the run's channels itself
    /// (the default without root). About twice as fast a turn as the sandbox's; what
    /// still holds is in the README's threat model.
    #[arg(long)]
    pub trusted_agents: bool,
    /// With `--sandbox`: the first agent's user id; agent I runs as user and group
    /// FIRST + I.
    #[arg(long, value_name = "FIRST", default_value_t = SandboxOptions::DEFAULT_FIRST_UID)]
    pub agent_uids: u32,
    /// With `--sandbox`: processes and threads an agent may have at most.
    #[arg(long, value_name = "N", default_value_t = Limits::default().pids_max, value_parser = clap::value_parser!(u32).range(4..))]
    pub agent_pids_max: u32,
    /// With `--sandbox`: memory an agent may use at most, in MiB.
    #[arg(long, value_name = "MIB", default_value_t = Limits::default().memory_mib, value_parser = clap::value_parser!(u64).range(16..))]
    pub agent_memory_mib: u64,
    /// With `--sandbox`: CPU an agent may use at most, in percent of one core.
    #[arg(long, value_name = "PERCENT", default_value_t = Limits::default().cpu_percent, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub agent_cpu_percent: u32,
}

impl SandboxArgs {
    /// `--sandbox` asked for, or implied by running as root; without root and without
    /// `--trusted-agents`, a warning says the agents are trusted.
    ///
    /// `zenoh_local_agents`: over Zenoh, how many agents this host starts (`None` over
    /// iceoryx2). They are sandboxed as over iceoryx2 (behind the sandbox's socket relay,
    /// with no key of their own); an agent started elsewhere is its own host's to
    /// sandbox, so a run whose agents are all remote has no sandbox here.
    pub fn options(
        &self,
        agents: usize,
        zenoh_local_agents: Option<usize>,
    ) -> Result<Option<SandboxOptions>, String> {
        let root = runner::turns::running_as_root();
        let none_here = zenoh_local_agents == Some(0);
        if self.sandbox && none_here {
            return Err(
                "--sandbox: every agent is remote (--remote), sandboxed by its own host".into(),
            );
        }
        if self.sandbox && !root {
            return Err(
                "--sandbox needs root (to give each agent a user and a control group of its own)"
                    .into(),
            );
        }
        if self.trusted_agents || none_here {
            return Ok(None);
        }
        if !root {
            tracing::warn!(
                "not root: the agents run as this user, trusted (see the README's threat model); --trusted-agents says so and silences this"
            );
            return Ok(None);
        }
        let last = u64::from(self.agent_uids) + agents as u64;
        if self.agent_uids == 0 || last > u64::from(u32::MAX) {
            return Err(format!(
                "--agent-uids {}: the {agents} agents' user ids must lie in 1 to {}",
                self.agent_uids,
                u32::MAX
            ));
        }
        Ok(Some(SandboxOptions {
            first_uid: self.agent_uids,
            limits: Limits {
                pids_max: self.agent_pids_max,
                memory_mib: self.agent_memory_mib,
                cpu_percent: self.agent_cpu_percent,
            },
        }))
    }
}

/// Arguments for agents over the network (`--transport zenoh`).
#[derive(Debug, Args)]
pub struct NetworkArgs {
    /// How agents reach the coordinator: `ipc` (shared memory, this host) or `zenoh`.
    #[arg(long, value_enum, default_value_t = TransportKind::Ipc)]
    pub transport: TransportKind,
    /// With `--transport zenoh`: where the coordinator's Zenoh router listens,
    /// `tls/HOST:PORT` (TLS with client certificates) or `tcp/HOST:PORT` (plain, with
    /// `--allow-plain-tcp` only).
    #[arg(long, value_name = "ENDPOINT", default_value = "tls/127.0.0.1:7447")]
    pub listen: net::Endpoint,
    /// With `--transport zenoh`: the agents the user starts elsewhere with
    /// `agent --connect ENDPOINT --agent I` (comma-separated); the coordinator starts the
    /// others on this host.
    #[arg(long, value_name = "AGENTS", value_delimiter = ',')]
    pub remote: Vec<usize>,
    /// With a `tls/` endpoint: the folder of TLS files, `ca.pem`, `coordinator.pem`,
    /// `relay.pem` and `agent-I.pem` for each agent started here, each with its
    /// `-key.pem` (`scripts/make-tls-dir --agents N DIR ADDRESS...`). Without it the run
    /// makes its own authority in its private folder (not with `--remote`).
    #[arg(long, value_name = "DIR")]
    pub tls_dir: Option<PathBuf>,
    /// Allow plain TCP (a `tcp/` endpoint), on the loopback too: anyone who reaches the
    /// port, another user of this machine included, could join and answer for an agent.
    #[arg(long)]
    pub allow_plain_tcp: bool,
}

impl NetworkArgs {
    /// The network options, `None` for `--transport ipc` (then the other flags must not be
    /// given).
    pub fn options(&self) -> Result<Option<runner::network::NetworkOptions>, String> {
        match self.transport {
            TransportKind::Ipc => {
                if !self.remote.is_empty() || self.tls_dir.is_some() || self.allow_plain_tcp {
                    return Err(
                        "--remote, --tls-dir and --allow-plain-tcp need --transport zenoh".into(),
                    );
                }
                Ok(None)
            }
            #[cfg(not(feature = "zenoh"))]
            TransportKind::Zenoh => Err(runner::network::NO_ZENOH.into()),
            #[cfg(feature = "zenoh")]
            TransportKind::Zenoh => Ok(Some(runner::network::NetworkOptions {
                listen: self.listen.clone(),
                remote: self.remote.clone(),
                tls_dir: self.tls_dir.clone(),
                allow_plain_tcp: self.allow_plain_tcp,
            })),
        }
    }
}

/// Arguments of `simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The scenario file (TOML); the embedded paper example when omitted.
    pub scenario: Option<PathBuf>,
    /// The controller, overriding the scenario's `controller`.
    #[arg(long, alias = "planner", value_parser = parse_controller)]
    pub controller: Option<ControllerKind>,
    /// Time this many runs and report each (the first is often slower: caches).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub repeat: u32,
}

/// `AGENT@STEP`.
fn parse_kill(s: &str) -> Result<(usize, usize), String> {
    let (a, t) = s
        .split_once('@')
        .ok_or_else(|| format!("{s:?}: expected AGENT@STEP, e.g. 2@40"))?;
    let agent = a
        .parse()
        .map_err(|_| format!("{a:?} is not an agent index"))?;
    let step = t
        .parse()
        .map_err(|_| format!("{t:?} is not a step number"))?;
    Ok((agent, step))
}

/// Arguments of `validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The scenario file (TOML), or a map's YAML file (`.yaml` or `.yml`).
    pub scenario: PathBuf,
}

/// Arguments of `plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The scenario file (TOML); the embedded paper example when omitted.
    pub scenario: Option<PathBuf>,
    /// Where to write the CSV (`step,x_m,y_m,heading_rad`); standard output when omitted.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Command {
        Cli::try_parse_from([&["coordinator"], args].concat())
            .expect("parses")
            .command
    }

    /// `--planner` and `--planners`, the flags' names before `--controller`, still work.
    #[test]
    fn the_older_flag_names_are_aliases_of_the_controller_flags() {
        for (old, new) in [
            (["run", "--planner", "cbf"], ["run", "--controller", "cbf"]),
            (
                ["simulate", "--planner", "orca"],
                ["simulate", "--controller", "orca"],
            ),
        ] {
            let kind = |c: Command| match c {
                Command::Run(a) => a.controller,
                Command::Simulate(a) => a.controller,
                _ => None,
            };
            let (old_kind, new_kind) = (kind(parse(&old)), kind(parse(&new)));
            assert!(old_kind.is_some(), "{old:?}");
            assert_eq!(old_kind, new_kind, "{old:?}");
        }
        let Command::Compare(a) = parse(&["compare", "--planners", "cbf,orca"]) else {
            panic!("not compare");
        };
        assert_eq!(a.controllers, [ControllerKind::Cbf, ControllerKind::Orca]);
        assert!(Cli::try_parse_from(["coordinator", "run", "--planer", "cbf"]).is_err());
    }

    /// Every command's help (long and short) reads as text: no rustdoc link markup
    /// (``[`wire::Doorbells`]``) carried over from the doc comments clap reads it from.
    #[test]
    fn no_help_shows_rustdoc_markup() {
        use clap::CommandFactory;
        fn check(command: &mut clap::Command, path: &str) {
            for help in [command.render_long_help(), command.render_help()] {
                let text = help.to_string();
                for markup in ["[`", "`]", "]("] {
                    assert!(
                        !text.contains(markup),
                        "`{path} --help` shows {markup}:\n{text}"
                    );
                }
            }
            for sub in command.get_subcommands_mut() {
                let name = format!("{path} {}", sub.get_name());
                check(sub, &name);
            }
        }
        let mut command = Cli::command();
        command.build();
        check(&mut command, "coordinator");
    }
}
