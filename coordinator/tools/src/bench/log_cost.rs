//! `coordinator bench --log-scenario FILE`: what writing the run log (`run.mcap`) costs
//! the step loop, in one bench run: the same scenario through the real [`run_scenario`]
//! with the log on and with it off, alternating `L N`, `N L`, ... so a machine that gets
//! busier or quieter weighs on both alike; and the log's size per agent and step.

use std::path::Path;

use serde::Serialize;

use crate::bench::run_options::bench_run_options;
use runner::CliError;
use runner::loaded::{Loaded, load_and_plan};
use runner::run_log::{LogOptions, SyncPolicy};
use runner::stats::median;
use runner::turns::{RunOptions, WakeMode, run_scenario};

/// The comparison (`log_cost` in the report).
#[derive(Clone, Debug, Serialize)]
pub struct LogCostReport {
    /// The scenario's `name`.
    pub scenario: String,
    /// The scenario file as given.
    pub file: String,
    /// Agents (one process each).
    pub agents: usize,
    /// Steps of the centre path.
    pub steps: usize,
    /// Runs of each kind.
    pub rounds: usize,
    /// The runs in the order they were made (`log`, `none`, ...).
    pub order: Vec<&'static str>,
    /// Steps per second of the step loop (start-up excluded) of each run with the log.
    pub with_log_steps_per_s: Vec<f64>,
    /// The same without the log.
    pub without_log_steps_per_s: Vec<f64>,
    /// `median(with) / median(without)`: below 1, the log slows the loop down.
    pub with_vs_without_steps_per_s: f64,
    /// Each round's `with / without`, of its two runs made one after the other (so a
    /// machine that gets busier or quieter between rounds weighs on both alike).
    pub round_ratios: Vec<f64>,
    /// The median of `round_ratios`: the figure least moved by a noisy machine.
    pub median_round_ratio: f64,
    /// The log of the last run with it (kept beside the report).
    pub log_file: String,
    /// Its size, bytes.
    pub log_bytes: u64,
    /// `log_bytes` per agent and step recorded (step 0 included).
    pub log_bytes_per_agent_step: f64,
}

/// Check the file and plan its path before anything runs (exit code 2 when bad).
pub fn prepare(file: &Path, rounds: usize) -> Result<Loaded, CliError> {
    if rounds == 0 {
        return Err(CliError::Usage("--log-rounds: at least 1".into()));
    }
    let loaded = load_and_plan(Some(file))?;
    Ok(loaded)
}

/// Run the comparison on `loaded` with the agent executable `bin`, `rounds` runs of each;
/// the runs with the log write it to `log_path` (the last one stays, to look at).
pub fn measure(
    loaded: &Loaded,
    rounds: usize,
    bin: &Path,
    wake: WakeMode,
    log_path: &Path,
    verbose: bool,
) -> Result<LogCostReport, CliError> {
    let base = bench_run_options(bin, wake);
    let logged = RunOptions {
        log: Some(LogOptions {
            path: log_path.to_path_buf(),
            source: loaded.source.clone(),
            sync: SyncPolicy::EverySecond,
        }),
        ..base.clone()
    };
    let scenario = &loaded.scenario;
    let path = &loaded.centre_path;
    let mut order = Vec::with_capacity(2 * rounds);
    let (mut with, mut without) = (Vec::new(), Vec::new());
    let mut recorded_steps = 0;
    let mut round_ratios = Vec::with_capacity(rounds);
    for round in 0..rounds {
        let pair = if round % 2 == 0 {
            [true, false]
        } else {
            [false, true]
        };
        for log in pair {
            let options = if log { &logged } else { &base };
            let outcome = run_scenario(scenario, path, options)
                .map_err(|failure| CliError::Other(failure.error))?;
            if outcome.interrupted {
                return Err(CliError::Other(anyhow::anyhow!("interrupted")));
            }
            let steps_per_s = outcome.timing.steps_per_s;
            if verbose {
                eprintln!(
                    "bench: {} with the log {}, round {} of {rounds}: {steps_per_s:.2} steps/s",
                    scenario.name,
                    if log { "on" } else { "off" },
                    round + 1
                );
            }
            order.push(if log { "log" } else { "none" });
            if log {
                with.push(steps_per_s);
                recorded_steps = outcome.run.steps.len();
            } else {
                without.push(steps_per_s);
            }
        }
        if let (Some(w), Some(n)) = (with.last(), without.last()) {
            round_ratios.push(runner::stats::ratio(*w, *n));
        }
    }
    let log_bytes = std::fs::metadata(log_path).map_or(0, |m| m.len());
    let agent_steps = (scenario.agents.len() * recorded_steps).max(1);
    Ok(LogCostReport {
        scenario: scenario.name.clone(),
        file: loaded.source.clone(),
        agents: scenario.agents.len(),
        steps: path.len().saturating_sub(1),
        rounds,
        order,
        with_vs_without_steps_per_s: runner::stats::ratio(median(&with), median(&without)),
        median_round_ratio: median(&round_ratios),
        round_ratios,
        with_log_steps_per_s: with,
        without_log_steps_per_s: without,
        log_file: log_path.display().to_string(),
        log_bytes,
        log_bytes_per_agent_step: log_bytes as f64 / agent_steps as f64,
    })
}

/// The comparison as lines for people.
pub fn table(r: &LogCostReport) -> String {
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "\nlog cost: {} ({}), {} agents, {} steps, {} run(s) of each\n  steps/s with the log: {}\n  steps/s without it: {}\n  with / without, each round: {}\n  with / without: {:.3}x steps/s (medians), {:.3}x (median of the rounds); run.mcap {} bytes, {:.0} bytes per agent and step\n",
        r.scenario,
        r.file,
        r.agents,
        r.steps,
        r.rounds,
        list(&r.with_log_steps_per_s),
        list(&r.without_log_steps_per_s),
        r.round_ratios
            .iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>()
            .join(", "),
        r.with_vs_without_steps_per_s,
        r.median_round_ratio,
        r.log_bytes,
        r.log_bytes_per_agent_step
    )
}
