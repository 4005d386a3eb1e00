//! `coordinator compare SCENARIO...`: every planner on every scenario, through the same
//! processes, protocol and safety monitor, tabulated side by side; each run's own files in
//! a folder of their own.

use std::path::Path;

use anyhow::Context;
use serde::Serialize;
use shared::record::Run;
use shared::vocabulary::PlannerKind;

use crate::cli::CompareArgs;
use crate::error::CliError;
use crate::output;
use crate::stats::Distribution;
use crate::turns::{RunOptions, run_scenario};
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

/// The folder name of one run of the comparison: `<scenario>-<planner>`, made of
/// letters, digits, `-` and `_` only, with `-2`, `-3`, ... when two scenarios share a
/// name.
fn run_folder_name(scenario: &str, planner: PlannerKind, taken: &mut Vec<String>) -> String {
    let clean = output::file_name_part(scenario);
    let base = format!("{clean}-{}", planner.name());
    let name = (1..)
        .map(|k| {
            if k == 1 {
                base.clone()
            } else {
                format!("{base}-{k}")
            }
        })
        .find(|n| !taken.contains(n))
        .unwrap_or(base);
    taken.push(name.clone());
    name
}

/// Carry out `compare`: every scenario is validated and the output folder checked before any
/// agent starts. One line per run on stderr, then the table; each run's files (its
/// `summary.json` with the refused moves in `faults`, its resolved `scenario.toml`, ...)
/// go to a folder of their own inside the output folder.
pub fn execute(args: &CompareArgs) -> Result<(), CliError> {
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
    let out = output::OutDir::check(
        args.out
            .clone()
            .unwrap_or_else(|| output::default_run_dir("compare")),
        args.force,
    )?;
    let options = RunOptions {
        agent_bin: args.agent_bin.clone(),
        progress: false,
        ..RunOptions::default()
    };
    // Dropped on an error or an interruption: nothing half-written is left.
    let staging = out.begin()?;
    let mut rows = Vec::new();
    let mut taken = Vec::new();
    for l in &loaded {
        for &planner in &planners {
            let scenario = l.scenario.with_planner(planner);
            let folder = run_folder_name(&scenario.name, planner, &mut taken);
            let outcome = run_scenario(&scenario, &l.centre_path, &options)
                .map_err(|failure| CliError::Other(failure.error))?;
            if outcome.interrupted {
                return Err(CliError::Other(anyhow::anyhow!(
                    "interrupted during {} with {}: nothing written",
                    scenario.name,
                    planner.name()
                )));
            }
            output::write_run(
                &staging.path().join(&folder),
                &scenario,
                &l.source,
                &outcome.run,
                &outcome.timing,
            )?;
            let r = row(&outcome.run, planner, &outcome.timing.compute_us);
            // One line per run, when it is done.
            eprintln!(
                "{} with {}: {}, {} collisions, {} unsafe moves refused, {} faults -> {folder}/",
                scenario.name,
                planner.name(),
                if r.completed {
                    "completed"
                } else {
                    "not completed"
                },
                r.collisions,
                r.unsafe_moves,
                outcome.run.faults.len()
            );
            rows.push(r);
        }
    }
    write(staging.path(), &rows)?;
    let dir = staging.commit()?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_folders_are_plain_names_and_never_shared() {
        let mut taken = Vec::new();
        let a = run_folder_name("paper example/1", PlannerKind::Cbf, &mut taken);
        let b = run_folder_name("paper example/1", PlannerKind::Cbf, &mut taken);
        let c = run_folder_name("paper example/1", PlannerKind::BestPoint, &mut taken);
        assert_eq!(a, "paper_example_1-cbf");
        assert_eq!(b, "paper_example_1-cbf-2");
        assert_eq!(c, "paper_example_1-best-point");
    }
}
