//! `coordinator simulate [SCENARIO] [--controller P] [--repeat N]`: the reference simulation
//! (`shared::run::simulate`, every agent in this process, no IPC) timed, the yardstick a
//! multi-process run's step loop (`steps_per_s` in its `summary.json`) is measured
//! against. One JSON object on stdout, one line on stderr.

use std::io::Write as _;
use std::time::Instant;

use anyhow::Context;
use serde::Serialize;
use shared::run::simulate::simulate_along;

use crate::cli::SimulateArgs;
use runner::CliError;
use runner::loaded::load_and_plan;

/// What `simulate` prints.
#[derive(Serialize)]
struct SimulateReport {
    scenario: String,
    agents: usize,
    steps: usize,
    turns: String,
    controller: &'static str,
    collisions: usize,
    mean_deviation_m: f64,
    max_deviation_m: f64,
    max_move_m: f64,
    /// Wall time of each run of the step loop (the centre path planned once, before).
    run_s: Vec<f64>,
    /// The fastest run.
    best_s: f64,
    /// Steps per second of the fastest run.
    steps_per_s: f64,
}

/// Carry out `simulate`.
pub fn execute(args: &SimulateArgs) -> Result<(), CliError> {
    let loaded = load_and_plan(args.scenario.as_deref())?;
    let scenario = match args.controller {
        Some(kind) => {
            if let Some(why) = loaded.scenario.refuses_controller(kind) {
                return Err(CliError::Usage(why));
            }
            loaded.scenario.with_controller(kind)
        }
        None => loaded.scenario.clone(),
    };
    let mut run_s = Vec::new();
    let mut last = None;
    for _ in 0..args.repeat {
        let started = Instant::now();
        let run =
            simulate_along(&scenario, &loaded.centre_path).context("the reference simulation")?;
        run_s.push(started.elapsed().as_secs_f64());
        last = Some(run);
    }
    let run = last.context("no run")?;
    let summary = run.summary();
    let best_s = run_s.iter().copied().fold(f64::INFINITY, f64::min);
    let report = SimulateReport {
        scenario: summary.scenario.clone(),
        agents: summary.agents,
        steps: summary.steps,
        turns: scenario.turns.name().to_string(),
        controller: scenario.controller.kind.name(),
        collisions: summary.collisions,
        mean_deviation_m: summary.mean_deviation_m,
        max_deviation_m: summary.max_deviation_m,
        max_move_m: summary.max_move_m,
        best_s,
        steps_per_s: if best_s > 0.0 {
            summary.steps as f64 / best_s
        } else {
            0.0
        },
        run_s,
    };
    eprintln!(
        "{}: {} agents, {} steps, {} collisions, simulate() best of {} runs {:.3} s ({:.1} steps/s)",
        report.scenario,
        report.agents,
        report.steps,
        report.collisions,
        args.repeat,
        report.best_s,
        report.steps_per_s
    );
    let mut json = serde_json::to_vec_pretty(&report).context("formatting the report")?;
    json.push(b'\n');
    std::io::stdout()
        .write_all(&json)
        .context("writing the report")?;
    Ok(())
}
