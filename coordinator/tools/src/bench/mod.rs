//! `coordinator bench`: the end-to-end latency of a turn over real agent processes,
//! against the floor of iceoryx2's events and against a Unix socket, in one run.
//!
//! For every formation size N:
//! 1. a generated scenario ([`scenario`]) runs through the real [`run_scenario`](runner::turns::run_scenario); every
//!    answered turn gives its latency and the agent's compute time, hence the IPC
//!    overhead `latency - compute` per turn. Before the first turn the agents are held
//!    idle and their CPU time is measured ([`IdleCpu`](runner::procfs::IdleCpu)).
//! 2. between steps, every agent of that run answers empty turns in turn order (the
//!    echo, [`wire::EVENT_ECHO`]): the round trip of waking a process that last
//!    ran N turns ago, with no world, planning or move. The two-process floor below
//!    wakes the same warm process every time; the echo shows what waking N processes in
//!    turn costs by itself, so the turn's overhead can be read against both.
//! 3. one process of the bench's own ping-pong program ([`floor::PEER_BIN`], beside the
//!    coordinator) answers an iceoryx2 publish-subscribe ping-pong rung each way as the
//!    run's turns are (`--wake`: by the doorbells, by default, or by iceoryx2 events; the
//!    floor of a turn's wake-up) and a Unix socket ping-pong with
//!    turn-sized payloads ([`floor`]), in short alternating blocks spread between the
//!    steps of that same run, so the floor sees the same (shared, noisy) machine as the
//!    turns.
//!
//! With `--turns-scenario FILE`, the same bench also runs that scenario with sequential
//! and with parallel turns, alternating ([`turns`]), and reports both modes' steps per
//! second, turn groups per step and turn latency side by side. With `--log-scenario
//! FILE`, the step loop with the run log and without ([`log_cost`]).
//!
//! The compute side alone is measured by the Criterion benchmarks in `shared/core/benches`.
//! JSON goes to stdout (and `--out`), the table to stderr, the histogram to an SVG file.
//! Speed is reported, never asserted.

mod args;
pub mod floor;
pub mod futex_floor;
pub mod log_cost;
pub mod loops;
pub mod plot;
pub mod report;
pub mod run_options;
pub mod scale;
pub mod scenario;
pub mod split;
pub mod turns;
pub use args::BenchArgs;

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use shared::control::vocabulary::MAX_AGENTS;

use crate::bench::run_options::{ECHO_DEADLINE, MAX_BENCH_STEPS, bench_run_options};
use runner::CliError;
use runner::agents::locate_agent_binary;
use runner::ipc::TurnSplit;
use runner::output::write_atomically;
use runner::procfs;
use runner::stats::{Distribution, ratio};
use runner::turns::{BetweenSteps, RunOptions, WakeMode, run_scenario_with};

pub use report::{Report, RunReport, Targets};
pub use split::{EchoSplit, OverheadSplit};

/// Fixed part of a serialized world (seq, step, token, turn agent, centre pose), bytes:
/// the wire header, so the socket carries what a turn carries.
const WORLD_HEADER_BYTES: usize = std::mem::offset_of!(wire::World, bodies);
/// A serialized agent position, bytes.
const BYTES_PER_AGENT: usize = 16;
/// Fixed part of a serialized move (seq, step, token, times, ids, status, slot, best):
/// the wire header.
const MOVE_HEADER_BYTES: usize = std::mem::offset_of!(wire::AgentState, waypoints);
/// A serialized waypoint, bytes.
const BYTES_PER_WAYPOINT: usize = 16;
/// Waypoints in the socket reply ("a few": a move on the straight path has two).
const REPLY_WAYPOINTS: usize = 4;
/// Most blocks of each ping-pong, spread evenly between the steps.
const BLOCKS: usize = 40;
/// Round trips dropped at the start of every block (the switch between mechanisms).
const BLOCK_WARMUP: usize = 10;

/// Formation sizes measured when `--agents` is not given (none with `--turns-scenario`).
pub const DEFAULT_AGENTS: [usize; 2] = [6, 200];

/// Carry out `bench`.
pub fn execute(args: &BenchArgs) -> Result<(), CliError> {
    let scenario_only = args.turns_scenario.is_some()
        || args.loop_scenario.is_some()
        || args.log_scenario.is_some()
        || !args.scale.is_empty();
    let scale_steps = args.scale_steps.unwrap_or(scale::DEFAULT_SCALE_STEPS);
    scale::check_sizes(&args.scale, scale_steps)?;
    let agents: Vec<usize> = match (scenario_only, args.agents.is_empty()) {
        (true, true) => Vec::new(),
        (false, true) => DEFAULT_AGENTS.to_vec(),
        (_, false) => args.agents.clone(),
    };
    if let Some(&n) = agents.iter().find(|&&n| n == 0 || n > MAX_AGENTS) {
        return Err(CliError::Usage(format!(
            "--agents {n}: a formation has 1 to {MAX_AGENTS} agents"
        )));
    }
    if args
        .steps
        .is_some_and(|k| !(2..=MAX_BENCH_STEPS).contains(&k))
    {
        return Err(CliError::Usage(format!(
            "--steps: 2 to {MAX_BENCH_STEPS} (the first step is a warm-up)"
        )));
    }
    if args.round_trips == 0 {
        return Err(CliError::Usage("--round-trips: at least 1".into()));
    }
    // The turns scenario is checked before anything runs (a bad one: exit code 2).
    let zenoh = args.transport == runner::network::TransportKind::Zenoh;
    #[cfg(not(feature = "zenoh"))]
    if zenoh {
        return Err(CliError::Usage(runner::network::NO_ZENOH.into()));
    }
    if zenoh && args.turns_scenario.is_none() {
        return Err(CliError::Usage(
            "--transport zenoh: measured on a --turns-scenario FILE (beside iceoryx2)".into(),
        ));
    }
    if args.zenoh_netns && !zenoh {
        return Err(CliError::Usage(
            "--zenoh-netns needs --transport zenoh".into(),
        ));
    }
    if args.sandboxed && args.turns_scenario.is_none() {
        return Err(CliError::Usage(
            "--sandboxed: measured on a --turns-scenario FILE (beside trusted agents)".into(),
        ));
    }
    if args.sandboxed && !runner::turns::running_as_root() {
        return Err(CliError::Usage(
            "--sandboxed needs root (each agent runs as a user of its own)".into(),
        ));
    }
    let mut links = vec![turns::Link::Iceoryx2];
    if zenoh {
        links.push(turns::Link::ZenohLoopback);
    }
    if args.zenoh_netns {
        links.push(turns::Link::ZenohVeth);
    }
    if args.sandboxed {
        links.push(turns::Link::Sandboxed);
    }
    let turns_bench = args
        .turns_scenario
        .as_deref()
        .map(|file| turns::TurnsBench {
            file,
            rounds: args.turns_rounds,
            steps: args.turns_steps,
            verbose: !args.json,
            links: links.clone(),
        });
    let turns_prepared = turns_bench.as_ref().map(turns::prepare).transpose()?;
    let loop_prepared = args
        .loop_scenario
        .as_deref()
        .map(|file| loops::prepare(file, args.loop_rounds))
        .transpose()?;
    let log_prepared = args
        .log_scenario
        .as_deref()
        .map(|file| log_cost::prepare(file, args.log_rounds))
        .transpose()?;
    let bin = locate_agent_binary(args.agent_bin.as_deref())?;
    let out = args.out.clone().unwrap_or_else(default_out);
    // The folder first: the log-cost runs write their log beside the report.
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let svg_path = out.with_extension("svg");
    let mut report = Report {
        runs: Vec::new(),
        build: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        },
        cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
        load_average_1m: procfs::load_average(),
        round_trips: args.round_trips,
        warmup_round_trips: 0,
        histogram_svg: None,
        turns: None,
        loops: None,
        log_cost: None,
        scale: None,
    };
    let mut samples = Vec::new();
    for &n in &agents {
        let steps = args.steps.unwrap_or_else(|| scenario::default_steps(n));
        if !args.json {
            eprintln!("bench: {n} agents, {steps} steps ...");
        }
        let (run, s) = bench_one(&bin, n, steps, args)?;
        report.warmup_round_trips = report
            .warmup_round_trips
            .max(run.floor_blocks * BLOCK_WARMUP);
        samples.push(s);
        report.runs.push(run);
    }

    if let (Some(b), Some(prepared)) = (&turns_bench, turns_prepared) {
        if !args.json {
            eprintln!(
                "bench: {} in sequential and parallel turns, {} run(s) each ...",
                b.file.display(),
                b.rounds
            );
        }
        report.turns = Some(turns::measure(b, prepared, &bin, args.wake)?);
    }
    if let (Some(file), Some(loaded)) = (&args.loop_scenario, loop_prepared) {
        if !args.json {
            eprintln!(
                "bench: {}: simulate() against the step loop, blocking and spinning, {} round(s) ...",
                file.display(),
                args.loop_rounds
            );
        }
        report.loops = Some(loops::measure(
            loaded,
            args.loop_rounds,
            &bin,
            args.wake,
            !args.json,
        )?);
    }
    if let Some(loaded) = &log_prepared {
        if !args.json {
            eprintln!(
                "bench: {}: the step loop with the run log and without, {} round(s) ...",
                loaded.source, args.log_rounds
            );
        }
        report.log_cost = Some(log_cost::measure(
            loaded,
            args.log_rounds,
            &bin,
            args.wake,
            &out.with_extension("mcap"),
            !args.json,
        )?);
    }

    if !args.scale.is_empty() {
        let mut r = scale::measure(&args.scale, scale_steps, &bin, !args.json)?;
        let scale_svg = out.with_extension("scale.svg");
        let svg = plot::scale_svg(&scale::charts(&r)).context("drawing the scale plot")?;
        write_atomically(&scale_svg, svg.as_bytes())?;
        r.plot_svg = Some(scale_svg.display().to_string());
        report.scale = Some(r);
    }

    // The latency histogram, when latency was measured.
    if !report.runs.is_empty() {
        let panels: Vec<plot::Panel<'_>> = report
            .runs
            .iter()
            .zip(&samples)
            .map(|(r, s)| s.panel(r))
            .collect();
        let svg = plot::histogram_svg(&panels).context("drawing the histogram")?;
        write_atomically(&svg_path, svg.as_bytes())?;
        report.histogram_svg = Some(svg_path.display().to_string());
    }
    let mut json = serde_json::to_string_pretty(&report).context("formatting the report")?;
    json.push('\n');
    write_atomically(&out, json.as_bytes())?;
    if !args.json {
        eprint!("{}", report::table(&report));
        eprintln!("report: {}", out.display());
    }
    print!("{json}");
    Ok(())
}

/// The samples behind one run's report (for the histogram).
struct Samples {
    turn_us: Vec<f64>,
    overhead_us: Vec<f64>,
    echo_us: Vec<f64>,
    floor_us: Vec<f64>,
    uds_us: Vec<f64>,
}

impl Samples {
    fn panel(&self, r: &RunReport) -> plot::Panel<'_> {
        plot::Panel {
            title: format!(
                "{} agents: turn latency vs. IPC overhead vs. iceoryx2 floor vs. Unix socket",
                r.agents
            ),
            series: [
                ("turn latency", r.turn_us.p50, &self.turn_us, plot::GREY),
                (
                    "turn IPC overhead",
                    r.ipc_overhead_us.p50,
                    &self.overhead_us,
                    plot::BLUE,
                ),
                (
                    "echo, same agents in turn",
                    r.echo_us.p50,
                    &self.echo_us,
                    plot::ORANGE,
                ),
                (
                    "iceoryx2 floor",
                    r.floor_us.p50,
                    &self.floor_us,
                    plot::GREEN,
                ),
                ("Unix socket", r.uds_us.p50, &self.uds_us, plot::VERMILLION),
            ]
            .into_iter()
            .map(|(what, p50_us, values_us, color)| plot::Series {
                label: format!("{what} (p50 {p50_us:.1} us)"),
                values_us,
                color,
            })
            .collect(),
        }
    }
}

/// The floor, socket and echo samples, gathered in blocks between the steps of a run.
struct Floors {
    /// How the floor's round trips are rung: as the run's turns are.
    wake: WakeMode,
    iceoryx2_us: Vec<f64>,
    uds_us: Vec<f64>,
    echoes: Vec<TurnSplit>,
    blocks: usize,
}

impl Floors {
    /// Block `k` of `blocks`: an equal share of `round_trips` of either mechanism.
    fn block(
        &mut self,
        session: &mut floor::PingPongSession,
        k: usize,
        blocks: usize,
        round_trips: usize,
        (request_bytes, reply_bytes): (usize, usize),
    ) -> anyhow::Result<()> {
        let count = round_trips * (k + 1) / blocks - round_trips * k / blocks;
        self.iceoryx2_us
            .extend(session.rung(self.wake, BLOCK_WARMUP, count)?);
        self.uds_us
            .extend(session.socket(BLOCK_WARMUP, count, request_bytes, reply_bytes)?);
        self.blocks += 1;
        Ok(())
    }

    /// `rounds` echo rounds: every live agent in agent order, one empty turn each.
    fn echo_rounds(&mut self, ctx: &BetweenSteps<'_>, rounds: usize) -> anyhow::Result<()> {
        for _ in 0..rounds {
            for agent in (0..ctx.alive.len()).filter(|&a| ctx.alive[a]) {
                let Some(pid) = ctx.pids.get(agent).copied().flatten() else {
                    continue;
                };
                let deadline = std::time::Instant::now() + ECHO_DEADLINE;
                if let Some(split) = ctx.ipc.echo(agent, pid, deadline)? {
                    self.echoes.push(split);
                }
            }
        }
        Ok(())
    }
}

/// Measure one formation size.
fn bench_one(
    bin: &std::path::Path,
    agents: usize,
    steps: usize,
    args: &BenchArgs,
) -> anyhow::Result<(RunReport, Samples)> {
    let (_, scenario, path) = scenario::generate(agents, steps)?;
    // Socket payloads the size a serialized turn would have.
    let request_bytes = WORLD_HEADER_BYTES + BYTES_PER_AGENT * agents;
    let reply_bytes = MOVE_HEADER_BYTES + BYTES_PER_WAYPOINT * REPLY_WAYPOINTS;
    let options = RunOptions {
        idle_probe: Some(Duration::from_millis(args.idle_ms)),
        ..bench_run_options(bin, args.wake)
    };
    let mut session = floor::PingPongSession::start().context("starting the ping-pong")?;
    let floor_prefix = session.prefix().to_string();
    let blocks = BLOCKS.min(args.round_trips).min(steps).max(1);
    let stride = (steps / blocks).max(1);
    let sizes = (request_bytes, reply_bytes);
    let mut pp = Floors {
        wake: args.wake,
        iceoryx2_us: Vec::with_capacity(args.round_trips),
        uds_us: Vec::with_capacity(args.round_trips),
        echoes: Vec::with_capacity(args.round_trips.max(agents)),
        blocks: 0,
    };
    // Enough echo rounds per block for about `round_trips` echoes in all.
    let echo_rounds = args.round_trips.div_ceil(blocks * agents).max(1);
    let outcome = run_scenario_with(&scenario, &path, &options, &mut |ctx| {
        if ctx.step % stride == 0 && pp.blocks < blocks {
            pp.block(&mut session, pp.blocks, blocks, args.round_trips, sizes)?;
            pp.echo_rounds(&ctx, echo_rounds)?;
        }
        Ok(())
    })?;
    if outcome.interrupted {
        anyhow::bail!("interrupted");
    }
    // A run with fewer steps than planned (it cannot happen, but cheaply covered).
    while pp.blocks < blocks {
        pp.block(&mut session, pp.blocks, blocks, args.round_trips, sizes)?;
    }
    session.finish()?;
    // Every agent's first turn is a warm-up (controller construction, first page touches).
    let measured: Vec<_> = outcome
        .turn_samples
        .iter()
        .filter(|t| t.step > 1)
        .copied()
        .collect();
    let warmup_turns = outcome.turn_samples.len() - measured.len();
    let turn_us: Vec<f64> = measured.iter().map(|t| t.latency_us).collect();
    let compute_us: Vec<f64> = measured.iter().map(|t| t.compute_us).collect();
    let overhead_us: Vec<f64> = measured
        .iter()
        .map(|t| t.latency_us - t.compute_us)
        .collect();

    let overhead_split = OverheadSplit::of(&measured);
    let turn = Distribution::of(&turn_us);
    let overhead = Distribution::of(&overhead_us);
    let floor_d = Distribution::of(&pp.iceoryx2_us);
    let echo_us: Vec<f64> = pp.echoes.iter().map(TurnSplit::total_us).collect();
    let echo = Distribution::of(&echo_us);
    let echo_split = EchoSplit {
        to_agent_us: Distribution::of_iter(pp.echoes.iter().map(|e| e.to_agent_us)),
        to_coordinator_us: Distribution::of_iter(pp.echoes.iter().map(|e| e.to_coordinator_us)),
    };
    let uds = Distribution::of(&pp.uds_us);
    let idle = outcome.idle_cpu.unwrap_or_default();
    let mut r = RunReport {
        agents,
        steps,
        warmup_turns,
        turn_us: turn,
        compute_us: Distribution::of(&compute_us),
        ipc_overhead_us: overhead,
        overhead_split,
        echo_us: echo,
        echo_split,
        floor_us: floor_d,
        floor_rung_by: args.wake.name(),
        uds_us: uds,
        uds_request_bytes: request_bytes,
        uds_reply_bytes: reply_bytes,
        overhead_vs_floor_p50: ratio(overhead.p50, floor_d.p50),
        overhead_vs_floor_p99: ratio(overhead.p99, floor_d.p99),
        overhead_vs_uds_p50: ratio(overhead.p50, uds.p50),
        overhead_vs_echo_p50: ratio(overhead.p50, echo.p50),
        overhead_vs_echo_p99: ratio(overhead.p99, echo.p99),
        agent_idle_cpu_s: idle.cpu_s,
        agent_idle: idle,
        startup_s: outcome.timing.startup_s,
        agent_rss_kib: outcome.timing.agent_rss_kib,
        faults: outcome.run.faults.len(),
        wall_s: outcome.timing.wall_s,
        prefix: outcome.prefix.clone(),
        floor_prefix,
        floor_blocks: pp.blocks,
        targets: Targets {
            overhead_p50_within_1_5x_floor: false,
            overhead_p99_within_3x_floor: false,
            overhead_p50_below_uds_p50: false,
            idle_cpu_zero: false,
        },
    };
    r.targets = Targets::of(&r);
    let samples = Samples {
        turn_us,
        overhead_us,
        echo_us,
        floor_us: pp.iceoryx2_us,
        uds_us: pp.uds_us,
    };
    Ok((r, samples))
}

/// `runs/bench-<UTC timestamp>.json`.
fn default_out() -> PathBuf {
    let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
        .to_string()
        .replace(':', "-");
    PathBuf::from("runs").join(format!("bench-{stamp}.json"))
}
