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

use coordinator::output::{moves_csv, trajectory_csv};
use coordinator::run_log::{RUN_LOG_FILE, read_run_log};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use shared::record::Run;
use shared::scenario::Scenario;
use shared::simulate::{plan_centre_path, simulate_along};
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
const ROOM_STEPS: usize = 2 * (progress::RUN_AHEAD_STEPS + 1);

/// The scenario in `file` as it is if its centre path has at least `min_steps` steps;
/// otherwise written into `dir` with its `step_m` divided by the smallest whole number
/// that gives it that many.
fn long_enough(dir: &Path, file: &Path, min_steps: usize) -> PathBuf {
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
fn resume(out: &Path, what: &str) -> u32 {
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
fn assert_same_files(out: &Path, reference: &Path, what: &str) {
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
        out.join(coordinator::render::PLOTS_DIR).is_dir()
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

/// Every file in `dir` (recursively) with its bytes: what a refusal must leave as it was.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return files;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files.extend(snapshot(&path));
        } else {
            files.insert(path.clone(), std::fs::read(&path).expect("read"));
        }
    }
    files
}

/// A killed run's folder made from the finished log `from` with the mcap crate's writer:
/// every message but the end, the scenario message's format version set to `version`.
fn killed_copy(from: &Path, to: &Path, version: u64) {
    killed_copy_editing_last_step(from, to, version, |_| {});
}

/// [`killed_copy`] with the last step's message (JSON, its CRC made right by the writer)
/// changed by `edit`: a crafted log that reads as well as a real one.
fn killed_copy_editing_last_step(from: &Path, to: &Path, version: u64, edit: impl Fn(&mut Value)) {
    std::fs::create_dir_all(to).expect("folder");
    let bytes = std::fs::read(from).expect("run.mcap");
    let is_step = |m: &mcap::Message| m.channel.topic == "/formation/step";
    let steps = mcap::MessageStream::new(&bytes)
        .expect("a complete MCAP file")
        .filter(|m| m.as_ref().is_ok_and(is_step))
        .count();
    let mut seen_steps = 0;
    let file =
        std::io::BufWriter::new(std::fs::File::create(to.join(RUN_LOG_FILE)).expect("create"));
    let mut writer = mcap::WriteOptions::new()
        .compression(None)
        .create(file)
        .expect("writer");
    for message in mcap::MessageStream::new(&bytes).expect("a complete MCAP file") {
        let mut message = message.expect("a message");
        match message.channel.topic.as_str() {
            "/formation/end" => continue,
            "/formation/step" => {
                seen_steps += 1;
                if seen_steps == steps {
                    let mut value: Value = serde_json::from_slice(&message.data).expect("JSON");
                    edit(&mut value);
                    message.data = serde_json::to_vec(&value).expect("JSON").into();
                }
            }
            "/formation/scenario" => {
                let mut value: Value = serde_json::from_slice(&message.data).expect("JSON");
                value["format_version"] = version.into();
                message.data = serde_json::to_vec(&value).expect("JSON").into();
            }
            _ => {}
        }
        writer.write(&message).expect("write");
    }
    writer.finish().expect("finish");
}

/// `run --resume` on what is not a killed run of this program's format and this
/// scenario: a missing or empty folder, a finished run, a log of another format
/// version, of another scenario, with a corrupted chunk, cut inside its first chunk, or
/// whose last step breaks the safety invariant (agents on each other, one far outside):
/// exit 2 with one line naming the folder or file and what is wrong, and every file there
/// as it was. The same killed copy, whole and of this version, resumes to the finished
/// run's files (so what is refused is refused for the reason named).
#[test]
fn resume_refuses_a_folder_that_is_not_a_killed_run_and_changes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let finished = dir.path().join("finished");
    let (output, pid) = run_to_end(&[], &finished);
    assert!(output.status.success());
    let log = finished.join(RUN_LOG_FILE);
    let version = coordinator::run_log::LOG_FORMAT_VERSION as u64;

    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).expect("folder");
    let other_version = dir.path().join("other-version");
    killed_copy(&log, &other_version, version + 6);
    let killed = dir.path().join("killed");
    killed_copy(&log, &killed, version);
    let corrupted = dir.path().join("corrupted");
    killed_copy(&log, &corrupted, version);
    let mut bytes = std::fs::read(corrupted.join(RUN_LOG_FILE)).expect("log");
    let summary_section = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("a summary");
    let chunk = &summary_section.chunk_indexes[summary_section.chunk_indexes.len() / 2];
    bytes[(chunk.chunk_start_offset + chunk.chunk_length - 8) as usize] ^= 0x20;
    std::fs::write(corrupted.join(RUN_LOG_FILE), &bytes).expect("write");
    let cut = dir.path().join("cut");
    std::fs::create_dir(&cut).expect("folder");
    std::fs::write(cut.join(RUN_LOG_FILE), &bytes[..40]).expect("write");
    let dense = support::repo_root().join("scenarios/dense.toml");
    // Crafted logs, read as well as real ones: the last step puts agent 0 on agent 1, or
    // far outside the field.
    let on_each_other = dir.path().join("on-each-other");
    killed_copy_editing_last_step(&log, &on_each_other, version, |step| {
        step["agents"][0]["position"] = step["agents"][1]["position"].clone();
    });
    let far_away = dir.path().join("far-away");
    killed_copy_editing_last_step(&log, &far_away, version, |step| {
        step["agents"][0]["position"] = serde_json::json!([1e300, 1e300]);
    });

    let cases: [(&str, &Path, Option<&Path>, &str); 9] = [
        (
            "a missing folder",
            &dir.path().join("missing"),
            None,
            "no such folder",
        ),
        ("an empty folder", &empty, None, "not a run folder"),
        ("a finished run", &finished, None, "finished"),
        ("another format", &other_version, None, "format version"),
        ("another scenario", &killed, Some(&dense), "not of"),
        ("a corrupted chunk", &corrupted, None, "corrupted"),
        ("a log cut short", &cut, None, "no scenario"),
        (
            "agents on each other",
            &on_each_other,
            None,
            "not where a run leaves its agents",
        ),
        (
            "an agent far outside the field",
            &far_away,
            None,
            "not where a run leaves its agents",
        ),
    ];
    for (what, folder, scenario, expected) in cases {
        let before = snapshot(folder);
        let mut command = Command::new(support::coordinator_bin());
        command.arg("run");
        if let Some(file) = scenario {
            command.arg(file);
        }
        let refused = command
            .arg("--resume")
            .arg(folder)
            .output()
            .expect("resume");
        let stderr = String::from_utf8_lossy(&refused.stderr);
        assert_eq!(refused.status.code(), Some(2), "{what}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{what}: {stderr}");
        assert!(stderr.contains(expected), "{what}: {stderr}");
        let named = folder.file_name().and_then(|n| n.to_str()).expect("name");
        assert!(
            stderr.contains(named),
            "{what}: the line names no file: {stderr}"
        );
        assert!(snapshot(folder) == before, "{what}: the folder changed");
    }
    let resumed = resume(&killed, "the killed copy");
    assert_same_files(&killed, &finished, "the killed copy");
    for pid in [pid, resumed] {
        assert_nothing_left(pid);
    }
}

/// Resumed runs of what a run can hold, killed twice at seeded steps (resumed after the
/// first kill, killed again, resumed again): deaths at fixed steps and their
/// replacements in parallel turns, moving obstacles. Each time the five data files equal
/// the uninterrupted run's byte for byte. (The system tier: sensing and a top speed.)
#[test]
fn resumed_runs_with_deaths_replacements_parallel_turns_and_moving_obstacles_equal_the_uninterrupted_ones()
 {
    let root = support::repo_root();
    resumed_twice(&[
        (
            "swarm16-parallel",
            root.join("tests/data/swarm16-parallel.toml"),
            &["--die-agent", "3@40", "--die-agent", "9@150", "--respawn"],
        ),
        (
            "moving-field",
            root.join("scenarios/moving-field.toml"),
            &[],
        ),
    ]);
}

/// For each case (a name, a scenario file, the run's extra flags), the run killed twice
/// and resumed twice, as the test above says; the file is made longer where the holds
/// need it ([`long_enough`]), and so that every `--die-agent` step falls in the run's
/// first half.
pub(crate) fn resumed_twice(cases: &[(&str, PathBuf, &[&str])]) {
    let mut rng = ChaCha8Rng::seed_from_u64(2612);
    let dir = tempfile::tempdir().expect("tempdir");
    let mut pids = Vec::new();
    for &(name, ref file, extra) in cases {
        let last_death = extra
            .iter()
            .filter_map(|a| a.split_once('@'))
            .filter_map(|(_, step)| step.parse::<usize>().ok())
            .max()
            .unwrap_or(0);
        let file = long_enough(dir.path(), file, ROOM_STEPS.max(2 * last_death));
        // A generous turn deadline (kept in the log for `--resume`): the runs are
        // compared byte for byte, and a loaded machine must not get an honest agent
        // killed as slow.
        let mut args = vec![file.to_str().expect("utf-8"), "--turn-deadline-ms", "10000"];
        args.extend_from_slice(extra);
        let uninterrupted = dir.path().join(format!("{name}-uninterrupted"));
        let (output, pid) = run_to_end(&args, &uninterrupted);
        assert!(output.status.success(), "{name}: the uninterrupted run");
        pids.push(pid);
        let latest = progress::latest_hold_step(progress::centre_path_steps(&file));
        let out = dir.path().join(name);
        // The first kill in the run as started, the second in the resumed run.
        let first = rng.random_range(1..=latest / 2);
        let mut run = Watched::spawn(coordinator(&args, &out), &[first]);
        let held = run.hold();
        kill(Pid::from_raw(run.id() as i32), Signal::SIGKILL).expect("kill");
        drop(held);
        pids.push(run.id());
        let _ = run.wait_with_output();
        let second = rng.random_range(first + 1..=latest);
        let mut resumed = Command::new(support::coordinator_bin());
        resumed
            .args(["run", "--quiet", "--no-plots", support::TRUSTED, "--resume"])
            .arg(&out)
            .env("FORMATION_AGENT_BIN", support::agent_bin())
            .stdin(std::process::Stdio::null());
        let mut run = Watched::spawn(resumed, &[second]);
        let held = run.hold();
        kill(Pid::from_raw(run.id() as i32), Signal::SIGKILL).expect("kill");
        drop(held);
        pids.push(run.id());
        let _ = run.wait_with_output();
        let what = format!("{name}, killed at steps {first} and {second}");
        pids.push(resume(&out, &what));
        assert_same_files(&out, &uninterrupted, &what);
        let s = summary(&out);
        assert_eq!(s["completed"], true, "{what}");
        // The same faults (the process ids and detection times are the run's own).
        let faults = |s: &Value| -> Vec<(Value, Value, Value)> {
            s["faults"]
                .as_array()
                .expect("faults")
                .iter()
                .map(|f| (f["agent"].clone(), f["step"].clone(), f["kind"].clone()))
                .collect()
        };
        assert_eq!(
            faults(&s),
            faults(&summary(&uninterrupted)),
            "{what}: the faults"
        );
    }
    for pid in pids {
        assert_nothing_left(pid);
    }
}

/// A run folder handed over may hold links and files of any size. `run --resume` and
/// `render` write nothing through a link (the log's temporary name or a data file linked
/// elsewhere is replaced by the run's own file; a `plots` linked to another folder is
/// refused) and read nothing unbounded (a sparse log or table over the bound, a FIFO in
/// a table's place: one line, at once).
#[test]
fn resume_and_render_write_nothing_through_links_and_read_nothing_unbounded() {
    use std::os::unix::fs::symlink;
    let dir = tempfile::tempdir().expect("tempdir");
    let finished = dir.path().join("finished");
    let (output, pid) = run_to_end(&[], &finished);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let version = coordinator::run_log::LOG_FORMAT_VERSION as u64;
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, b"not the run's").expect("write");

    // --resume with the log's temporary name and a data file linked to the victim.
    let linked = dir.path().join("linked");
    killed_copy(&finished.join(RUN_LOG_FILE), &linked, version);
    for name in ["run.mcap.resuming", "trajectory.csv"] {
        symlink(&victim, linked.join(name)).expect("symlink");
    }
    let resumed = resume(&linked, "links in the folder");
    assert_eq!(std::fs::read(&victim).expect("victim"), b"not the run's");
    assert_same_files(&linked, &finished, "links in the folder");
    for name in [RUN_LOG_FILE, "trajectory.csv"] {
        let meta = std::fs::symlink_metadata(linked.join(name)).expect(name);
        assert!(meta.is_file(), "{name} is still a link");
    }

    // render with `plots` linked to another folder: refused, nothing written there.
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).expect("folder");
    let plots = linked.join(coordinator::render::PLOTS_DIR);
    if plots.exists() {
        std::fs::remove_dir_all(&plots).expect("remove plots");
    }
    symlink(&elsewhere, &plots).expect("symlink");
    let mut render = Command::new(support::coordinator_bin());
    render.arg("render").arg(&linked);
    let rendered = support::run_bounded(render).unwrap_or_else(|e| panic!("{e}"));
    let stderr = String::from_utf8_lossy(&rendered.stderr);
    assert_eq!(
        rendered.status.code(),
        Some(2),
        "render through a link is bad input: {stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("symbolic link"), "{stderr}");
    assert_eq!(std::fs::read_dir(&elsewhere).expect("read").count(), 0);

    // A sparse log over the bound: --resume refuses it in one line.
    let sparse_log = dir.path().join("sparse-log");
    std::fs::create_dir(&sparse_log).expect("folder");
    std::fs::File::create(sparse_log.join(RUN_LOG_FILE))
        .and_then(|f| f.set_len(coordinator::run_log::MAX_RUN_LOG_BYTES + 1))
        .expect("a sparse log");
    let mut command = Command::new(support::coordinator_bin());
    command.args(["run", "--resume"]).arg(&sparse_log);
    let refused = support::run_bounded(command).unwrap_or_else(|e| panic!("{e}"));
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("run.mcap") && stderr.contains("more than"),
        "{stderr}"
    );

    // render of a finished run whose table is sparse over the bound, or a FIFO.
    let sparse_table = |path: &Path| {
        std::fs::File::create(path)
            .and_then(|f| f.set_len(coordinator::run_log::MAX_RUN_LOG_BYTES + 1))
            .expect("a sparse table");
    };
    let fifo_table = |path: &Path| {
        nix::unistd::mkfifo(path, nix::sys::stat::Mode::from_bits_truncate(0o600)).expect("mkfifo");
    };
    type MakeTable<'a> = &'a dyn Fn(&Path);
    let makers: [(&str, MakeTable); 2] = [("sparse", &sparse_table), ("fifo", &fifo_table)];
    for (what, make) in makers {
        let copy = dir.path().join(what);
        std::fs::create_dir(&copy).expect("folder");
        for entry in std::fs::read_dir(&finished).expect("read").flatten() {
            if entry.path().is_file() {
                std::fs::copy(entry.path(), copy.join(entry.file_name())).expect("copy");
            }
        }
        let table = copy.join("trajectory.csv");
        std::fs::remove_file(&table).expect("remove");
        make(&table);
        let mut render = Command::new(support::coordinator_bin());
        render.arg("render").arg(&copy);
        let refused = support::run_bounded(render).unwrap_or_else(|e| panic!("{what}: {e}"));
        let stderr = String::from_utf8_lossy(&refused.stderr);
        assert_eq!(refused.status.code(), Some(2), "{what}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{what}: {stderr}");
        assert!(stderr.contains("trajectory.csv"), "{what}: {stderr}");
    }
    for pid in [pid, resumed] {
        assert_nothing_left(pid);
    }
}
