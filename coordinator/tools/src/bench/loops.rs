//! `coordinator bench --loop-scenario FILE`: the cost of decentralisation on one
//! scenario, in one bench run: the in-process reference (`simulate()`, every agent in the
//! coordinator's process) against the multi-process step loop with turns handed over by
//! sleeping (`--wait block`) and by spinning (`--wait spin`), alternating `simulate B S`,
//! `simulate S B`, ... so a machine that gets busier or quieter weighs on all alike.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use shared::run::simulate::simulate_along;

use crate::bench::run_options::bench_run_options;
use runner::CliError;
use runner::loaded::{Loaded, load_and_plan};
use runner::stats::{Distribution, median};
use runner::turns::{RunOptions, RunOutcome, TurnSample, WaitMode, WakeMode, run_scenario};

/// Round trips of each floor per round, after [`FLOOR_WARMUP`] unrecorded ones.
const FLOOR_ROUND_TRIPS: usize = 2000;
/// Round trips made and dropped before each floor's recorded ones.
const FLOOR_WARMUP: usize = 200;

/// The comparison (`loops` in the report).
#[derive(Clone, Debug, Serialize)]
pub struct LoopsReport {
    /// The scenario's `name`.
    pub scenario: String,
    /// The scenario file as given.
    pub file: String,
    /// Agents (one process each in the multi-process runs).
    pub agents: usize,
    /// Steps of the centre path.
    pub steps: usize,
    /// Rounds (each: one `simulate()`, one blocking run, one spinning run).
    pub rounds: usize,
    /// `simulate()`'s wall time, each round, seconds.
    pub simulate_s: Vec<f64>,
    /// Their median.
    pub simulate_median_s: f64,
    /// Round trips between two processes over iceoryx2 publish-subscribe, both sides
    /// busy-polling (no event): the floor a spinning hand-over can reach, microseconds.
    pub floor_spin_us: Distribution,
    /// The same round trips rung each way as the runs' turns are (both sides sleep):
    /// the floor of the blocking hand-over, microseconds.
    pub floor_block_us: Distribution,
    /// How those were rung: `doorbell` or `event` (`--wake`).
    pub floor_rung_by: &'static str,
    /// The multi-process runs, turns handed over by sleeping.
    pub block: WaitReport,
    /// The multi-process runs, turns handed over by spinning.
    pub spin: WaitReport,
}

/// The figures of one wait mode over its runs.
#[derive(Clone, Debug, Serialize)]
pub struct WaitReport {
    /// `block` or `spin`.
    pub wait: &'static str,
    /// Step-loop wall time of each run (start-up excluded), seconds.
    pub loop_s: Vec<f64>,
    /// Their median.
    pub loop_median_s: f64,
    /// `loop_median_s / simulate_median_s`: what the processes and the IPC cost.
    pub vs_simulate: f64,
    /// Turn latency (world published to move held), every run pooled, step 1 (warm-up)
    /// left out, microseconds.
    pub turn_us: Distribution,
    /// The agents' own compute time per turn, pooled the same way, microseconds.
    pub compute_us: Distribution,
    /// Turn latency minus compute, per turn: the IPC overhead, microseconds.
    pub ipc_overhead_us: Distribution,
    /// Where the IPC overhead goes: waking (or reaching) the agent, its reading and
    /// writing, reaching the coordinator.
    pub overhead_split: super::split::OverheadSplit,
    /// The coordinator's own time per turn outside the turns (judging and recording the
    /// moves, the monitor, building the next world): the step loop's time minus every
    /// turn's latency, over the turns, microseconds (mean over every run). Sequential
    /// turns only (`None` with parallel turns, whose latencies overlap).
    pub between_turns_us: Option<f64>,
    /// The share of the turns granted without a ring, to an agent told it came next
    /// (0 when sleeping).
    pub polled_share: f64,
    /// Reaching the agent in those turns (the world published to the agent holding it),
    /// microseconds: near the busy-polled floor when the agent was already polling,
    /// longer when it woke only after its world came.
    pub polled_to_agent_us: Distribution,
    /// Collisions over every run (0 when safe).
    pub collisions: usize,
    /// Faults over every run (0 for clean runs).
    pub faults: usize,
}

/// The scenario of `--loop-scenario FILE`, checked (with the rounds) before anything
/// runs: a bad file or `--loop-rounds 0` is refused with exit code 2.
pub fn prepare(file: &Path, rounds: usize) -> Result<Loaded, CliError> {
    if rounds == 0 {
        return Err(CliError::Usage("--loop-rounds: at least 1".into()));
    }
    let loaded = load_and_plan(Some(file))?;
    Ok(loaded)
}

/// Run the comparison on `loaded` ([`prepare`]), `rounds` rounds, with the agent
/// executable `bin`, rung as `wake` has it.
pub fn measure(
    loaded: Loaded,
    rounds: usize,
    bin: &Path,
    wake: WakeMode,
    verbose: bool,
) -> Result<LoopsReport, CliError> {
    let Loaded {
        scenario,
        centre_path,
        source,
        ..
    } = loaded;
    let options = |wait| RunOptions {
        wait,
        ..bench_run_options(bin, wake)
    };
    let mut simulate_s = Vec::with_capacity(rounds);
    let (mut block, mut spin) = (Vec::new(), Vec::new());
    let mut session = super::floor::PingPongSession::start().map_err(CliError::Other)?;
    let (mut floor_spin, mut floor_block) = (Vec::new(), Vec::new());
    for round in 0..rounds {
        floor_spin.extend(
            session
                .iceoryx2_spin(FLOOR_WARMUP, FLOOR_ROUND_TRIPS)
                .map_err(CliError::Other)?,
        );
        floor_block.extend(
            session
                .rung(wake, FLOOR_WARMUP, FLOOR_ROUND_TRIPS)
                .map_err(CliError::Other)?,
        );
        let started = Instant::now();
        simulate_along(&scenario, &centre_path)
            .map_err(|e| CliError::Other(anyhow::anyhow!("the reference simulation: {e}")))?;
        simulate_s.push(started.elapsed().as_secs_f64());
        let pair = if round % 2 == 0 {
            [WaitMode::Block, WaitMode::Spin]
        } else {
            [WaitMode::Spin, WaitMode::Block]
        };
        for wait in pair {
            let outcome = run_scenario(&scenario, &centre_path, &options(wait))
                .map_err(|failure| CliError::Other(failure.error))?;
            if outcome.interrupted {
                return Err(CliError::Other(anyhow::anyhow!("interrupted")));
            }
            if verbose {
                eprintln!(
                    "bench: {:?} wait, round {} of {rounds}: step loop {:.3} s (simulate() {:.3} s), turn p50 {:.1} us",
                    wait,
                    round + 1,
                    loop_s(&outcome),
                    simulate_s[round],
                    outcome.timing.turn_latency_us.p50
                );
            }
            if wait == WaitMode::Spin {
                spin.push(outcome);
            } else {
                block.push(outcome);
            }
        }
    }
    session.finish().map_err(CliError::Other)?;
    let simulate_median_s = median(&simulate_s);
    let sequential = scenario.turns == shared::control::vocabulary::TurnMode::Sequential;
    Ok(LoopsReport {
        floor_spin_us: Distribution::of(&floor_spin),
        floor_block_us: Distribution::of(&floor_block),
        floor_rung_by: wake.name(),
        scenario: scenario.name.clone(),
        file: source,
        agents: scenario.agents.len(),
        steps: centre_path.len().saturating_sub(1),
        rounds,
        block: wait_report("block", &block, simulate_median_s, sequential),
        spin: wait_report("spin", &spin, simulate_median_s, sequential),
        simulate_s,
        simulate_median_s,
    })
}

/// The step loop's wall time of a run, seconds.
fn loop_s(o: &RunOutcome) -> f64 {
    let steps = o.run.steps.len().saturating_sub(1) as f64;
    if o.timing.steps_per_s > 0.0 {
        steps / o.timing.steps_per_s
    } else {
        0.0
    }
}

fn wait_report(
    wait: &'static str,
    runs: &[RunOutcome],
    simulate_s: f64,
    sequential: bool,
) -> WaitReport {
    let loops: Vec<f64> = runs.iter().map(loop_s).collect();
    let measured: Vec<TurnSample> = runs
        .iter()
        .flat_map(|o| o.turn_samples.iter().filter(|t| t.step > 1))
        .copied()
        .collect();
    let turns: usize = runs.iter().map(|o| o.turn_samples.len()).sum();
    let in_turns_us: f64 = runs
        .iter()
        .flat_map(|o| o.turn_samples.iter().map(|t| t.latency_us))
        .sum();
    let loops_us: f64 = loops.iter().sum::<f64>() * 1e6;
    let (mut turn, mut compute, mut overhead) = (Vec::new(), Vec::new(), Vec::new());
    for t in &measured {
        turn.push(t.latency_us);
        compute.push(t.compute_us);
        overhead.push(t.latency_us - t.compute_us);
    }
    let loop_median_s = median(&loops);
    WaitReport {
        wait,
        loop_s: loops,
        loop_median_s,
        vs_simulate: runner::stats::ratio(loop_median_s, simulate_s),
        turn_us: Distribution::of(&turn),
        compute_us: Distribution::of(&compute),
        ipc_overhead_us: Distribution::of(&overhead),
        overhead_split: super::split::OverheadSplit::of(&measured),
        polled_share: if measured.is_empty() {
            0.0
        } else {
            measured.iter().filter(|t| t.polled).count() as f64 / measured.len() as f64
        },
        polled_to_agent_us: Distribution::of_iter(
            measured
                .iter()
                .filter(|t| t.polled)
                .filter_map(|t| t.split.map(|s| s.to_agent_us)),
        ),
        between_turns_us: (sequential && turns > 0)
            .then(|| (loops_us - in_turns_us).max(0.0) / turns as f64),
        collisions: runs.iter().map(|o| o.run.summary().collisions).sum(),
        faults: runs.iter().map(|o| o.run.faults.len()).sum(),
    }
}

/// The comparison as a table for people.
pub fn table(l: &LoopsReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nloop: {} ({}), {} agents, {} steps, {} round(s); simulate() median {:.3} s",
        l.scenario, l.file, l.agents, l.steps, l.rounds, l.simulate_median_s
    );
    let _ = writeln!(
        s,
        "  floor between two processes: busy-polled publish-subscribe p50 {:.2} us p99 {:.2} us; rung each way ({}) p50 {:.1} us p99 {:.1} us",
        l.floor_spin_us.p50,
        l.floor_spin_us.p99,
        l.floor_rung_by,
        l.floor_block_us.p50,
        l.floor_block_us.p99
    );
    let _ = writeln!(
        s,
        "  {:<8}{:>12}{:>14}{:>14}{:>14}{:>16}{:>16}{:>8}{:>12}",
        "wait",
        "loop s",
        "vs simulate",
        "turn p50 us",
        "turn p99 us",
        "ipc p50 us",
        "ipc p99 us",
        "faults",
        "collisions"
    );
    for w in [&l.block, &l.spin] {
        let _ = writeln!(
            s,
            "  {:<8}{:>12.3}{:>13.2}x{:>14.1}{:>14.1}{:>16.1}{:>16.1}{:>8}{:>12}",
            w.wait,
            w.loop_median_s,
            w.vs_simulate,
            w.turn_us.p50,
            w.turn_us.p99,
            w.ipc_overhead_us.p50,
            w.ipc_overhead_us.p99,
            w.faults,
            w.collisions
        );
    }
    let _ = writeln!(
        s,
        "  where a turn's time goes, p50 us: {:<8}{:>14}{:>14}{:>16}{:>16}",
        "wait", "reach agent", "agent I/O", "reach coord.", "between turns"
    );
    for w in [&l.block, &l.spin] {
        let split = &w.overhead_split;
        let _ = writeln!(
            s,
            "  {:<33}{:<8}{:>14.1}{:>14.1}{:>16.1}{:>16}",
            "",
            w.wait,
            split.to_agent_us.p50,
            split.agent_io_us.p50,
            split.to_coordinator_us.p50,
            w.between_turns_us
                .map_or("-".to_string(), |us| format!("{us:.1}"))
        );
    }
    let _ = writeln!(
        s,
        "  (between turns: the coordinator's own work per turn, the loop's time minus the turns', a mean; sequential turns only)"
    );
    let w = &l.spin;
    let _ = writeln!(
        s,
        "  spin: {:.0} % of the turns granted without a ring (the agent told it came next); reaching it then p50 {:.1} us, p90 {:.1} us (busy-polled floor one way: about half the round trip above)",
        100.0 * w.polled_share,
        w.polled_to_agent_us.p50,
        w.polled_to_agent_us.p90
    );
    s
}
