//! Output files (`docs/outputs.md`): `summary.json`, `trajectory.csv`, `moves.csv`,
//! `path.csv` (the path followed), `plans.csv` (the first plan and every replan taken) and
//! `obstacles.csv` (the moving obstacles at every step, the unknown ones and when they
//! became known).
//! Every file is written whole or not at all (a temporary file, then a rename), and an
//! output folder too ([`OutDir`]: a temporary sibling folder, then a rename).

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Serialize;
use shared::geometry::Pose;
use shared::record::{Run, Summary};
use shared::scenario::Scenario;

use crate::error::CliError;
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
/// round-trip decimal form, so the file reads back to the same bits). In a run folder
/// this is the path the centre actually followed ([`Run::centre_path`]: one pose per step,
/// a wait repeats the pose); `coordinator plan` writes the planned path in this form.
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

/// The reason of plan 0 in `plans.csv`: the path planned before the run.
pub const FIRST_PLAN_REASON: &str = "first";

/// The centre's plans as CSV, one row per pose: `plan,step,reason,x_m,y_m,heading_rad`.
/// Plan 0 is `first_plan` (step 0, reason [`FIRST_PLAN_REASON`]); plans 1, 2, ... are the
/// replans that found a path, in order, each from the pose the centre stood at when it was
/// planned at the start of `step` (reasons `found-obstacle`, `moving-obstacle`). Replans
/// that found no path (the centre waited) have no rows: `summary.json` `replans` lists
/// them all.
pub fn plans_csv(first_plan: &[Pose], run: &Run) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["plan", "step", "reason", "x_m", "y_m", "heading_rad"])?;
    let replans = run
        .course
        .replans
        .iter()
        .filter(|r| r.found)
        .map(|r| (r.step, r.reason.name(), r.path.as_slice()));
    let plans = std::iter::once((0, FIRST_PLAN_REASON, first_plan)).chain(replans);
    for (plan, (step, reason, poses)) in plans.enumerate() {
        for p in poses {
            w.write_record([
                plan.to_string(),
                step.to_string(),
                reason.to_string(),
                p.x_m.to_string(),
                p.y_m.to_string(),
                p.heading_rad.to_string(),
            ])?;
        }
    }
    Ok(w.into_inner()?)
}

/// The obstacles of a changing world as CSV:
/// `step,kind,index,x_m,y_m,radius_m,known_from_step`. First one row per moving obstacle
/// per recorded step (kind `moving`, `index` its place in `[[obstacles.moving]]`, where it
/// stands during the step, `known_from_step` empty: the centre's planner knows their
/// routes); then one row per `[[obstacles.unknown]]` obstacle (kind `unknown`, `step`
/// empty, `known_from_step` the step it joined the known map, empty when never). A static
/// world gives the header alone.
pub fn obstacles_csv(scenario: &Scenario, run: &Run) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "step",
        "kind",
        "index",
        "x_m",
        "y_m",
        "radius_m",
        "known_from_step",
    ])?;
    for s in &run.steps {
        for (i, (p, m)) in s.moving.iter().zip(&scenario.moving).enumerate() {
            w.write_record([
                s.step.to_string(),
                "moving".to_string(),
                i.to_string(),
                p.x.to_string(),
                p.y.to_string(),
                m.radius_m.to_string(),
                String::new(),
            ])?;
        }
    }
    for (i, o) in scenario.unknown.iter().enumerate() {
        let found = run.course.found_at.get(i).copied().flatten();
        w.write_record([
            String::new(),
            "unknown".to_string(),
            i.to_string(),
            o.centre.x.to_string(),
            o.centre.y.to_string(),
            o.radius_m.to_string(),
            found.map_or_else(String::new, |k| k.to_string()),
        ])?;
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
    /// Steps per second of the step loop (start-up excluded).
    pub steps_per_s: f64,
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

/// Create `dir` and write every output file of `run` into it, with the scenario as run in
/// its resolved form (`scenario.toml`: every obstacle listed, every default and the
/// planner written out; see [`Scenario::to_resolved_toml`]), so the run can be rendered
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
pub(crate) fn file_name_part(text: &str) -> String {
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

/// An output folder (`run --out`, `compare --out`), checked before anything runs.
///
/// A folder *holds something* when it exists and is not an empty folder: a previous run,
/// an unrelated folder of the user's, a file or a symbolic link. Such a path is refused
/// (exit code 2, nothing touched) unless `--force` is given; with `--force` it is replaced
/// whole. Either way the new outputs are written into a fresh temporary sibling folder
/// ([`Staging`]) and renamed into place when complete, so no file of an older run
/// survives beside the new ones and the folder is never seen half-written.
#[derive(Debug, Clone)]
pub struct OutDir {
    dir: PathBuf,
    force: bool,
}

impl OutDir {
    /// Check `dir` (creating nothing): refuse, as a usage error, a path that holds
    /// something unless `force`, a path with no folder name of its own (`.`, `..`, `/`),
    /// a folder that contains the current directory, and a path below a file.
    pub fn check(dir: PathBuf, force: bool) -> Result<Self, CliError> {
        let shown = dir.display().to_string();
        let usage = |reason: &str| CliError::Usage(format!("{shown}: {reason}"));
        if dir.file_name().is_none() {
            return Err(usage("not a folder name to write a run into"));
        }
        match std::fs::symlink_metadata(&dir) {
            Ok(meta) => {
                let empty_folder = meta.is_dir()
                    && std::fs::read_dir(&dir)
                        .map_err(|e| usage(&e.to_string()))?
                        .next()
                        .is_none();
                if !empty_folder && !force {
                    let what = if meta.is_dir() {
                        "folder is not empty"
                    } else {
                        "exists and is not a folder"
                    };
                    return Err(usage(&format!(
                        "{what}; pass --force to replace it whole, or choose another --out"
                    )));
                }
                if meta.is_dir()
                    && let (Ok(cwd), Ok(target)) =
                        (std::env::current_dir(), std::fs::canonicalize(&dir))
                    && cwd.starts_with(&target)
                {
                    return Err(usage("contains the current directory; it is not replaced"));
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
                ) =>
            {
                // The nearest existing ancestor must be a folder, or nothing can be
                // created below it.
                if let Some(a) = dir
                    .ancestors()
                    .skip(1)
                    .filter(|a| !a.as_os_str().is_empty())
                    .find(|a| std::fs::symlink_metadata(a).is_ok())
                    && !a.is_dir()
                {
                    return Err(usage(&format!("{} is not a folder", a.display())));
                }
            }
            Err(e) => return Err(usage(&e.to_string())),
        }
        Ok(Self { dir, force })
    }

    /// The folder the outputs end up in.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Create the fresh temporary sibling folder (and any missing parent) to write the
    /// outputs into.
    pub fn begin(&self) -> anyhow::Result<Staging> {
        let parent = match self.dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("creating {}", parent.display()))?;
        let name = self
            .dir
            .file_name()
            .with_context(|| format!("{}: not a folder name", self.dir.display()))?
            .to_string_lossy()
            .into_owned();
        let sibling = |what: &str| parent.join(format!(".{name}.{what}-{}", std::process::id()));
        let tmp = sibling("tmp");
        // Only a run of a process with this id (long dead: it is us now) left it.
        if std::fs::symlink_metadata(&tmp).is_ok() {
            remove_any(&tmp)?;
        }
        std::fs::create_dir(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        Ok(Staging {
            tmp,
            old: sibling("old"),
            target: self.dir.clone(),
            force: self.force,
            done: false,
        })
    }
}

/// The temporary folder a run's outputs are written into; [`Staging::commit`] renames it
/// into place. Dropped without a commit (an error on the way), it is removed.
#[derive(Debug)]
pub struct Staging {
    tmp: PathBuf,
    old: PathBuf,
    target: PathBuf,
    force: bool,
    done: bool,
}

impl Staging {
    /// The folder to write into.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Put the complete folder in place: a rename onto a missing or empty target; with
    /// `--force`, an atomic exchange with whatever is there, which is then removed.
    /// Returns the final folder.
    pub fn commit(mut self) -> anyhow::Result<PathBuf> {
        self.done = true;
        let exists = std::fs::symlink_metadata(&self.target).is_ok();
        if !(exists && self.force) {
            // rename(2) replaces a missing or an empty folder and nothing else: a folder
            // filled since the check is not lost.
            return match std::fs::rename(&self.tmp, &self.target) {
                Ok(()) => Ok(self.target.clone()),
                Err(e) => Err(anyhow::anyhow!(
                    "{}: {e}; the outputs are in {}",
                    self.target.display(),
                    self.tmp.display()
                )),
            };
        }
        use nix::fcntl::{AT_FDCWD, RenameFlags, renameat2};
        match renameat2(
            AT_FDCWD,
            &self.tmp,
            AT_FDCWD,
            &self.target,
            RenameFlags::RENAME_EXCHANGE,
        ) {
            // The old contents are now at the temporary name.
            Ok(()) => remove_any(&self.tmp)?,
            // A file system without the exchange: two renames (a moment with no folder,
            // never a mixed or half-written one).
            Err(_) => {
                std::fs::rename(&self.target, &self.old).with_context(|| {
                    format!(
                        "moving {} aside; the outputs are in {}",
                        self.target.display(),
                        self.tmp.display()
                    )
                })?;
                std::fs::rename(&self.tmp, &self.target).with_context(|| {
                    format!(
                        "renaming {} to {} (the old one is in {})",
                        self.tmp.display(),
                        self.target.display(),
                        self.old.display()
                    )
                })?;
                remove_any(&self.old)?;
            }
        }
        Ok(self.target.clone())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

/// Remove `path` whatever it is (a folder with its contents, a file, a link).
fn remove_any(path: &Path) -> anyhow::Result<()> {
    let meta =
        std::fs::symlink_metadata(path).with_context(|| format!("reading {}", path.display()))?;
    if meta.is_dir() {
        std::fs::remove_dir_all(path)
    } else {
        std::fs::remove_file(path)
    }
    .with_context(|| format!("removing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch folder of this test, removed when dropped.
    struct Scratch(PathBuf);
    impl Scratch {
        fn new(name: &str) -> Self {
            let dir = std::env::temp_dir()
                .join(format!("coordinator-output-{name}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).expect("scratch folder");
            Self(dir)
        }
        fn names(&self) -> Vec<String> {
            let mut v: Vec<String> = std::fs::read_dir(&self.0)
                .expect("read_dir")
                .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        }
    }
    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn an_abandoned_staging_folder_is_removed_and_the_target_never_appears() {
        let s = Scratch::new("abandon");
        let out = OutDir::check(s.0.join("run"), false).expect("a missing folder is fine");
        let staging = out.begin().expect("begin");
        std::fs::write(staging.path().join("half.csv"), b"1,2").expect("write");
        assert_eq!(s.names().len(), 1, "only the hidden temporary folder");
        drop(staging);
        assert!(s.names().is_empty(), "{:?}", s.names());
    }

    #[test]
    fn force_swaps_the_new_folder_in_whole() {
        let s = Scratch::new("force");
        let target = s.0.join("run");
        std::fs::create_dir_all(target.join("plots")).expect("mkdir");
        std::fs::write(target.join("plots").join("old.png"), b"old").expect("write");
        let refused = OutDir::check(target.clone(), false).expect_err("not empty");
        assert_eq!(refused.exit_code(), 2);
        let staging = OutDir::check(target.clone(), true)
            .expect("forced")
            .begin()
            .expect("begin");
        std::fs::write(staging.path().join("summary.json"), b"{}").expect("write");
        assert_eq!(staging.commit().expect("commit"), target);
        assert_eq!(s.names(), ["run"]);
        assert!(!target.join("plots").exists());
        assert_eq!(
            std::fs::read(target.join("summary.json")).expect("new"),
            b"{}"
        );
    }

    #[test]
    fn without_force_a_folder_filled_meanwhile_is_kept_and_the_new_one_named() {
        let s = Scratch::new("race");
        let target = s.0.join("run");
        let staging = OutDir::check(target.clone(), false)
            .expect("missing")
            .begin()
            .expect("begin");
        std::fs::create_dir(&target).expect("mkdir");
        std::fs::write(target.join("theirs"), b"x").expect("write");
        let tmp = staging.path().to_path_buf();
        let e = staging.commit().expect_err("not replaced without --force");
        assert!(e.to_string().contains(&tmp.display().to_string()), "{e}");
        assert_eq!(std::fs::read(target.join("theirs")).expect("kept"), b"x");
        assert!(
            tmp.is_dir(),
            "the new outputs are kept where the message says"
        );
    }

    #[test]
    fn names_that_are_no_folder_of_their_own_are_refused() {
        for dir in [".", "..", "/"] {
            let e = OutDir::check(PathBuf::from(dir), true).expect_err(dir);
            assert_eq!(e.exit_code(), 2, "{dir}");
        }
    }
}
