//! `coordinator compare SCENARIO...`: every planner on every scenario, through the same
//! processes, protocol and safety monitor, tabulated side by side.

use std::path::Path;

use anyhow::Context;
use serde::Serialize;
use shared::run::Run;
use shared::scenario::PlannerKind;

use crate::cli::CompareArgs;
use crate::error::CliError;
use crate::output;
use crate::runner::{RunOptions, run_scenario};
use crate::stats::Distribution;
use crate::validate::load_and_plan;

/// One row of the comparison table.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Scenario name.
    pub scenario: String,
    /// Planner name.
    pub planner: String,
    /// Whether the run went through the whole path.
    pub completed: bool,
    /// Agent records overlapping another body at the end of a step (0 when safe).
    pub collisions: usize,
    /// Moves the safety monitor refused (unsafe moves the planner tried).
    pub unsafe_moves: usize,
    /// Smallest clearance over the run, in metres.
    pub min_clearance_m: f64,
    /// Mean deviation, in metres.
    pub mean_deviation_m: f64,
    /// Largest deviation, in metres.
    pub max_deviation_m: f64,
    /// Mean deviation at the last step, in metres.
    pub final_mean_deviation_m: f64,
    /// Agent-steps in which a live agent off its slot did not move at all.
    pub deadlocked_steps: usize,
    /// Agent compute time per turn, median, in microseconds.
    pub compute_p50_us: f64,
    /// Agent compute time per turn, 99th percentile, in microseconds.
    pub compute_p99_us: f64,
}

/// Agent-steps where a live agent off its slot did not move.
pub fn deadlocked_steps(run: &Run) -> usize {
    run.steps
        .iter()
        .skip(1)
        .flat_map(|s| s.agents.iter())
        .filter(|a| a.alive && a.waypoints.len() == 1 && a.deviation_m > 1e-6)
        .count()
}

fn row(run: &Run, planner: PlannerKind, compute: &Distribution) -> Row {
    let s = run.summary();
    Row {
        scenario: s.scenario.clone(),
        planner: planner.name().to_string(),
        completed: s.completed,
        collisions: s.collisions,
        unsafe_moves: s.faults.iter().filter(|f| f.kind == "rejected").count(),
        min_clearance_m: s.min_clearance_m,
        mean_deviation_m: s.mean_deviation_m,
        max_deviation_m: s.max_deviation_m,
        final_mean_deviation_m: s.final_mean_deviation_m,
        deadlocked_steps: deadlocked_steps(run),
        compute_p50_us: compute.p50,
        compute_p99_us: compute.p99,
    }
}

/// The table as Markdown.
pub fn markdown(rows: &[Row]) -> String {
    let mut md = String::from(
        "| scenario | planner | completed | collisions | unsafe moves refused | min clearance (m) | mean dev. (m) | max dev. (m) | final dev. (m) | deadlocked agent-steps | compute p50 (us) | compute p99 (us) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {} | {:.1} | {:.1} |\n",
            r.scenario,
            r.planner,
            r.completed,
            r.collisions,
            r.unsafe_moves,
            r.min_clearance_m,
            r.mean_deviation_m,
            r.max_deviation_m,
            r.final_mean_deviation_m,
            r.deadlocked_steps,
            r.compute_p50_us,
            r.compute_p99_us
        ));
    }
    md
}

fn csv_bytes(rows: &[Row]) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    Ok(w.into_inner()?)
}

/// Run `compare`.
pub fn run(args: &CompareArgs) -> Result<(), CliError> {
    let planners = if args.planners.is_empty() {
        PlannerKind::ALL.to_vec()
    } else {
        args.planners.clone()
    };
    // Validate every scenario before running anything.
    let loaded = if args.scenarios.is_empty() {
        vec![load_and_plan(None)?]
    } else {
        args.scenarios
            .iter()
            .map(|f| load_and_plan(Some(f)))
            .collect::<Result<Vec<_>, _>>()?
    };
    let options = RunOptions {
        agent_bin: args.agent_bin.clone(),
        progress: false,
        ..RunOptions::default()
    };
    let mut rows = Vec::new();
    for l in &loaded {
        for &planner in &planners {
            let scenario = l.scenario.with_planner(planner);
            eprintln!("{} with {} ...", scenario.name, planner.name());
            let outcome = run_scenario(&scenario, &l.centre_path, &options)
                .map_err(|failure| CliError::Other(failure.error))?;
            if outcome.interrupted {
                return Err(CliError::Other(anyhow::anyhow!("interrupted")));
            }
            rows.push(row(&outcome.run, planner, &outcome.timing.compute_us));
        }
    }
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| output::default_run_dir("compare"));
    write(&dir, &rows)?;
    eprint!("{}", markdown(&rows));
    eprintln!("-> {}", dir.display());
    Ok(())
}

fn write(dir: &Path, rows: &[Row]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    output::write_atomically(&dir.join("compare.csv"), &csv_bytes(rows)?)?;
    output::write_atomically(&dir.join("compare.md"), markdown(rows).as_bytes())?;
    Ok(())
}
