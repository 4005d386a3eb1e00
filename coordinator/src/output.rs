//! Output files (`docs/outputs.md`): `summary.json`, `trajectory.csv`, `path.csv`.
//! Every file is written whole or not at all (a temporary file, then a rename).

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Serialize;
use shared::geometry::Pose;
use shared::run::{Run, Summary};

use crate::stats::Distribution;

/// Write `bytes` to `path` atomically: a temporary file beside it, then a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let name = path
        .file_name()
        .with_context(|| format!("{}: not a file name", path.display()))?;
    let tmp = path.with_file_name(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("renaming to {}", path.display()))?;
    Ok(())
}

/// The centre path as CSV: `step,x_m,y_m,heading_rad`, full precision (shortest
/// round-trip decimal form, so the file reads back to the same bits).
pub fn path_csv(path: &[Pose]) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["step", "x_m", "y_m", "heading_rad"])?;
    for (step, p) in path.iter().enumerate() {
        w.write_record([
            step.to_string(),
            p.x_m.to_string(),
            p.y_m.to_string(),
            p.heading_rad.to_string(),
        ])?;
    }
    Ok(w.into_inner()?)
}

/// The trajectory as CSV, one row per agent per step (`docs/outputs.md`), full
/// precision.
pub fn trajectory_csv(run: &Run) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "step",
        "agent",
        "x",
        "y",
        "slot_x",
        "slot_y",
        "best_x",
        "best_y",
        "deviation_m",
        "clearance_m",
        "status",
        "alive",
    ])?;
    for s in &run.steps {
        for (i, a) in s.agents.iter().enumerate() {
            w.write_record([
                s.step.to_string(),
                i.to_string(),
                a.position.x.to_string(),
                a.position.y.to_string(),
                a.slot.x.to_string(),
                a.slot.y.to_string(),
                a.best.x.to_string(),
                a.best.y.to_string(),
                a.deviation_m.to_string(),
                a.clearance_m.to_string(),
                a.status.name().to_string(),
                u8::from(a.alive).to_string(),
            ])?;
        }
    }
    Ok(w.into_inner()?)
}

/// Every move's polyline as CSV: `step,agent,index,x,y` (one row per waypoint).
pub fn moves_csv(run: &Run) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["step", "agent", "index", "x", "y"])?;
    for s in &run.steps {
        for (i, a) in s.agents.iter().enumerate() {
            for (k, p) in a.waypoints.iter().enumerate() {
                w.write_record([
                    s.step.to_string(),
                    i.to_string(),
                    k.to_string(),
                    p.x.to_string(),
                    p.y.to_string(),
                ])?;
            }
        }
    }
    Ok(w.into_inner()?)
}

/// Timing figures of a multi-process run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timing {
    /// Turn latency (world published to move received), microseconds.
    pub turn_latency_us: Distribution,
    /// Agent compute time per turn, microseconds.
    pub compute_us: Distribution,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// From the first spawn to the last ready handshake, seconds.
    pub startup_s: f64,
    /// Resident set size of the agent processes at the end of the run, KiB.
    pub agent_rss_kib: Distribution,
}

/// `summary.json`: the run's figures and its timing.
#[derive(Serialize)]
struct SummaryFile<'a> {
    #[serde(flatten)]
    summary: &'a Summary,
    #[serde(flatten)]
    timing: &'a Timing,
    /// The step the run stopped after (the last one when it completed).
    last_step: usize,
}

/// Create `dir` and write every output file of `run` into it, with the scenario's text
/// (`scenario.toml`) so the run can be rendered again without re-planning.
pub fn write_run(
    dir: &Path,
    scenario_text: &str,
    run: &Run,
    timing: &Timing,
) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let summary = run.summary();
    let file = SummaryFile {
        summary: &summary,
        timing,
        last_step: run.steps.last().map_or(0, |s| s.step),
    };
    let mut json = serde_json::to_vec_pretty(&file).context("formatting summary.json")?;
    json.push(b'\n');
    let files = [
        ("scenario.toml", scenario_text.as_bytes().to_vec()),
        ("trajectory.csv", trajectory_csv(run)?),
        ("moves.csv", moves_csv(run)?),
        ("path.csv", path_csv(&run.centre_path)?),
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

/// `runs/<name>-<UTC timestamp>` below the current directory.
pub fn default_run_dir(scenario_name: &str) -> PathBuf {
    let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
        .to_string()
        .replace(':', "-");
    let name: String = scenario_name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    PathBuf::from("runs").join(format!("{name}-{stamp}"))
}
