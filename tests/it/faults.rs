//! Faults with real processes and real signals: agents killed (by the built-in injection
//! and from outside, at random steps), respawned, misbehaving; the coordinator killed
//! or interrupted, at a step of the run it reported. Each test checks the exit code, `summary.json`, the processes left
//! (none) and the shared-memory files left (none).

use crate::support;

use std::os::unix::process::ExitStatusExt;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use support::progress::{self, Watched};
use support::{
    agent_rows, assert_nothing_left, assert_safe, coordinator, faults_of, prefix_stem, run_to_end,
    summary,
};

#[test]
fn a_killed_agent_is_frozen_as_an_obstacle_and_the_run_completes_safely() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let (output, pid) = run_to_end(&["--kill-agent", "2@40"], &out);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["completed"], true);
    assert_safe(&s);
    assert_eq!(faults_of(&s, "killed").len(), 1);
    let dead = faults_of(&s, "dead");
    assert_eq!(dead.len(), 1);
    assert_eq!(dead[0]["agent"].as_u64(), Some(2));
    // Killed during its turn at step 40; if its move got out first, the death is noticed
    // by the liveness check at the start of step 41.
    let noticed = dead[0]["step"].as_u64().expect("step") as usize;
    assert!(noticed == 40 || noticed == 41, "noticed at step {noticed}");
    // Noticed by the liveness check, not by a missed deadline: never `missed` first.
    assert!(dead[0]["detection_ms"].as_f64().expect("detection_ms") >= 0.0);
    assert!(missed_before(&s, 2, noticed).is_empty(), "{s:#}");
    // Frozen where it stood, out of the formation from then on.
    let rows = agent_rows(&out, 2);
    let frozen: Vec<_> = rows.iter().filter(|r| r.0 >= noticed).collect();
    assert!(frozen.len() > 100);
    assert!(
        frozen
            .iter()
            .all(|r| !r.3 && r.1 == frozen[0].1 && r.2 == frozen[0].2)
    );
    assert!(rows.iter().filter(|r| r.0 < noticed).all(|r| r.3));
    assert_nothing_left(pid);
}

/// Rung by doorbells (the default) or by iceoryx2 events, a replacement process takes
/// the killed one's slot and its rings.
#[test]
fn a_respawned_agent_takes_its_slot_again() {
    for wake in ["doorbell", "event"] {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let (output, pid) =
            run_to_end(&["--kill-agent", "1@30", "--respawn", "--wake", wake], &out);
        assert!(
            output.status.success(),
            "{wake}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let s = summary(&out);
        assert_safe(&s);
        assert_eq!(faults_of(&s, "dead").len(), 1, "{wake}");
        assert_eq!(faults_of(&s, "respawned").len(), 1, "{wake}");
        let rows = agent_rows(&out, 1);
        let last = rows.last().expect("rows");
        assert!(last.3, "{wake}: the replacement is alive at the end");
        assert!(
            s["final_mean_deviation_m"].as_f64().expect("final") < 0.05,
            "{wake}: {s:#}"
        );
        assert_nothing_left(pid);
    }
}

#[test]
fn every_misbehaviour_is_refused_and_nobody_collides() {
    for (mode, kind) in [
        ("nan", "rejected"),
        ("teleport", "rejected"),
        ("through-obstacle", "rejected"),
        ("garbage", "rejected"),
        ("silent", "hung"),
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let (output, pid) = run_to_end(&["--misbehave", &format!("3={mode}")], &out);
        assert!(
            output.status.success(),
            "{mode}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let s = summary(&out);
        assert_safe(&s);
        let found = faults_of(&s, kind);
        assert!(!found.is_empty(), "{mode}: no {kind} fault: {s:#}");
        assert!(found.iter().all(|f| f["agent"] == 3), "{mode}");
        if kind == "rejected" {
            // Every turn of agent 3 was refused: it never moved.
            let steps = s["steps"].as_u64().expect("steps") as usize;
            assert_eq!(found.len(), steps, "{mode}");
            let rows = agent_rows(&out, 3);
            assert!(
                rows.iter().all(|r| r.1 == rows[0].1 && r.2 == rows[0].2),
                "{mode}"
            );
        }
        assert_nothing_left(pid);
    }
}

#[test]
fn a_unicycle_that_turns_too_far_is_refused_at_every_turn_and_nobody_collides() {
    // paper-unicycle.toml: at most 3 rad of turning a step, under the half turn the
    // rogue adds to every honest end heading; a holonomic agent (the default scenario)
    // may report no heading at all.
    let unicycles = support::repo_root().join("scenarios/paper-unicycle.toml");
    let unicycles = unicycles.to_str().expect("a UTF-8 path");
    for (scenario, why) in [
        (Some(unicycles), "turning and driving take"),
        (None, "end heading for a holonomic agent"),
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let mut args: Vec<&str> = scenario.into_iter().collect();
        args.extend(["--misbehave", "3=over-turn"]);
        let (output, pid) = run_to_end(&args, &out);
        assert!(
            output.status.success(),
            "{scenario:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let s = summary(&out);
        assert_safe(&s);
        assert_eq!(s["completed"], true, "{scenario:?}");
        let rejected = faults_of(&s, "rejected");
        let steps = s["steps"].as_u64().expect("steps") as usize;
        assert_eq!(rejected.len(), steps, "{scenario:?}: {s:#}");
        for f in &rejected {
            assert_eq!(f["agent"], 3, "{scenario:?}");
            let detail = f["detail"].as_str().expect("detail");
            assert!(detail.contains(why), "{scenario:?}: {detail}");
        }
        // It never moved; the others did.
        let rows = agent_rows(&out, 3);
        assert!(rows.iter().all(|r| r.1 == rows[0].1 && r.2 == rows[0].2));
        let others = agent_rows(&out, 2);
        assert!(others.iter().any(|r| r.1 != others[0].1), "{scenario:?}");
        assert_nothing_left(pid);
    }
}

/// The first two runs of the seeded kill campaign (the system tier runs the other 18):
/// one without and one with `--respawn`.
#[test]
fn random_agents_killed_at_random_steps_first_two_seeds() {
    kill_campaign(0..2);
}

/// The paper example with a random agent killed at a random step (by the built-in
/// injection), once per seed, half of them with `--respawn`: the death is noticed during
/// the turn or at the next step's liveness check, never as a missed deadline, and the run
/// completes safely with nothing left.
pub(crate) fn kill_campaign(seeds: std::ops::Range<u64>) {
    let mut detections = Vec::new();
    for seed in seeds {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let agent = rng.random_range(0..6usize);
        let step = rng.random_range(1..170usize);
        let respawn = seed % 2 == 1;
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let kill_arg = format!("{agent}@{step}");
        // A generous turn deadline: the death is noticed by the process check, and a
        // loaded machine must not get an honest agent killed as slow.
        let mut args = vec!["--kill-agent", &kill_arg, "--turn-deadline-ms", "10000"];
        if respawn {
            args.push("--respawn");
        }
        let (output, pid) = run_to_end(&args, &out);
        let context = format!("seed {seed}: agent {agent} at step {step}, respawn {respawn}");
        assert!(
            output.status.success(),
            "{context}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let s = summary(&out);
        assert_safe(&s);
        assert_eq!(s["completed"], true, "{context}");
        let dead = faults_of(&s, "dead");
        assert_eq!(dead.len(), 1, "{context}: {s:#}");
        assert_eq!(dead[0]["agent"].as_u64(), Some(agent as u64), "{context}");
        // The kill lands during the turn; if the agent still got its move out first, the
        // death is noticed by the liveness check at the start of the next step.
        let noticed = dead[0]["step"].as_u64().expect("step") as usize;
        assert!(
            noticed == step || noticed == step + 1,
            "{context}: noticed at {noticed}"
        );
        detections.push(dead[0]["detection_ms"].as_f64().expect("detection_ms"));
        // Noticed by the liveness check, not by a missed deadline (however long the
        // check took on a loaded machine: its time is reported, not asserted).
        assert!(
            missed_before(&s, agent, noticed).is_empty(),
            "{context}: {s:#}"
        );
        assert_eq!(
            faults_of(&s, "respawned").len(),
            usize::from(respawn),
            "{context}"
        );
        assert_nothing_left(pid);
    }
    detections.sort_by(f64::total_cmp);
    eprintln!(
        "detection over {} kills: p50 {:.2} ms, max {:.2} ms",
        detections.len(),
        detections[detections.len() / 2],
        detections[detections.len() - 1]
    );
    assert!(detections.iter().all(|&d| d >= 0.0), "{detections:?}");
}

/// A scenario run long enough for a kill or a signal timed by its progress
/// ([`progress::latest_hold_step`]) to land mid-run, and its number of agents.
#[derive(Clone, Copy)]
pub(crate) enum LongRun {
    /// The paper example as shipped: 6 agents.
    Paper,
    /// The 64-agent block of `scenarios/large.toml`, its `step_m` halved to give the
    /// hold room (the system tier's).
    #[cfg(feature = "system")]
    Large,
}

impl LongRun {
    /// The number of agents.
    pub(crate) fn agents(self) -> usize {
        match self {
            LongRun::Paper => 6,
            #[cfg(feature = "system")]
            LongRun::Large => 64,
        }
    }

    /// The scenario file, written into `dir` when it is not shipped as it is.
    #[cfg_attr(not(feature = "system"), allow(unused_variables))]
    pub(crate) fn file_in(self, dir: &std::path::Path) -> PathBuf {
        match self {
            LongRun::Paper => support::repo_root().join("scenarios/paper.toml"),
            #[cfg(feature = "system")]
            LongRun::Large => {
                let text =
                    std::fs::read_to_string(support::repo_root().join("scenarios/large.toml"))
                        .expect("large.toml");
                assert!(text.contains("step_m = 0.5\n"), "large.toml's step changed");
                let path = dir.join("large-long.toml");
                std::fs::write(&path, text.replace("step_m = 0.5\n", "step_m = 0.25\n"))
                    .expect("write");
                path
            }
        }
    }
}

/// An agent of the paper example killed with SIGKILL from outside at a random step (the
/// system tier does it three times on 64 agents).
#[test]
fn an_agent_killed_from_outside_at_a_random_moment_is_survived() {
    agents_killed_from_outside(LongRun::Paper, 100..101);
}

/// For each seed, a run of `long` in which a random agent process is killed with SIGKILL
/// from outside at a random step (timed by the run's progress): the run completes
/// safely, one death recorded, nothing left.
pub(crate) fn agents_killed_from_outside(long: LongRun, seeds: std::ops::Range<u64>) {
    let planned = tempfile::tempdir().expect("tempdir");
    let latest =
        progress::latest_hold_step(progress::centre_path_steps(&long.file_in(planned.path())));
    for seed in seeds {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let scenario = long.file_in(dir.path());
        let step = rng.random_range(1..=latest);
        // A generous turn deadline: the death is noticed by the process check, and a
        // loaded machine must not get an honest agent killed as slow (seen with three
        // test suites running at once at the default 250 ms).
        let args = [
            scenario.to_str().expect("utf-8 path"),
            "--turn-deadline-ms",
            "10000",
        ];
        let mut run = Watched::spawn(coordinator(&args, &out), &[step]);
        let pid = run.id();
        support::wait_for_agents(pid, long.agents());
        let held = run.hold();
        let victims = support::processes_mentioning(&format!("--prefix {}", prefix_stem(pid)));
        let victim = victims[rng.random_range(0..victims.len())];
        kill(Pid::from_raw(victim as i32), Signal::SIGKILL).expect("kill agent");
        drop(held);
        let output = run.wait_with_output();
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        let s = summary(&out);
        assert_safe(&s);
        assert_eq!(
            faults_of(&s, "dead").len(),
            1,
            "seed {seed}, step {step}: {s:#}"
        );
        assert_nothing_left(pid);
    }
}

/// A run of `long` (written into `dir`, its outputs into `out`) watched to be held
/// mid-run, halfway to the latest step at which whatever the test does surely lands
/// before the run's end; returned with its process id once its agents are up.
fn run_held_mid_way(long: LongRun, dir: &std::path::Path, out: &std::path::Path) -> (Watched, u32) {
    let scenario = long.file_in(dir);
    let step = progress::latest_hold_step(progress::centre_path_steps(&scenario)) / 2 + 1;
    let run = Watched::spawn(
        coordinator(&[scenario.to_str().expect("utf-8 path")], out),
        &[step],
    );
    let pid = run.id();
    support::wait_for_agents(pid, long.agents());
    (run, pid)
}

#[test]
fn agents_leave_when_the_coordinator_is_killed_and_the_next_run_cleans_up() {
    agents_leave_when_the_coordinator_is_killed(LongRun::Paper);
}

/// A run of `long` whose coordinator is killed with SIGKILL mid-run: its agents go with
/// it, it leaves its log and no summary, and the next run cleans up its files.
pub(crate) fn agents_leave_when_the_coordinator_is_killed(long: LongRun) {
    let dir = tempfile::tempdir().expect("tempdir");
    let (mut run, pid) = run_held_mid_way(long, dir.path(), &dir.path().join("a"));
    let held = run.hold();
    kill(Pid::from_raw(pid as i32), Signal::SIGKILL).expect("kill coordinator");
    let killed = Instant::now();
    drop(held);
    assert_eq!(run.wait().signal(), Some(Signal::SIGKILL as i32));
    let needle = format!("--prefix {}", prefix_stem(pid));
    // The kernel kills them with the coordinator; how soon they are gone is printed, not
    // asserted (a loaded machine may take longer).
    support::wait_for_no_process_mentioning(&needle, support::EXIT_ROOM);
    eprintln!(
        "agents gone {:.0} ms after the coordinator was killed",
        killed.elapsed().as_secs_f64() * 1e3
    );
    // Every agent gone, the coordinator's stderr is closed.
    run.wait_with_output();
    // A killed run leaves its log, and nothing else half-written.
    let killed_dir = dir.path().join("a");
    assert!(
        killed_dir.join("run.mcap").is_file(),
        "no log of the killed run"
    );
    assert!(
        !killed_dir.join("summary.json").exists(),
        "a killed run wrote a summary"
    );
    // The dead coordinator's files are still there; the next run cleans them.
    assert!(!support::leftovers(&prefix_stem(pid)).is_empty());
    let (output, next) = run_to_end(&[], &dir.path().join("b"));
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_nothing_left(pid);
    assert_nothing_left(next);
}

/// An agent is started with `posix_spawn`, so it asks to die with the coordinator itself;
/// one whose named coordinator is not its parent (that coordinator died before the agent
/// could ask) leaves at once, saying why, before it opens anything.
#[test]
fn an_agent_whose_coordinator_is_already_gone_leaves_at_once() {
    let out = std::process::Command::new(support::agent_bin())
        .args(["--prefix", "fc1x0_", "--agent", "0"])
        // Process 1 is never this test's own process, the agent's parent.
        .env(wire::PARENT_ENV, "1")
        .output()
        .expect("the agent runs");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the coordinator (process 1) is gone"),
        "{stderr}"
    );
}

/// On the paper example (the system tier does it on 64 agents).
#[test]
fn sigterm_and_ctrl_c_stop_the_run_cleanly_with_complete_outputs() {
    sigterm_and_ctrl_c_stop_cleanly(LongRun::Paper);
}

/// A run of `long` sent SIGTERM, then one sent SIGINT, to its whole process group
/// mid-run: each stops with exit code 1 and complete outputs of the steps done.
pub(crate) fn sigterm_and_ctrl_c_stop_cleanly(long: LongRun) {
    for signal in [Signal::SIGTERM, Signal::SIGINT] {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let scenario = long.file_in(dir.path());
        let steps = progress::centre_path_steps(&scenario);
        // Mid-run: halfway to the latest step a signal surely lands before the run's end.
        let step = progress::latest_hold_step(steps) / 2 + 1;
        let mut command = coordinator(&[scenario.to_str().expect("utf-8 path")], &out);
        // Like a terminal: the coordinator leads its own process group, and the signal
        // goes to the whole group (agents run in groups of their own).
        std::os::unix::process::CommandExt::process_group(&mut command, 0);
        let mut run = Watched::spawn(command, &[step]);
        let pid = run.id();
        support::wait_for_agents(pid, long.agents());
        let held = run.hold();
        kill(Pid::from_raw(-(pid as i32)), signal).expect("signal the group");
        drop(held);
        let output = run.wait_with_output();
        assert_eq!(
            output.status.code(),
            Some(1),
            "{signal}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let s = summary(&out);
        assert_eq!(s["completed"], false, "{signal}");
        let last = s["last_step"].as_u64().expect("last_step") as usize;
        // Stopped partway: after the first step, before the centre path's last.
        assert!(
            last > 0 && last < steps,
            "{signal}: last step {last} of {steps}"
        );
        assert_eq!(s["steps"].as_u64(), Some(last as u64));
        let mut rows = 0;
        for record in csv::Reader::from_path(out.join("trajectory.csv"))
            .expect("trajectory.csv")
            .records()
        {
            assert_eq!(record.expect("a whole row").len(), 12, "{signal}");
            rows += 1;
        }
        assert_eq!(
            rows,
            (last + 1) * long.agents(),
            "{signal}: complete steps only"
        );
        assert_safe(&s);
        assert_nothing_left(pid);
    }
}

/// A coordinator that cannot get to stop (held at a step of its run, its stderr a full
/// pipe, so every log line blocks it) ends at the second SIGINT at once: exit code 130,
/// no process of the run left, no file of it in shared memory.
#[test]
fn a_second_ctrl_c_ends_a_stuck_coordinator_at_once_and_leaves_nothing() {
    a_second_ctrl_c_ends_a_stuck_coordinator(LongRun::Paper);
}

/// The test above on a run of `long`.
pub(crate) fn a_second_ctrl_c_ends_a_stuck_coordinator(long: LongRun) {
    let dir = tempfile::tempdir().expect("tempdir");
    let (mut run, pid) = run_held_mid_way(long, dir.path(), &dir.path().join("out"));
    // Held: the coordinator runs on until its stderr pipe is full, then blocks there; it
    // cannot stop cleanly any more (nor print its last line) before the hold ends.
    let held = run.hold();
    support::wait_until(
        Duration::from_secs(60),
        "the held coordinator never blocked writing to its stderr",
        || blocked_writing_to_stderr(pid),
    );
    // Two signals sent before the first is taken are one: the second goes once the
    // kernel has handed the first to the coordinator (no SIGINT pending any more).
    kill(Pid::from_raw(pid as i32), Signal::SIGINT).expect("interrupt the coordinator");
    support::wait_until(
        Duration::from_secs(60),
        "the first SIGINT still pending after 60 s",
        || !sigint_pending(pid),
    );
    kill(Pid::from_raw(pid as i32), Signal::SIGINT).expect("interrupt the coordinator again");
    let status = run.wait();
    drop(held);
    assert_eq!(status.code(), Some(130), "{status:?}");
    let output = run.wait_with_output();
    assert!(
        !dir.path().join("out").join("summary.json").exists(),
        "a forced exit wrote a summary"
    );
    drop(output);
    assert_nothing_left(pid);
}

/// Whether a thread of process `pid` is in write(2) on its stderr (the system call each
/// is in, from /proc/PID/task/TID/syscall: number 1, first argument 2). Held by the
/// test's reader, that means the pipe is full: the process cannot end by itself until
/// the reader goes on, not even with its last line.
fn blocked_writing_to_stderr(pid: u32) -> bool {
    let Ok(threads) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return false;
    };
    threads.flatten().any(|t| {
        std::fs::read_to_string(t.path().join("syscall"))
            .is_ok_and(|call| call.split_whitespace().take(2).eq(["1", "0x2"]))
    })
}

/// Whether a SIGINT sent to process `pid` is pending (not yet taken by any of its
/// threads), from the `ShdPnd` mask of /proc/PID/status; false once the process is gone.
fn sigint_pending(pid: u32) -> bool {
    let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else {
        return false;
    };
    status
        .lines()
        .find_map(|l| l.strip_prefix("ShdPnd:"))
        .and_then(|mask| u64::from_str_radix(mask.trim(), 16).ok())
        .is_some_and(|mask| mask & (1 << (Signal::SIGINT as u64 - 1)) != 0)
}

#[test]
fn two_coordinators_at_once_do_not_interfere() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A generous deadline: the comparison is about isolation, not about liveness.
    let args = ["--turn-deadline-ms", "10000"];
    let a = coordinator(&args, &dir.path().join("a"))
        .spawn()
        .expect("a");
    let b = coordinator(&args, &dir.path().join("b"))
        .spawn()
        .expect("b");
    let (pa, pb) = (a.id(), b.id());
    let (oa, ob) = (
        a.wait_with_output().expect("a"),
        b.wait_with_output().expect("b"),
    );
    assert!(oa.status.success() && ob.status.success());
    let ta = std::fs::read(dir.path().join("a/trajectory.csv")).expect("a");
    let tb = std::fs::read(dir.path().join("b/trajectory.csv")).expect("b");
    assert_eq!(
        ta, tb,
        "the same scenario gives the same trajectory, byte for byte"
    );
    assert_nothing_left(pa);
    assert_nothing_left(pb);
}

/// The `missed` faults of `agent` up to `step`: none when a death is noticed by the
/// liveness check rather than by a missed deadline.
fn missed_before(s: &serde_json::Value, agent: usize, step: usize) -> Vec<serde_json::Value> {
    faults_of(s, "missed")
        .into_iter()
        .filter(|f| {
            f["agent"].as_u64() == Some(agent as u64)
                && f["step"].as_u64().is_some_and(|k| k as usize <= step)
        })
        .collect()
}
