//! `run --resume DIR`: a killed run's folder refused when it is not one, changing
//! nothing; resumed runs (with deaths, replacements, parallel turns, moving obstacles)
//! equal to the uninterrupted ones; resume and render writing through no link and
//! reading nothing unbounded. The kills that make the folders are in `run_log.rs`.

use crate::support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use runner::run_log::RUN_LOG_FILE;
use serde_json::Value;
use support::progress::{self, Watched};
use support::{assert_nothing_left, coordinator, run_to_end, summary};

use crate::run_log::{ROOM_STEPS, assert_same_files, long_enough, resume};

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
    let version = runner::run_log::LOG_FORMAT_VERSION as u64;

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
    let version = runner::run_log::LOG_FORMAT_VERSION as u64;
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
    let plots = linked.join(runner::output::PLOTS_DIR);
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
        .and_then(|f| f.set_len(runner::run_log::MAX_RUN_LOG_BYTES + 1))
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
            .and_then(|f| f.set_len(runner::run_log::MAX_RUN_LOG_BYTES + 1))
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
