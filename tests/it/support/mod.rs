//! Helpers shared by the integration tests: where the binaries are, what a run left
//! behind, and the reference simulation to compare with.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

pub mod json_schema;
#[cfg(feature = "zenoh")]
pub mod network;
pub mod progress;
pub mod system;

/// `target/<profile>/` of this test build.
pub fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    // target/<profile>/deps/<test>-<hash>
    exe.parent()
        .and_then(Path::parent)
        .expect("the test executable lives in target/<profile>/deps")
        .to_path_buf()
}

fn binary(name: &str) -> PathBuf {
    let path = target_dir().join(name);
    assert!(
        path.is_file(),
        "{} is missing: run the tests with `cargo test --workspace` so the binaries are built",
        path.display()
    );
    path
}

/// The `agent` executable.
pub fn agent_bin() -> PathBuf {
    binary("agent")
}

/// The `coordinator` executable.
pub fn coordinator_bin() -> PathBuf {
    binary("coordinator")
}

/// The repository's root.
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The large formation under a top speed (`scenarios/large-top-speed.toml`, 64 agents)
/// with the `orca` controller in its own model: every agent moves at once.
pub fn orca_crowd() -> shared::world::scenario::Scenario {
    let file = repo_root().join("scenarios/large-top-speed.toml");
    let mut scenario = shared::world::scenario::Scenario::load(&file)
        .expect("large-top-speed.toml")
        .with_controller(shared::control::vocabulary::ControllerKind::Orca);
    scenario.turns = shared::control::vocabulary::TurnMode::Simultaneous;
    scenario
}

/// Every shipped scenario file.
pub fn shipped_scenarios() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo_root().join("scenarios"))
        .expect("scenarios/")
        .map(|e| e.expect("scenario entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
}

/// Files of the iceoryx2 run with this prefix still present in /dev/shm or below the
/// iceoryx2 root.
pub fn leftovers(prefix: &str) -> Vec<PathBuf> {
    fn walk(dir: &Path, prefix: &str, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let path = e.path();
            if e.file_name().to_string_lossy().starts_with(prefix) {
                out.push(path.clone());
            }
            if path.is_dir() {
                walk(&path, prefix, out);
            }
        }
    }
    let mut out = Vec::new();
    walk(Path::new("/dev/shm"), prefix, &mut out);
    walk(Path::new("/tmp/iceoryx2"), prefix, &mut out);
    out
}

/// Every process id in /proc.
fn all_pids() -> Vec<u32> {
    std::fs::read_dir("/proc")
        .map(|entries| {
            entries
                .flatten()
                .filter_map(|e| e.file_name().to_string_lossy().parse().ok())
                .collect()
        })
        .unwrap_or_default()
}

/// A process's state letter and parent, from `/proc/PID/stat` (`pid (comm) state ppid ...`;
/// the command name may hold spaces and parentheses, so the fields are read after the last
/// `)`).
fn state_and_parent(pid: u32) -> Option<(char, u32)> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let mut fields = stat.rsplit(')').next()?.split_whitespace();
    let state = fields.next()?.chars().next()?;
    let ppid = fields.next()?.parse().ok()?;
    Some((state, ppid))
}

/// Processes whose parent is `parent` (from /proc).
pub fn children_of(parent: u32) -> Vec<u32> {
    all_pids()
        .into_iter()
        .filter(|&pid| state_and_parent(pid).is_some_and(|(_, ppid)| ppid == parent))
        .collect()
}

/// Running processes (not zombies) whose command line mentions `needle` (e.g. a run
/// prefix).
pub fn processes_mentioning(needle: &str) -> Vec<u32> {
    all_pids()
        .into_iter()
        .filter(|&pid| {
            let Ok(cmdline) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
                return false;
            };
            let cmdline = String::from_utf8_lossy(&cmdline).replace('\0', " ");
            let zombie = state_and_parent(pid).is_some_and(|(state, _)| state == 'Z');
            cmdline.contains(needle) && !zombie
        })
        .collect()
}

// ---- `coordinator run` as a user runs it: a real process, its files, what it left

/// The run prefixes a coordinator process uses start with this.
pub fn prefix_stem(coordinator_pid: u32) -> String {
    wire::RunPrefix::head(coordinator_pid)
}

/// The flag that runs the agents as this user, unsandboxed, even as root (where `run`
/// sandboxes them by default). Every `coordinator run` of a test that does not test the
/// sandbox passes it.
pub const TRUSTED: &str = "--trusted-agents";

/// `coordinator run ARGS --out OUT --quiet --no-plots`, its agents from this build, its
/// output piped. The agents are trusted (`--trusted-agents`) unless `args` asks for
/// `--sandbox`: as root a run sandboxes its agents by default, at about twice the turn's
/// cost, and only the sandbox's own tests test it.
pub fn coordinator(args: &[&str], out: &Path) -> Command {
    let mut c = Command::new(coordinator_bin());
    c.arg("run").args(args);
    if !args.contains(&"--sandbox") {
        c.arg(TRUSTED);
    }
    c.arg("--out")
        .arg(out)
        .args(["--quiet", "--no-plots"])
        .env("FORMATION_AGENT_BIN", agent_bin())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

pub fn summary(out: &Path) -> Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json parses")
}

/// Polls `done` every few milliseconds until it holds; panics with `what` if it still
/// does not after `timeout`. A test waits for a state this way, never for a fixed time.
pub fn wait_until(timeout: Duration, what: &str, done: impl FnMut() -> bool) {
    wait_until_or_say(timeout, done, || what.to_string());
}

/// [`wait_until`], the failure's message made by `what` when it fails (it may say what
/// the state was then).
pub fn wait_until_or_say(
    timeout: Duration,
    mut done: impl FnMut() -> bool,
    what: impl FnOnce() -> String,
) {
    let deadline = Instant::now() + timeout;
    while !done() {
        if Instant::now() >= deadline {
            panic!("{} (after {timeout:?})", what());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// How long processes that must go (told to quit, or killed with their parent by the
/// kernel) may take to be gone on a loaded machine. A test waits for the state, so only a
/// failure waits this long.
pub const EXIT_ROOM: Duration = Duration::from_secs(10);

/// Waits until no process's command line mentions `needle` (at most `timeout`); on
/// failure, names what was left (state, parent and command line of each).
pub fn wait_for_no_process_mentioning(needle: &str, timeout: Duration) {
    wait_until_or_say(
        timeout,
        || processes_mentioning(needle).is_empty(),
        || {
            let left: Vec<String> = processes_mentioning(needle)
                .into_iter()
                .map(describe)
                .collect();
            format!("processes of {needle} left running: {}", left.join("; "))
        },
    );
}

/// `pid (state S, parent P): command line`, for a failure message.
fn describe(pid: u32) -> String {
    let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
    let cmdline = String::from_utf8_lossy(&cmdline).replace('\0', " ");
    match state_and_parent(pid) {
        Some((state, parent)) => format!("{pid} (state {state}, parent {parent}): {cmdline}"),
        None => format!("{pid}: {cmdline}"),
    }
}

/// Waits until at least `count` agent processes of coordinator `pid` run; their pids.
pub fn wait_for_agents(pid: u32, count: usize) -> Vec<u32> {
    let needle = format!("--prefix {}", prefix_stem(pid));
    let mut found = Vec::new();
    wait_until(Duration::from_secs(30), "agents did not start", || {
        found = processes_mentioning(&needle);
        found.len() >= count
    });
    found
}

/// Nothing of the coordinator process `pid` is left: no agent process, no iceoryx2 file.
pub fn assert_nothing_left(pid: u32) {
    let stem = prefix_stem(pid);
    wait_for_no_process_mentioning(&format!("--prefix {stem}"), EXIT_ROOM);
    let left = leftovers(&stem);
    assert!(left.is_empty(), "iceoryx2 files left: {left:?}");
}

/// How long [`run_to_end`] lets a run go before it kills it as hung: far beyond what any
/// test run takes on a loaded machine, so that a hang fails its test instead of the
/// whole suite.
pub const HUNG_RUN: Duration = Duration::from_secs(600);

/// Run the coordinator with `args` (outputs into `out`) to its end; a run still going
/// after [`HUNG_RUN`] is killed and the test fails.
pub fn run_to_end(args: &[&str], out: &Path) -> (Output, u32) {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Arc, mpsc};
    let child = coordinator(args, out).spawn().expect("start coordinator");
    let pid = child.id();
    let (finished, ended) = mpsc::channel::<()>();
    let killed = Arc::new(AtomicBool::new(false));
    let watchdog = {
        let killed = Arc::clone(&killed);
        std::thread::spawn(move || {
            if ended.recv_timeout(HUNG_RUN).is_err() {
                killed.store(true, Ordering::SeqCst);
                let _ = nix::sys::signal::kill(
                    nix::unistd::Pid::from_raw(pid as i32),
                    nix::sys::signal::Signal::SIGKILL,
                );
            }
        })
    };
    let output = child.wait_with_output().expect("coordinator output");
    let _ = finished.send(());
    let _ = watchdog.join();
    assert!(
        !killed.load(Ordering::SeqCst),
        "{args:?}: the run was still going after {HUNG_RUN:?} and was killed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    (output, pid)
}

pub fn faults_of(s: &Value, kind: &str) -> Vec<Value> {
    s["faults"]
        .as_array()
        .expect("faults")
        .iter()
        .filter(|f| f["kind"] == kind)
        .cloned()
        .collect()
}

/// Every fault in the summary `s` is recorded against `agent`: an attacker's faults cost
/// nobody else.
pub fn assert_faults_only_against(s: &Value, agent: u64) {
    assert!(
        s["faults"]
            .as_array()
            .expect("faults")
            .iter()
            .all(|f| f["agent"] == agent),
        "a fault against another agent than {agent}: {s:#}"
    );
}

pub fn assert_safe(s: &Value) {
    assert_eq!(s["collisions"], 0, "{s:#}");
    assert!(
        s["min_clearance_m"].as_f64().expect("min_clearance_m") >= -1e-9,
        "{s:#}"
    );
}

/// Rows of trajectory.csv for one agent: (step, x, y, alive).
pub fn agent_rows(out: &Path, agent: usize) -> Vec<(usize, f64, f64, bool)> {
    let mut reader = csv::Reader::from_path(out.join("trajectory.csv")).expect("trajectory.csv");
    reader
        .records()
        .map(|r| r.expect("row"))
        .filter(|r| r[1].parse::<usize>().ok() == Some(agent))
        .map(|r| {
            (
                r[0].parse().expect("step"),
                r[2].parse().expect("x"),
                r[3].parse().expect("y"),
                &r[11] == "1",
            )
        })
        .collect()
}

/// How long [`run_bounded`] lets a process run: a refusal takes well under a second, so
/// only a hang (on a FIFO, a device) comes near it.
pub const BOUNDED_RUN_LIMIT: Duration = Duration::from_secs(60);

/// `cmd` run to completion with stdin closed and its output captured, or an error if it
/// could not start or outlived [`BOUNDED_RUN_LIMIT`] (then it is killed).
pub fn run_bounded(mut cmd: Command) -> Result<Output, String> {
    let child = cmd
        .env_remove("RUST_LOG")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start {cmd:?}: {e}"))?;
    let pid = child.id();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    match rx.recv_timeout(BOUNDED_RUN_LIMIT) {
        Ok(Ok(output)) => Ok(output),
        Ok(Err(e)) => Err(format!("waiting for {cmd:?} failed: {e}")),
        Err(_) => {
            // The child is not reaped until the waiting thread returns, so the id is still
            // this child's.
            let pid = nix::unistd::Pid::from_raw(i32::try_from(pid).expect("pid fits i32"));
            let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGKILL);
            Err(format!(
                "{cmd:?} did not finish within {BOUNDED_RUN_LIMIT:?} (a hang on bad input?)"
            ))
        }
    }
}
