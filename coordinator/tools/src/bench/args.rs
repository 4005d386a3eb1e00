//! The command line of `coordinator bench`.

use std::path::PathBuf;

use clap::Args;
use runner::network::TransportKind;
use runner::turns::WakeMode;

/// Arguments of `bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// How the measured runs' processes wake each other (`--scale` runs both, side by
    /// side): `doorbell` or `event`, as `run --wake`.
    #[arg(long, value_enum, default_value_t = WakeMode::Doorbell)]
    pub wake: WakeMode,
    /// Formation sizes to measure (repeatable or comma-separated; default 6,200, or none
    /// with --turns-scenario or --loop-scenario).
    #[arg(long, value_name = "N", value_delimiter = ',')]
    pub agents: Vec<usize>,
    /// Steps of the straight path (default: about 3000 turns, at least 40 steps).
    #[arg(long, value_name = "K")]
    pub steps: Option<usize>,
    /// Round trips of each ping-pong (floor and socket), after a 10% warm-up.
    #[arg(long, default_value_t = 2000)]
    pub round_trips: usize,
    /// How long the agents are held idle to measure their idle CPU time, ms.
    #[arg(long, default_value_t = 1000)]
    pub idle_ms: u64,
    /// Machine output only: the JSON on stdout, no table on stderr.
    #[arg(long)]
    pub json: bool,
    /// Where to write the JSON report (default `runs/bench-<UTC time>.json`); the
    /// histogram goes beside it, with the extension `.svg`.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Also compare sequential and parallel turns on this scenario (it needs a top
    /// speed): it runs with its `[turns] mode` forced to each, same processes, same top
    /// speed, alternating; steps per second, groups per step and turn latency of both.
    #[arg(long, value_name = "SCENARIO")]
    pub turns_scenario: Option<PathBuf>,
    /// Runs of each turn mode with --turns-scenario, alternating (S P, P S, S P, ...).
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub turns_rounds: usize,
    /// With --turns-scenario: run only the first K steps of its centre path (default:
    /// the whole path).
    #[arg(long, value_name = "K")]
    pub turns_steps: Option<usize>,
    /// Also measure the cost of decentralisation on this scenario: `simulate()` in this
    /// process against the multi-process step loop with `--wait block` and `--wait spin`,
    /// alternating; loop times, their ratio to `simulate()`, turn latency and IPC
    /// overhead of both.
    #[arg(long, value_name = "SCENARIO")]
    pub loop_scenario: Option<PathBuf>,
    /// Rounds with --loop-scenario (each: simulate(), a blocking run, a spinning run).
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub loop_rounds: usize,
    /// Also measure what the run log (`run.mcap`) costs on this scenario: the step loop
    /// with the log and without, alternating; the last log is kept beside the report
    /// (`--out` with the extension `.mcap`).
    #[arg(long, value_name = "SCENARIO")]
    pub log_scenario: Option<PathBuf>,
    /// Runs of each kind with --log-scenario.
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub log_rounds: usize,
    /// With `--turns-scenario`: also run each mode with every agent over Zenoh on the
    /// loopback (`zenoh`), beside iceoryx2 (`ipc`, always).
    #[arg(long, value_enum, default_value_t = TransportKind::Ipc)]
    pub transport: TransportKind,
    /// With `--transport zenoh`: also run each mode with every agent on a second host, a
    /// network namespace joined by a veth pair that the bench makes and removes (needs
    /// root and iproute2).
    #[arg(long)]
    pub zenoh_netns: bool,
    /// Also measure the runtime against the number of agents: for each N given
    /// (comma-separated, e.g. `100,300,1000`), a generated swarm of N agents (a top speed,
    /// a 3 m sensing radius, parallel turns) runs for real beside `simulate()` and the
    /// spawn floor (N `agent --help` processes); start-up and its phases, steps/s, turn
    /// latency, agent CPU and memory (PSS), the ratios, and a plot against N (`--out` with
    /// the extension `.scale.svg`).
    #[arg(long, value_name = "N", value_delimiter = ',')]
    pub scale: Vec<usize>,
    /// With `--scale`: steps of the swarm's straight path (default 48).
    #[arg(long, value_name = "K")]
    pub scale_steps: Option<usize>,
    /// With `--turns-scenario`: also run each mode with every agent sandboxed (its own
    /// user and control group behind a relay; needs root), beside the trusted agents, and
    /// report what the sandbox costs.
    #[arg(long)]
    pub sandboxed: bool,
    /// The agent executable (default: `agent` beside this program).
    #[arg(long)]
    pub agent_bin: Option<PathBuf>,
}
