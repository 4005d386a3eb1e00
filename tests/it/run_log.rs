//! The run's log (`run.mcap`, written as the run goes): read back by the mcap crate's own
//! reader with every Foxglove message fitting its schema, the outputs equal to what the
//! log holds, and a coordinator killed with SIGKILL at seeded random moments (during
//! start-up and between steps) leaving a folder from which `render` recovers every step
//! before the kill, equal to the reference's first steps byte for byte.

use crate::support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use runner::output::{moves_csv, trajectory_csv};
use runner::run_log::{RUN_LOG_FILE, read_run_log};
use serde_json::Value;
use shared::run::record::Run;
use shared::run::simulate::{plan_centre_path, simulate_along};
use shared::world::scenario::Scenario;
use support::progress::{self, Watched};
use support::{assert_nothing_left, coordinator, json_schema, run_to_end, summary};

#[test]
fn the_schema_check_can_fail() {
    let schema = serde_json::json!({
        "type": "object", "required": ["a"],
        "properties": {"a": {"type": "array", "items": {"type": "integer", "minimum": 0}}}
    });
    assert!(json_schema::check(&schema, &serde_json::json!({"a": [1, 2]})).is_ok());
    for bad in [
        serde_json::json!({"a": [1, -2]}),
        serde_json::json!({"a": [1.5]}),
        serde_json::json!({"b": []}),
        serde_json::json!([]),
    ] {
        assert!(json_schema::check(&schema, &bad).is_err(), "{bad}");
    }
}

/// `discovered-wall.toml` (unknown obstacles found on the way, the centre replanned): the
/// finished log is a complete MCAP file for the mcap crate's strict reader; every message
/// is JSON on a channel with a JSON schema, every Foxglove message fits its schema; one
/// step, scene and frame message per step, one plan per plan found; and the log read back
/// gives exactly the CSV files the run wrote.
#[test]
fn the_log_is_read_by_the_mcap_reader_and_every_foxglove_message_fits_its_schema() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let scenario_file = support::repo_root().join("scenarios/discovered-wall.toml");
    let (output, pid) = run_to_end(&[scenario_file.to_str().expect("utf-8")], &out);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let s = summary(&out);
    let bytes = std::fs::read(out.join(RUN_LOG_FILE)).expect("run.mcap");
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("a complete MCAP file") {
        let message = message.expect("a message");
        let channel = &message.channel;
        assert_eq!(channel.message_encoding, "json", "{}", channel.topic);
        let schema = channel.schema.as_ref().expect("every channel has a schema");
        assert_eq!(schema.encoding, "jsonschema", "{}", channel.topic);
        let value: Value = serde_json::from_slice(&message.data).expect("JSON");
        let schema_json: Value = serde_json::from_slice(&schema.data).expect("JSON schema");
        if schema.name.starts_with("foxglove.") {
            json_schema::check(&schema_json, &value)
                .unwrap_or_else(|e| panic!("{} ({}): {e}", channel.topic, schema.name));
        }
        *counts.entry(channel.topic.clone()).or_default() += 1;
    }
    let steps = s["steps"].as_u64().expect("steps") as usize;
    for topic in ["/formation/step", "/scene", "/tf"] {
        assert_eq!(counts.get(topic), Some(&(steps + 1)), "{topic}: {counts:?}");
    }
    let found_plans = s["replans"]
        .as_array()
        .expect("replans")
        .iter()
        .filter(|r| r["found"] == true)
        .count();
    assert!(found_plans > 0, "discovered-wall replans: {s:#}");
    assert_eq!(counts.get("/centre/plan"), Some(&(1 + found_plans)));
    assert_eq!(counts.get("/formation/end"), Some(&1));
    assert_eq!(counts.get("/formation/scenario"), Some(&1));
    let summary_section = mcap::Summary::read(&bytes)
        .expect("the summary section")
        .expect("a summary");
    // A chunk for what comes before the run, one per step (step 0 too), one for the end.
    assert_eq!(summary_section.chunk_indexes.len(), steps + 3);
    // The outputs are the log's.
    let logged = read_run_log(&out.join(RUN_LOG_FILE)).expect("read back");
    assert!(!logged.truncated);
    let scenario = Scenario::load(&scenario_file).expect("scenario");
    let run = logged.to_run(&scenario.name, scenario.unknown.len());
    assert!(run.completed);
    for (name, bytes) in [
        ("trajectory.csv", trajectory_csv(&run).expect("csv")),
        ("moves.csv", moves_csv(&scenario, &run).expect("csv")),
    ] {
        assert!(
            std::fs::read(out.join(name)).expect(name) == bytes,
            "{name} differs from the log's"
        );
    }
    assert_nothing_left(pid);
}

/// The steps a run must have for kills timed by its progress to have room: the latest
/// step a hold may take ([`progress::latest_hold_step`]) at least half the run.
pub(crate) const ROOM_STEPS: usize = 2 * (progress::RUN_AHEAD_STEPS + 1);

/// The scenario in `file` as it is if its centre path has at least `min_steps` steps;
/// otherwise written into `dir` with its `step_m` divided by the smallest whole number
/// that gives it that many.
pub(crate) fn long_enough(dir: &Path, file: &Path, min_steps: usize) -> PathBuf {
    if progress::centre_path_steps(file) >= min_steps {
        return file.to_path_buf();
    }
    let text = std::fs::read_to_string(file).expect("scenario");
    let (at, line) = text
        .match_indices("\nstep_m = ")
        .next()
        .map(|(at, _)| (at, text[at + 1..].lines().next().unwrap_or("")))
        .unwrap_or_else(|| panic!("{}: no step_m line", file.display()));
    let step_m: f64 = line["step_m = ".len()..]
        .split('#')
        .next()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("{}: {line}", file.display()));
    let stem = file.file_stem().and_then(|s| s.to_str()).expect("name");
    let path = dir.join(format!("{stem}-long.toml"));
    for divisor in 2..=8u32 {
        let longer = format!(
            "{}\nstep_m = {}{}",
            &text[..at],
            step_m / f64::from(divisor),
            &text[at + 1 + line.len()..]
        );
        std::fs::write(&path, longer).expect("write");
        if progress::centre_path_steps(&path) >= min_steps {
            return path;
        }
    }
    panic!(
        "{}: not {min_steps} steps even with step_m / 8",
        file.display()
    );
}

/// The first `last + 1` steps of `run`, as a run that ended there.
fn first_steps(run: &Run, last: usize) -> Run {
    let mut cut = run.clone();
    cut.steps.truncate(last + 1);
    cut
}

/// Wait until the log in `out` holds step 0 (a kill from then on is during start-up).
fn wait_for_step_zero(out: &Path) {
    support::wait_until(Duration::from_secs(60), "step 0 never logged", || {
        read_run_log(&out.join(RUN_LOG_FILE)).is_ok_and(|log| !log.steps.is_empty())
    });
}

/// The files a resumed run must write as the uninterrupted run did, byte for byte.
const RESUMED_EQUAL: [&str; 5] = [
    "trajectory.csv",
    "moves.csv",
    "path.csv",
    "plans.csv",
    "obstacles.csv",
];

/// `coordinator run --resume DIR` (exit 0 required); its process id.
pub(crate) fn resume(out: &Path, what: &str) -> u32 {
    let child = Command::new(support::coordinator_bin())
        .args(["run", "--quiet", "--no-plots", support::TRUSTED, "--resume"])
        .arg(out)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("resume");
    let pid = child.id();
    let resumed = child.wait_with_output().expect("resume");
    assert!(
        resumed.status.success(),
        "{what}: --resume failed: {}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    pid
}

/// Every file of [`RESUMED_EQUAL`] in `out` is the one in `reference`.
pub(crate) fn assert_same_files(out: &Path, reference: &Path, what: &str) {
    for name in RESUMED_EQUAL {
        let got = std::fs::read(out.join(name)).unwrap_or_else(|e| panic!("{what}: {name}: {e}"));
        let want = std::fs::read(reference.join(name)).expect(name);
        assert!(
            got == want,
            "{what}: {name} differs from the uninterrupted run's"
        );
    }
}

/// SIGKILL of the coordinator in runs of the paper example: the first during start-up,
/// the next at a seeded random step while steps are still to come. Each time the folder
/// has no `summary.json`; `render` recovers it (exit 0): `completed` false, every step up
/// to the kill (at least the step the run had reported), and `trajectory.csv` and
/// `moves.csv` equal to the reference's first steps byte for byte. Then `run --resume`
/// goes on from there, and its five data files equal the uninterrupted run's byte for
/// byte. One more kill while the plots are drawn: the data files are whole, `render`
/// draws the plots, and `--resume` refuses the finished run. Nothing is left once the
/// next run has cleaned up. (The system tier: eight more seeded kills, and ten in a
/// changing world.)
#[test]
fn a_coordinator_killed_at_seeded_random_moments_leaves_every_step_before_the_kill() {
    coordinator_killed_at_seeded_moments("paper", 0..2, true);
}

/// The kills `kills` of the test above (kill 0 during start-up, kill K > 0 at the step
/// drawn by seed 26 + K) in runs of the shipped scenario `name` (made longer where the
/// hold needs it: [`long_enough`]), each recovered by `render` and resumed; with `plots`,
/// once more while the plots are drawn.
pub(crate) fn coordinator_killed_at_seeded_moments(
    name: &str,
    kills: std::ops::Range<u64>,
    plots: bool,
) {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut killed = Vec::new();
    let file = long_enough(
        dir.path(),
        &support::repo_root().join(format!("scenarios/{name}.toml")),
        ROOM_STEPS,
    );
    let scenario = Scenario::load(&file).expect("scenario");
    let path = plan_centre_path(&scenario).expect("centre path");
    let reference = simulate_along(&scenario, &path).expect("reference");
    let latest = progress::latest_hold_step(path.len() - 1);
    let uninterrupted = dir.path().join(format!("{name}-uninterrupted"));
    // A generous turn deadline (the log keeps it for `--resume`): the runs are
    // compared byte for byte, and a loaded machine must not turn an honest agent's
    // late answer into a missed turn or a slow kill.
    let args = [file.to_str().expect("utf-8"), "--turn-deadline-ms", "10000"];
    let (output, pid) = run_to_end(&args, &uninterrupted);
    assert!(output.status.success(), "{name}: the uninterrupted run");
    killed.push(pid);
    for kill_number in kills {
        let out = dir.path().join(format!("{name}-{kill_number}"));
        let reported = if kill_number == 0 {
            let mut child = coordinator(&args, &out).spawn().expect("start");
            wait_for_step_zero(&out);
            kill(Pid::from_raw(child.id() as i32), Signal::SIGKILL).expect("kill");
            let _ = child.wait();
            killed.push(child.id());
            0
        } else {
            let step = ChaCha8Rng::seed_from_u64(26 + kill_number).random_range(1..=latest);
            let mut run = Watched::spawn(coordinator(&args, &out), &[step]);
            let held = run.hold();
            kill(Pid::from_raw(run.id() as i32), Signal::SIGKILL).expect("kill");
            drop(held);
            killed.push(run.id());
            let _ = run.wait_with_output();
            step
        };
        let what = format!("{name}, kill {kill_number} (step {reported})");
        assert!(
            !out.join("summary.json").exists(),
            "{what}: the run finished"
        );
        let rendered = Command::new(support::coordinator_bin())
            .arg("render")
            .arg(&out)
            .output()
            .expect("render");
        let stderr = String::from_utf8_lossy(&rendered.stderr);
        assert!(rendered.status.success(), "{what}: {stderr}");
        assert!(stderr.contains("recovered steps 0 to"), "{what}: {stderr}");
        let s = summary(&out);
        assert_eq!(s["completed"], false, "{what}");
        let last = s["last_step"].as_u64().expect("last_step") as usize;
        assert!(last >= reported, "{what}: recovered only up to step {last}");
        assert!(last < path.len() - 1, "{what}: recovered past the kill");
        let want = first_steps(&reference, last);
        for (file_name, bytes) in [
            ("trajectory.csv", trajectory_csv(&want).expect("csv")),
            ("moves.csv", moves_csv(&scenario, &want).expect("csv")),
        ] {
            assert!(
                std::fs::read(out.join(file_name)).expect(file_name) == bytes,
                "{what}: {file_name} differs from the reference's first {} steps",
                last + 1
            );
        }
        killed.push(resume(&out, &what));
        assert_same_files(&out, &uninterrupted, &what);
        let (resumed, whole) = (summary(&out), summary(&uninterrupted));
        assert_eq!(resumed["completed"], true, "{what}");
        // Every answered turn counts in the timing, those before the kill too.
        assert_eq!(
            resumed["turn_latency_us"]["count"], whole["turn_latency_us"]["count"],
            "{what}"
        );
    }
    // Killed while drawing its plots: the data files are there and whole.
    if !plots {
        return finish(killed, dir.path());
    }
    let out = dir.path().join(format!("{name}-plots"));
    let mut child = Command::new(support::coordinator_bin())
        .args(["run", "--quiet", support::TRUSTED])
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start");
    support::wait_until(Duration::from_secs(300), "no plot drawn", || {
        out.join(runner::output::PLOTS_DIR).is_dir()
    });
    kill(Pid::from_raw(child.id() as i32), Signal::SIGKILL).expect("kill");
    let _ = child.wait();
    killed.push(child.id());
    let what = format!("{name}, killed while drawing");
    assert_same_files(&out, &uninterrupted, &what);
    let rendered = Command::new(support::coordinator_bin())
        .arg("render")
        .arg(&out)
        .output()
        .expect("render");
    assert!(rendered.status.success(), "{what}: render");
    let refused = Command::new(support::coordinator_bin())
        .args(["run", "--resume"])
        .arg(&out)
        .output()
        .expect("resume");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{what}: {stderr}");
    assert!(stderr.contains("finished"), "{what}: {stderr}");
    finish(killed, dir.path());
}

/// The killed coordinators' agents went with them; their files go with the next run (in
/// `dir`).
fn finish(killed: Vec<u32>, dir: &Path) {
    let (next, next_pid) = run_to_end(&[], &dir.join("next"));
    assert!(next.status.success());
    for pid in killed.into_iter().chain([next_pid]) {
        assert_nothing_left(pid);
    }
}

/// A log cut at any byte (a run killed while the kernel wrote it) reads back as its
/// first steps, never a step half-read; a byte flipped inside a complete chunk is
/// refused as corrupted, naming the file.
#[test]
fn a_cut_log_reads_as_its_first_steps_and_a_corrupted_chunk_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let (output, pid) = run_to_end(&[], &out);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let log_path = out.join(RUN_LOG_FILE);
    let full = read_run_log(&log_path).expect("the whole log");
    let bytes = std::fs::read(&log_path).expect("run.mcap");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("a summary");
    // The end message is in the last chunk: only a cut after that chunk keeps it.
    let last_chunk_end = summary
        .chunk_indexes
        .last()
        .map(|c| (c.chunk_start_offset + c.chunk_length) as usize)
        .expect("chunks");
    let cut_path = dir.path().join("cut.mcap");
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let mut cuts: Vec<usize> = (0..60).map(|_| rng.random_range(8..bytes.len())).collect();
    cuts.sort_unstable();
    let mut seen_steps = Vec::new();
    for cut in cuts {
        std::fs::write(&cut_path, &bytes[..cut]).expect("write");
        let log = read_run_log(&cut_path).unwrap_or_else(|e| panic!("cut at {cut}: {e}"));
        assert!(log.steps.len() <= full.steps.len(), "cut at {cut}");
        assert_eq!(log.steps[..], full.steps[..log.steps.len()], "cut at {cut}");
        assert_eq!(log.end.is_some(), cut >= last_chunk_end, "cut at {cut}");
        seen_steps.push(log.steps.len());
    }
    // The cuts fell all over the run: some early, some late.
    assert!(seen_steps.first() < seen_steps.last(), "{seen_steps:?}");
    let chunk = &summary.chunk_indexes[summary.chunk_indexes.len() / 2];
    let mut bad = bytes.clone();
    let at = (chunk.chunk_start_offset + chunk.chunk_length - 8) as usize;
    bad[at] ^= 0x20;
    std::fs::write(&cut_path, &bad).expect("write");
    let err = read_run_log(&cut_path).expect_err("a corrupted chunk is refused");
    let text = err.to_string();
    assert!(
        text.contains("cut.mcap") && text.contains("corrupted"),
        "{text}"
    );
    assert_nothing_left(pid);
}
