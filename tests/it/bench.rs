//! `coordinator bench` for real, small: real agent processes, the iceoryx2 floor and the
//! Unix socket ping-pong. The figures must be consistent and complete, and nothing may
//! be left behind. Speed is never asserted here (the machine is shared and noisy).

use crate::support;

use std::process::Command;

use serde_json::Value;

const DISTRIBUTIONS: [&str; 7] = [
    "turn_us",
    "compute_us",
    "ipc_overhead_us",
    "echo_us",
    "floor_us",
    "uds_us",
    "agent_rss_kib",
];

/// `coordinator bench` with `args`, on the scenario `FLAG FILE` if one is given, with
/// `--json --out OUT` and the agents built for the tests: the JSON report on stdout (the
/// bench must succeed).
fn bench_report(
    args: &[&str],
    scenario: Option<(&str, &std::path::Path)>,
    out: &std::path::Path,
) -> Value {
    let mut command = Command::new(support::coordinator_bin());
    command.arg("bench");
    if let Some((flag, file)) = scenario {
        command.arg(flag).arg(file);
    }
    let output = command
        .args(args)
        .args(["--json", "--out"])
        .arg(out)
        .arg("--agent-bin")
        .arg(support::agent_bin())
        .output()
        .expect("running coordinator bench");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "bench failed: {stderr}");
    serde_json::from_slice(&output.stdout)
        .unwrap_or_else(|e| panic!("stdout is not JSON ({e}): {stderr}"))
}

/// `coordinator bench` with `args`, which it must refuse before running: exit 2, nothing
/// on stdout; its stderr.
fn bench_refusal(args: &[&std::ffi::OsStr]) -> String {
    let output = Command::new(support::coordinator_bin())
        .arg("bench")
        .args(args)
        .output()
        .expect("running coordinator bench");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(output.stdout.is_empty(), "{args:?}");
    stderr
}

pub(crate) fn number(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number in {v}"))
}

/// p50 <= p90 <= p99 <= p999 <= max, all finite and non-negative, count > 0.
fn check_distribution(run: &Value, key: &str) -> [f64; 5] {
    let d = &run[key];
    let v = ["p50", "p90", "p99", "p999", "max"].map(|k| number(d, k));
    assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0), "{key}: {d}");
    assert!(v.windows(2).all(|w| w[0] <= w[1]), "{key} not ordered: {d}");
    assert!(d["count"].as_u64().is_some_and(|c| c > 0), "{key}: {d}");
    v
}

#[test]
fn bench_reports_consistent_figures_and_leaves_nothing_behind() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let out_file = dir.path().join("bench.json");
    let report = bench_report(&["--agents", "3", "--steps", "20"], None, &out_file);
    // --out holds the same report; the histogram is beside it.
    let saved: Value =
        serde_json::from_slice(&std::fs::read(&out_file).expect("--out file")).expect("JSON");
    assert_eq!(saved, report);
    let svg = std::fs::read_to_string(out_file.with_extension("svg")).expect("histogram");
    assert!(svg.contains("<svg"), "not an SVG");

    let runs = report["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 1);
    let run = &runs[0];
    assert_eq!(run["agents"], 3);
    for key in DISTRIBUTIONS {
        check_distribution(run, key);
    }
    // 20 steps of 3 turns, the first step dropped as a warm-up.
    assert_eq!(run["turn_us"]["count"], 57);
    assert_eq!(run["ipc_overhead_us"]["count"], 57);
    assert_eq!(run["floor_us"]["count"], 2000);
    // The floor is rung as the run's turns are: by the doorbells, the default.
    assert_eq!(run["floor_rung_by"], "doorbell");
    assert_eq!(run["uds_us"]["count"], 2000);
    // Spread between the 20 steps of the same run.
    assert_eq!(run["floor_blocks"], 20);
    assert_eq!(run["agent_rss_kib"]["count"], 3);
    // Every agent stamps its moves, so every measured turn is split in three parts.
    for key in ["to_agent_us", "agent_io_us", "to_coordinator_us"] {
        let part = check_distribution(&run["overhead_split"], key);
        assert_eq!(run["overhead_split"][key]["count"], 57, "{key}");
        let overhead = check_distribution(run, "ipc_overhead_us");
        assert!(
            part[0] <= overhead[4],
            "{key} p50 above the overhead's max: {run}"
        );
    }
    // Echoes: 3 agents in turn, ceil(2000 / (20 blocks * 3 agents)) = 34 rounds per
    // block, all answered.
    assert_eq!(run["echo_us"]["count"], 20 * 34 * 3);
    let echo = check_distribution(run, "echo_us");
    for key in ["to_agent_us", "to_coordinator_us"] {
        let part = check_distribution(&run["echo_split"], key);
        assert!(
            part[4] <= echo[4],
            "echo part {key} above the echo's max: {run}"
        );
    }
    // The overhead is the turn minus its compute, turn by turn: never above the turn.
    let turn = check_distribution(run, "turn_us");
    let overhead = check_distribution(run, "ipc_overhead_us");
    assert!(overhead[0] <= turn[0], "overhead p50 above turn p50: {run}");
    assert!(overhead[4] <= turn[4], "overhead max above turn max: {run}");
    for key in [
        "overhead_vs_floor_p50",
        "overhead_vs_floor_p99",
        "overhead_vs_uds_p50",
        "overhead_vs_echo_p50",
        "overhead_vs_echo_p99",
    ] {
        let r = number(run, key);
        assert!(r.is_finite() && r > 0.0, "{key} = {r}");
    }
    let floor = check_distribution(run, "floor_us");
    let ratio = number(run, "overhead_vs_floor_p50");
    assert!((ratio - overhead[0] / floor[0]).abs() <= 1e-9 * ratio.max(1.0));
    let idle = number(run, "agent_idle_cpu_s");
    assert!(idle.is_finite() && idle >= 0.0, "idle CPU {idle}");
    assert_eq!(run["agent_idle"]["processes"], 3);
    // Blocked, not polling: any timer of a second or less would wake each of the 3
    // agents at least once while they are held idle for a second.
    assert!(
        run["agent_idle"]["wakeups"].as_u64().is_some_and(|w| w < 3),
        "idle agents woke up: {}",
        run["agent_idle"]
    );
    assert!(number(&run["agent_idle"], "held_s") >= 0.9);
    assert!(number(run, "startup_s") > 0.0);
    assert_eq!(run["faults"], 0);
    for key in ["overhead_p50_within_1_5x_floor", "idle_cpu_zero"] {
        assert!(run["targets"][key].is_boolean(), "targets.{key}");
    }

    // Nothing left behind: no process and no iceoryx2 file of either prefix, no socket.
    for key in ["prefix", "floor_prefix"] {
        let prefix = run[key].as_str().expect("prefix");
        assert!(!prefix.is_empty());
        assert!(
            support::leftovers(prefix).is_empty(),
            "iceoryx2 files of {prefix} left: {:?}",
            support::leftovers(prefix)
        );
        assert!(
            support::processes_mentioning(prefix).is_empty(),
            "processes of {prefix} left running"
        );
        let socket = std::env::temp_dir().join(format!("{prefix}pingpong.sock"));
        assert!(!socket.exists(), "{} left", socket.display());
    }
}

#[test]
fn bench_refuses_bad_arguments_with_exit_code_2() {
    for args in [
        ["--agents", "0"],
        ["--agents", "1025"],
        ["--steps", "1"],
        ["--round-trips", "0"],
    ] {
        bench_refusal(&args.map(std::ffi::OsStr::new));
    }
}

#[test]
fn bench_compares_sequential_and_parallel_turns_on_one_scenario() {
    let report = turns_report(&[]);
    assert!(report["turns"]["sandboxed"].is_null(), "{report}");
}

/// `coordinator bench --turns-scenario paper-top-speed.toml` over 6 steps and 2 rounds
/// with `extra` flags; checks the sequential and parallel figures and returns the report.
pub(crate) fn turns_report(extra: &[&str]) -> Value {
    let dir = tempfile::tempdir().expect("temporary directory");
    let out_file = dir.path().join("turns.json");
    let scenario = support::repo_root()
        .join("scenarios")
        .join("paper-top-speed.toml");
    let args = [&["--turns-steps", "6", "--turns-rounds", "2"], extra].concat();
    let report = bench_report(&args, Some(("--turns-scenario", &scenario)), &out_file);
    // Only the turns were asked for: no latency runs, no histogram.
    assert_eq!(report["runs"].as_array().expect("runs").len(), 0);
    assert!(report["histogram_svg"].is_null());
    assert!(!out_file.with_extension("svg").exists());
    let t = &report["turns"];
    assert_eq!(t["scenario"], "paper-top-speed");
    assert_eq!(t["agents"], 6);
    assert_eq!(t["steps"], 6);
    assert_eq!(t["rounds"], 2);
    assert_eq!(
        t["order"],
        serde_json::json!(["sequential", "parallel", "parallel", "sequential"])
    );
    assert_eq!(t["max_step_m"], serde_json::json!([0.5, 0.5]));
    for mode in ["sequential", "parallel"] {
        let m = &t[mode];
        assert_eq!(m["mode"], mode);
        assert_eq!(m["steps_per_s_runs"].as_array().expect("runs").len(), 2);
        assert!(number(m, "steps_per_s") > 0.0, "{m}");
        check_distribution(m, "turn_us");
        check_distribution(m, "compute_us");
        assert_eq!(m["collisions"], 0, "{m}");
        assert_eq!(m["faults"], 0, "{m}");
        assert_eq!(m["completed"], true, "{m}");
        assert!(number(m, "max_move_m") <= 0.5 + 1e-6, "{m}");
    }
    assert_eq!(number(&t["sequential"], "mean_groups_per_step"), 6.0);
    let groups = number(&t["parallel"], "mean_groups_per_step");
    assert!((1.0..6.0).contains(&groups), "{groups}");
    let ratio = number(t, "parallel_vs_sequential_steps_per_s");
    let expected = number(&t["parallel"], "steps_per_s") / number(&t["sequential"], "steps_per_s");
    assert!(
        (ratio - expected).abs() <= 1e-9 * expected,
        "{ratio} vs {expected}"
    );
    report
}

#[test]
fn bench_refuses_a_turns_scenario_without_a_top_speed_before_running() {
    let paper = support::repo_root().join("scenarios").join("paper.toml");
    for extra in [&["--turns-rounds", "1"][..], &["--turns-rounds", "0"][..]] {
        let mut args = vec![std::ffi::OsStr::new("--turns-scenario"), paper.as_os_str()];
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        let stderr = bench_refusal(&args);
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

#[test]
fn bench_times_the_step_loop_against_simulate_blocking_and_spinning() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let out_file = dir.path().join("loops.json");
    let scenario = support::repo_root().join("tests/data/swarm16-parallel.toml");
    // Rung by iceoryx2's events, the floor too (the first test has both by doorbells).
    let report = bench_report(
        &["--loop-rounds", "1", "--wake", "event"],
        Some(("--loop-scenario", &scenario)),
        &out_file,
    );
    assert_eq!(report["runs"].as_array().expect("runs").len(), 0);
    let l = &report["loops"];
    assert_eq!(l["floor_rung_by"], "event");
    assert_eq!(l["agents"], 16);
    assert_eq!(l["simulate_s"].as_array().map(Vec::len), Some(1));
    assert!(l["simulate_median_s"].as_f64().expect("simulate") > 0.0);
    // Both floors measured, the busy-polled one without any wake-up.
    for floor in ["floor_spin_us", "floor_block_us"] {
        assert!(l[floor]["count"].as_u64().expect("count") > 0, "{floor}");
    }
    for wait in ["block", "spin"] {
        let w = &l[wait];
        assert_eq!(w["wait"], wait);
        assert_eq!(w["collisions"], 0, "{wait}");
        assert_eq!(w["faults"], 0, "{wait}");
        let loop_s = w["loop_median_s"].as_f64().expect("loop");
        let ratio = w["vs_simulate"].as_f64().expect("ratio");
        // The ratio is the two times divided, whatever they are.
        let simulate_s = l["simulate_median_s"].as_f64().expect("simulate");
        assert!(
            (ratio - loop_s / simulate_s).abs() < 1e-9 * ratio.max(1.0),
            "{wait}"
        );
        assert!(w["turn_us"]["count"].as_u64().expect("count") > 0, "{wait}");
        let turn_p50 = w["turn_us"]["p50"].as_f64().expect("p50");
        let ipc_p50 = w["ipc_overhead_us"]["p50"].as_f64().expect("ipc p50");
        assert!(ipc_p50 <= turn_p50, "{wait}: overhead is part of the turn");
        // Every agent stamps its moves: every measured turn is split, each part no
        // longer than the longest turn.
        let turns = w["turn_us"]["count"].as_u64();
        let longest = w["turn_us"]["max"].as_f64().expect("max");
        for part in ["to_agent_us", "agent_io_us", "to_coordinator_us"] {
            let d = check_distribution(&w["overhead_split"], part);
            assert_eq!(w["overhead_split"][part]["count"].as_u64(), turns, "{part}");
            assert!(d[4] <= longest, "{wait} {part}: {d:?} beyond {longest}");
        }
        // Parallel turns overlap: no time between turns to tell.
        assert!(w["between_turns_us"].is_null(), "{wait}");
        // Only a spinning coordinator grants a turn without a ring.
        let polled = w["polled_share"].as_f64().expect("polled share");
        assert!((0.0..=1.0).contains(&polled), "{wait}: {polled}");
        if wait == "block" {
            assert_eq!(polled, 0.0);
            assert_eq!(w["polled_to_agent_us"]["count"], 0);
        }
    }
    // With sequential turns, the coordinator's time between turns is told.
    let report = bench_report(
        &["--loop-rounds", "1"],
        Some((
            "--loop-scenario",
            &support::repo_root().join("scenarios/paper.toml"),
        )),
        &dir.path().join("sequential.json"),
    );
    for wait in ["block", "spin"] {
        let between = report["loops"][wait]["between_turns_us"].as_f64();
        assert!(
            between.is_some_and(|us| us.is_finite() && us >= 0.0),
            "{wait}"
        );
    }
    // A bad scenario is refused before anything runs.
    bench_refusal(&["--loop-scenario", "no-such-file.toml"].map(std::ffi::OsStr::new));
}

/// `--log-scenario`: the step loop with the run log and without, alternating; the report
/// names the kept log, whose size it gives per agent and step.
#[test]
fn bench_measures_what_the_run_log_costs() {
    let dir = tempfile::tempdir().expect("temporary directory");
    // In a folder that does not exist yet: the bench makes it before the log is written.
    let out_file = dir.path().join("not-yet").join("log.json");
    let scenario = support::repo_root().join("scenarios").join("paper.toml");
    let report = bench_report(
        &["--log-rounds", "2"],
        Some(("--log-scenario", &scenario)),
        &out_file,
    );
    let l = &report["log_cost"];
    assert_eq!(
        l["order"],
        serde_json::json!(["log", "none", "none", "log"])
    );
    let with: Vec<f64> = serde_json::from_value(l["with_log_steps_per_s"].clone()).expect("with");
    let without: Vec<f64> =
        serde_json::from_value(l["without_log_steps_per_s"].clone()).expect("without");
    assert_eq!((with.len(), without.len()), (2, 2));
    let median = |v: &[f64]| (v[0] + v[1]) / 2.0;
    let ratio = number(l, "with_vs_without_steps_per_s");
    let expected = median(&with) / median(&without);
    assert!(
        (ratio - expected).abs() <= 1e-9 * expected,
        "{ratio} vs {expected}"
    );
    // Round 1 is (log, none), round 2 (none, log): each round's ratio is of its own two.
    let rounds: Vec<f64> = serde_json::from_value(l["round_ratios"].clone()).expect("rounds");
    assert_eq!(rounds.len(), 2);
    for (r, (w, n)) in rounds.iter().zip(with.iter().zip(&without)) {
        assert!((r - w / n).abs() <= 1e-9 * r, "{r} vs {w} / {n}");
    }
    let median_round = number(l, "median_round_ratio");
    assert!((median_round - median(&rounds)).abs() <= 1e-9 * median_round);
    let log = std::path::PathBuf::from(l["log_file"].as_str().expect("log_file"));
    assert_eq!(log, out_file.with_extension("mcap"));
    let bytes = std::fs::metadata(&log).expect("the kept log").len();
    assert_eq!(l["log_bytes"], bytes);
    let agent_steps =
        l["agents"].as_u64().expect("agents") * (l["steps"].as_u64().expect("steps") + 1);
    assert!(
        (number(l, "log_bytes_per_agent_step") - bytes as f64 / agent_steps as f64).abs() < 1e-9
    );
}

/// `--scale`: a generated swarm at each size, run for real beside `simulate()` and the
/// spawn floor; every figure present and consistent, the ratios the quotients of the times
/// they name, the plot written, and sizes out of range refused before anything runs.
#[test]
fn bench_measures_the_runtime_against_the_number_of_agents() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let out_file = dir.path().join("scale.json");
    let report = bench_report(&["--scale", "3,8", "--scale-steps", "6"], None, &out_file);
    assert_eq!(report["runs"].as_array().expect("runs").len(), 0);
    let sizes = report["scale"]["sizes"].as_array().expect("sizes");
    assert_eq!(sizes.len(), 2);
    for (p, n) in sizes.iter().zip([3, 8]) {
        assert_eq!(p["agents"], n);
        assert_eq!(p["steps"], 6);
        assert_eq!(p["collisions"], 0, "{p}");
        assert_eq!(p["faults"], 0, "{p}");
        let startup = number(p, "startup_s");
        let phases: f64 = ["prepare", "spawn", "handshakes", "intruder_scan"]
            .iter()
            .map(|k| number(&p["startup_phases_s"], k))
            .sum();
        assert!(phases > 0.0 && phases <= startup + 1e-6, "{p}");
        for (ratio, a, b) in [
            ("startup_vs_floor", "startup_s", "spawn_floor_s"),
            ("loop_vs_simulate", "loop_s", "simulate_s"),
            ("wake_floor_vs_simulate", "wake_floor_s", "simulate_s"),
            ("loop_vs_wake_floor", "loop_s", "wake_floor_s"),
            ("futex_floor_vs_simulate", "futex_floor_s", "simulate_s"),
            ("wake_floor_vs_futex_floor", "wake_floor_s", "futex_floor_s"),
        ] {
            let (a, b) = (number(p, a), number(p, b));
            assert!(a > 0.0 && b > 0.0, "{p}");
            assert!(
                (number(p, ratio) - a / b).abs() <= 1e-9 * (a / b),
                "{ratio}: {p}"
            );
        }
        // The same run rung by iceoryx2 events: as safe, its ratio the quotient it names.
        let events = &p["event_rings"];
        assert_eq!(events["collisions"], 0, "{p}");
        assert_eq!(events["faults"], 0, "{p}");
        let (event_loop, loop_s) = (number(events, "loop_s"), number(p, "loop_s"));
        assert!(
            event_loop > 0.0 && number(events, "wake_floor_s") > 0.0,
            "{p}"
        );
        assert!(
            (number(events, "loop_vs_doorbells") - event_loop / loop_s).abs()
                <= 1e-9 * (event_loop / loop_s),
            "{p}"
        );
        // Every agent answered every empty turn of the wake-up floor.
        assert_eq!(p["wake_floor_unanswered"], 0, "{p}");
        // Parallel turns: fewer groups than agents once there is more than one.
        let groups = number(p, "mean_groups_per_step");
        assert!(groups >= 1.0 && groups <= f64::from(n), "{p}");
        // Every group of every step is timed, none larger than the formation.
        let timed = &p["groups"];
        let steps = number(p, "steps");
        assert_eq!(
            number(&timed["size"], "count"),
            (groups * steps).round(),
            "{p}"
        );
        assert!(number(&timed["size"], "max") <= f64::from(n), "{p}");
        assert!(number(&timed["size"], "p50") >= 1.0, "{p}");
        if let Some(idle) = timed["loop_idle_share"].as_f64() {
            assert!((0.0..=1.0).contains(&idle), "{p}");
        }
        check_distribution(timed, "wall_us");
        for key in [
            "turn_us",
            "compute_us",
            "agent_cpu_s",
            "agent_pss_kib",
            "agent_rss_kib",
        ] {
            check_distribution(p, key);
        }
        // One figure per agent process, each alive at the end.
        assert_eq!(p["agent_pss_kib"]["count"], n, "{p}");
        assert!(number(&p["agent_pss_kib"], "p50") <= number(&p["agent_rss_kib"], "p50"));
    }
    let svg = report["scale"]["plot_svg"].as_str().expect("plot");
    let text = std::fs::read_to_string(svg).expect("the plot");
    assert!(
        text.starts_with("<svg") && text.contains("spawn floor") && text.contains("wake-up floor"),
        "{svg}"
    );
    for bad in ["0", "5000"] {
        bench_refusal(&["--scale", bad].map(std::ffi::OsStr::new));
    }
}
