//! An agent is an untrusted process: what it starts dies with the run, and the run's
//! files are private to its user. A rogue agent (`--misbehave fork`) leaves two sleeping
//! children that ignore SIGTERM, one in its process group and one escaped into a session
//! of its own; after the run neither is alive nor left as a zombie, and nothing of the
//! run is left in /dev/shm. While a run goes, its folder is 0700 and ours, and no file of
//! the run in /dev/shm is open to group or others.

use crate::support;

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use runner::turns::{BetweenSteps, FaultInjection, RunOptions, run_scenario, run_scenario_with};
use shared::geometry::Pose;
use shared::run::simulate::plan_centre_path;
use shared::world::scenario::Scenario;
use wire::{RUN_ENV, effective_uid, run_root};

/// `argv[0]` of the processes a `fork` agent starts (`agent::misbehave::stray_marker`).
fn stray_marker(prefix: &str) -> String {
    format!("formation-stray-{prefix}")
}

/// A process: its pid, and its start time (with the pid, names it for good).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Proc {
    pid: u32,
    start: u64,
    pgid: u32,
}

fn stat(pid: u32) -> Option<(u8, Proc)> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let rest: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    Some((
        *rest.first()?.as_bytes().first()?,
        Proc {
            pid,
            pgid: rest.get(2)?.parse().ok()?,
            start: rest.get(19)?.parse().ok()?,
        },
    ))
}

/// Whether process `p` still exists, zombie or not (a zombie is a process not reaped).
fn exists(p: &Proc) -> bool {
    stat(p.pid).is_some_and(|(_, now)| now.start == p.start)
}

/// Live processes whose `argv[0]` is `marker`.
fn strays(marker: &str) -> Vec<Proc> {
    all_pids()
        .filter(|&pid| {
            std::fs::read(format!("/proc/{pid}/cmdline"))
                .is_ok_and(|c| c.split(|&b| b == 0).next() == Some(marker.as_bytes()))
        })
        .filter_map(stat)
        .filter(|(state, _)| *state != b'Z')
        .map(|(_, p)| p)
        .collect()
}

/// Live processes with `FORMATION_RUN=<prefix>` in their environment.
fn processes_of_run(prefix: &str) -> Vec<u32> {
    let entry = format!("{RUN_ENV}={prefix}").into_bytes();
    all_pids()
        .filter(|&pid| {
            std::fs::read(format!("/proc/{pid}/environ"))
                .is_ok_and(|env| env.split(|&b| b == 0).any(|e| e == entry.as_slice()))
        })
        .collect()
}

fn all_pids() -> impl Iterator<Item = u32> {
    std::fs::read_dir("/proc")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse().ok())
}

fn options(misbehave: &[(usize, &str)]) -> RunOptions {
    RunOptions {
        agent_bin: Some(support::agent_bin()),
        // About processes, not liveness: a loaded machine must not turn a late honest
        // agent into a missed turn.
        turn_deadline: Duration::from_secs(10),
        progress: false,
        faults: FaultInjection {
            misbehave: misbehave
                .iter()
                .map(|(a, m)| (*a, m.parse().expect("a misbehave mode")))
                .collect(),
            ..FaultInjection::default()
        },
        ..RunOptions::default()
    }
}

fn paper() -> (Scenario, Vec<Pose>) {
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    (scenario, path)
}

/// Nothing of run `prefix` is left: no process of the run, none of `started` alive or
/// unreaped, no file.
fn assert_nothing_left(prefix: &str, started: &[Proc]) {
    // The run is over when the call returns: no grace period.
    let alive: Vec<_> = started.iter().filter(|p| exists(p)).collect();
    assert!(
        alive.is_empty(),
        "{prefix}: strays left, alive or zombie: {alive:?}"
    );
    assert!(strays(&stray_marker(prefix)).is_empty(), "{prefix}");
    assert_eq!(processes_of_run(prefix), Vec::<u32>::new(), "{prefix}");
    let left = support::leftovers(prefix);
    assert!(left.is_empty(), "{prefix}: files left: {left:?}");
}

#[test]
fn what_a_rogue_agent_starts_dies_with_the_run_in_process() {
    let (scenario, path) = paper();
    let mut seen: Option<(String, Vec<Proc>)> = None;
    let outcome = run_scenario_with(
        &scenario,
        &path,
        &options(&[(2, "fork")]),
        &mut |b: BetweenSteps<'_>| {
            if seen.is_none() {
                let prefix = b.prefix.to_string();
                // The strays start before the agent's handshake: by step 1 both run.
                let found = strays(&stray_marker(&prefix));
                seen = Some((prefix, found));
            }
            Ok(())
        },
    )
    .expect("run");
    let (prefix, started) = seen.expect("at least one step");
    assert_eq!(prefix, outcome.prefix);
    // The test means something only if the rogue did its part: one stray in the agent's
    // group, one that left it for a session (and group) of its own.
    assert_eq!(started.len(), 2, "{started:?}");
    let escaped: Vec<_> = started.iter().filter(|p| p.pgid == p.pid).collect();
    assert_eq!(escaped.len(), 1, "{started:?}");
    assert!(!outcome.interrupted);
    assert!(outcome.run.completed);
    let s = outcome.run.summary();
    assert_eq!(s.collisions, 0);
    assert!(s.min_clearance_m >= -shared::control::safety::SAFETY_TOLERANCE_M);
    // Playing honestly otherwise: no fault at all.
    assert!(outcome.run.faults.is_empty(), "{:?}", outcome.run.faults);
    assert_nothing_left(&prefix, &started);
}

#[test]
fn what_a_rogue_agent_starts_dies_with_the_run_from_the_command_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let child = Command::new(support::coordinator_bin())
        .args([
            "run",
            "--misbehave",
            "2=fork",
            "--turn-deadline-ms",
            "10000",
        ])
        .arg("--out")
        .arg(&out)
        .args(["--quiet", "--no-plots"])
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start coordinator");
    // The run's prefix, from the strays' names, while it goes.
    let stem = stray_marker(&wire::RunPrefix::head(child.id()));
    let mut started: Vec<(String, Proc)> = Vec::new();
    support::wait_until(
        Duration::from_secs(60),
        "the rogue's strays never showed",
        || {
            started = all_pids()
                .filter_map(|pid| {
                    let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).ok()?;
                    let argv0 = cmdline.split(|&b| b == 0).next()?;
                    let argv0 = String::from_utf8_lossy(argv0).to_string();
                    argv0.starts_with(&stem).then_some(())?;
                    Some((argv0, stat(pid)?.1))
                })
                .collect();
            started.len() == 2
        },
    );
    let prefix = started[0].0["formation-stray-".len()..].to_string();
    let started: Vec<Proc> = started.into_iter().map(|(_, p)| p).collect();
    let output = child.wait_with_output().expect("coordinator");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("summary.json")).expect("summary.json"),
    )
    .expect("summary parses");
    assert_eq!(summary["completed"], true);
    assert_eq!(summary["collisions"], 0);
    assert_nothing_left(&prefix, &started);
}

/// Permission bits of `path` (lstat) and its owner.
fn mode_and_owner(path: &Path) -> (u32, u32) {
    let meta = std::fs::symlink_metadata(path).expect("lstat");
    (meta.mode() & 0o7777, meta.uid())
}

#[test]
fn while_a_run_goes_its_files_are_private() {
    let (scenario, path) = paper();
    let mut checked: Option<(String, Vec<PathBuf>)> = None;
    // Three steps are enough: every file of the run exists from the handshake on.
    let outcome = run_scenario_with(
        &scenario,
        &path[..4],
        &options(&[]),
        &mut |b: BetweenSteps<'_>| {
            if checked.is_some() {
                return Ok(());
            }
            let prefix = b.prefix.to_string();
            let root = run_root(&prefix).expect("/dev/shm");
            let meta = std::fs::symlink_metadata(&root).expect("the run folder");
            assert!(meta.is_dir(), "{}", root.display());
            assert_eq!(mode_and_owner(&root), (0o700, effective_uid()));
            let mut files = Vec::new();
            for e in std::fs::read_dir("/dev/shm").expect("/dev/shm").flatten() {
                if e.file_name().to_string_lossy().starts_with(&prefix) {
                    let (mode, owner) = mode_and_owner(&e.path());
                    assert_eq!(mode & 0o077, 0, "{} is {mode:04o}", e.path().display());
                    assert_eq!(owner, effective_uid(), "{}", e.path().display());
                    files.push(e.path());
                }
            }
            checked = Some((prefix, files));
            Ok(())
        },
    )
    .expect("run");
    let (prefix, files) = checked.expect("a step");
    // iceoryx2's management segment lies in /dev/shm itself, outside the folder (it is
    // made 0666, then private by the coordinator): the check above saw it.
    assert!(
        files
            .iter()
            .any(|f| f.to_string_lossy().ends_with(".global_mgmt")),
        "{files:?}"
    );
    assert_eq!(outcome.prefix, prefix);
    assert!(support::leftovers(&prefix).is_empty());
}

/// A process that cannot be started fails that agent alone (here every agent's: the
/// executable cannot be run), never the run: each is recorded `failed-to-start`, saying
/// why, frozen where it starts, and the run completes.
#[test]
fn an_agent_whose_process_cannot_be_started_fails_alone_and_the_run_goes_on() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let not_runnable = dir.path().join("agent");
    std::fs::write(&not_runnable, b"not a program").expect("write");
    std::fs::set_permissions(&not_runnable, std::fs::Permissions::from_mode(0o644)).expect("chmod");
    let (scenario, path) = paper();
    let options = RunOptions {
        agent_bin: Some(not_runnable),
        ..options(&[])
    };
    let outcome = run_scenario(&scenario, &path, &options).expect("the run goes on");
    assert!(outcome.run.completed);
    let failed: Vec<_> = outcome
        .run
        .faults
        .iter()
        .filter(|f| f.kind == shared::run::record::FaultKind::FailedToStart)
        .collect();
    assert_eq!(
        failed.len(),
        scenario.agents.len(),
        "{:?}",
        outcome.run.faults
    );
    for f in failed {
        assert!(f.detail.contains("could not be started"), "{f:?}");
        assert_eq!(f.step, 0);
    }
    assert!(support::leftovers(&outcome.prefix).is_empty());
}
