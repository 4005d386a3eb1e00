//! Output files (`docs/outputs.md`): `summary.json`, `trajectory.csv`, `moves.csv`,
//! `path.csv` (the path followed), `plans.csv` (the first plan and every replan taken) and
//! `obstacles.csv` (the moving obstacles at every step, the unknown ones and when they
//! became known).
//! Every file is written whole or not at all (a temporary file, then a rename), and an
//! output folder too ([`OutDir`]: a temporary sibling folder, then a rename).
//!
//! One concept per file:
//! - `rows`: one serde struct per CSV file's row, written here and read by
//!   `coordinator render` (the `tools` crate);
//! - `csv_format`: the number format of the CSV files' cells, and a file's bytes;
//! - `tables`: the CSV files made from a run;
//! - `summary`: `summary.json`, as written and as read back;
//! - `out_dir`: the output folder, checked, staged and put in place.

use std::path::{Path, PathBuf};

use anyhow::Context;

use crate::stats::Distribution;
use shared::geometry::Pose;
use shared::run::record::Run;
use shared::world::scenario::Scenario;

mod csv_format;
mod out_dir;
pub mod rows;
mod summary;
mod tables;

pub use out_dir::{OutDir, Staging};
pub use summary::{FaultRecord, GroupTiming, StartupPhases, SummaryFile, SummaryRead, Timing};
pub use tables::{moves_csv, obstacles_csv, path_csv, plans_csv, trajectory_csv};

/// The folder inside a run directory that receives the plots (`coordinator render`
/// writes them).
pub const PLOTS_DIR: &str = "plots";

/// Write `bytes` to `path` atomically: a temporary file beside it, created new, then a
/// rename; never through a symbolic link ([`shared::output_file::write_replacing`]).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    shared::output_file::write_replacing(path, bytes)
        .with_context(|| format!("writing {}", path.display()))
}

/// The record of the run logged in `log` (`run.mcap`) of `scenario`: every step in the
/// log, complete only if the log says the run ended complete.
pub fn run_from_log(log: &Path, scenario: &Scenario) -> anyhow::Result<Run> {
    let logged = crate::run_log::read_run_log(log)?;
    Ok(logged.to_run(&scenario.name, scenario.unknown.len()))
}

/// Make the outputs of a run that was killed (or whose outputs were lost) from its log:
/// when `dir` holds `run.mcap` but no `summary.json`, every complete step of the log is
/// written out as a run would write it, marked not completed (`"completed": false`,
/// `last_step`). Returns the last step recovered and whether the log says the run ended
/// complete, or `None` when there was nothing to recover.
pub fn recover_run_dir(dir: &Path) -> anyhow::Result<Option<(usize, bool)>> {
    let log_path = dir.join(crate::run_log::RUN_LOG_FILE);
    if dir.join("summary.json").exists() || !log_path.is_file() {
        return Ok(None);
    }
    let logged = crate::run_log::read_run_log(&log_path)?;
    let source = log_path.display().to_string();
    let scenario = Scenario::parse(&logged.scenario_toml, &source)
        .with_context(|| format!("{source}: the scenario logged"))?;
    let run = logged.to_run(&scenario.name, scenario.unknown.len());
    let Some(last) = run.steps.last().map(|s| s.step) else {
        anyhow::bail!("{source}: no step logged");
    };
    let timing = Timing {
        turn_latency_us: Distribution::of_iter(logged.turns.iter().map(|t| t.latency_us)),
        compute_us: Distribution::of_iter(logged.turns.iter().map(|t| t.compute_us)),
        ..Timing::default()
    };
    write_run(dir, &scenario, &source, &run, &logged.first_plan, &timing)?;
    Ok(Some((last, run.completed)))
}

/// Create `dir` and write every output file of `run` into it, with the scenario as run in
/// its resolved form (`scenario.toml`: every obstacle listed, every default and the
/// controller written out; see [`Scenario::to_resolved_toml`]), so the run can be rendered
/// again, or reproduced elsewhere, without this program's random obstacle generator.
/// `source` names the scenario file in the header comment; `first_plan` is the centre path
/// planned before the run (the one the run started along), written as plan 0 of
/// `plans.csv`.
pub fn write_run(
    dir: &Path,
    scenario: &Scenario,
    source: &str,
    run: &Run,
    first_plan: &[Pose],
    timing: &Timing,
) -> anyhow::Result<Vec<PathBuf>> {
    let scenario_text = scenario
        .to_resolved_toml(source)
        .with_context(|| format!("writing the resolved form of {source}"))?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    // The scenario as run names the copy of its map beside it.
    if let Some(map) = &scenario.map {
        map.write_copy(dir)
            .with_context(|| format!("writing the map's copy into {}", dir.display()))?;
    }
    let summary = run.summary();
    let file = SummaryFile {
        summary: &summary,
        timing,
        headings: run.heading_summary(scenario),
        last_step: run.steps.last().map_or(0, |s| s.step),
        log_lines_suppressed: wire::logging::suppressed_log_lines(),
    };
    let mut json = serde_json::to_vec_pretty(&file).context("formatting summary.json")?;
    json.push(b'\n');
    let files = [
        ("scenario.toml", scenario_text.as_bytes().to_vec()),
        ("trajectory.csv", trajectory_csv(run)?),
        ("moves.csv", moves_csv(scenario, run)?),
        ("path.csv", path_csv(&run.centre_path)?),
        ("plans.csv", plans_csv(first_plan, run)?),
        ("obstacles.csv", obstacles_csv(scenario, run)?),
        // Last: a summary.json present means the other files are complete.
        ("summary.json", json),
    ];
    let mut written = Vec::new();
    for (name, bytes) in files {
        let path = dir.join(name);
        write_atomically(&path, &bytes)?;
        written.push(path);
    }
    Ok(written)
}

/// `runs/<name>-<UTC timestamp>` below the current directory, with `-2`, `-3`, ... added
/// when a folder of that name exists already (two runs in the same second).
pub fn default_run_dir(scenario_name: &str) -> PathBuf {
    let base = timestamped_run_dir(scenario_name);
    let taken = |p: &Path| std::fs::symlink_metadata(p).is_ok();
    if !taken(&base) {
        return base;
    }
    let name = base
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    (2..)
        .map(|k| base.with_file_name(format!("{name}-{k}")))
        .find(|p| !taken(p))
        .unwrap_or(base)
}

fn timestamped_run_dir(scenario_name: &str) -> PathBuf {
    let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
        .to_string()
        .replace(':', "-");
    let name = file_name_part(scenario_name);
    PathBuf::from("runs").join(format!("{name}-{stamp}"))
}

/// `text` as a part of a file name: ASCII letters, digits, `-` and `_` kept, anything
/// else `_`.
pub fn file_name_part(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
