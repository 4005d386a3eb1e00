//! `coordinator compare`: every controller through the same processes and the same safety
//! monitor. The paper's LogSumExp barrier tries unsafe moves (the monitor refuses them,
//! so nobody collides); the barrier-function QP never does.

use crate::support;

use std::process::Command;

#[test]
fn the_comparison_table_shows_the_papers_failure_and_the_fix() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    let output = Command::new(support::coordinator_bin())
        .args(["compare", "--out"])
        .arg(&out)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .output()
        .expect("coordinator compare");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    assert!(md.starts_with("| scenario | controller |"));
    let mut reader = csv::Reader::from_path(out.join("compare.csv")).expect("compare.csv");
    let headers = reader.headers().expect("headers").clone();
    let col = |name: &str| headers.iter().position(|h| h == name).expect(name);
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    assert_eq!(rows.len(), 4, "four controllers on the paper example");
    for r in &rows {
        assert_eq!(
            &r[col("collisions")],
            "0",
            "the monitor keeps every controller safe"
        );
        assert_eq!(&r[col("completed")], "true");
    }
    let by = |controller: &str| {
        rows.iter()
            .find(|r| &r[col("controller")] == controller)
            .expect(controller)
    };
    let unsafe_moves = |controller: &str| {
        by(controller)[col("unsafe_moves")]
            .parse::<usize>()
            .expect("count")
    };
    assert_eq!(unsafe_moves("best-point"), 0);
    assert_eq!(unsafe_moves("cbf"), 0);
    assert!(
        unsafe_moves("zcbf-logsumexp") > 0,
        "the smoothed max overshoots (paper, IV.C.1)"
    );
    let final_dev = |controller: &str| {
        by(controller)[col("final_mean_deviation_m")]
            .parse::<f64>()
            .expect("dev")
    };
    assert!(final_dev("best-point") < 0.05);
    // The new columns come after the old ones: the paper's own (sequential) turns, a
    // move length, a speed and the paper's turn order (agent order) for every run.
    assert_eq!(headers.len(), 18);
    assert_eq!(
        headers.iter().skip(12).collect::<Vec<_>>(),
        [
            "turns",
            "max_move_m",
            "steps_per_s",
            "worst_agent",
            "worst_step",
            "turn_order"
        ]
    );
    for r in &rows {
        assert_eq!(&r[col("turns")], "sequential");
        assert_eq!(&r[col("turn_order")], "agent");
        assert!(r[col("max_move_m")].parse::<f64>().expect("max move") > 0.0);
        assert!(r[col("steps_per_s")].parse::<f64>().expect("steps/s") > 0.0);
        // The worst agent and step name a deviation of the run: that agent's record at
        // that step in the run's own trajectory.csv holds the largest deviation.
        let (agent, step) = (
            r[col("worst_agent")].parse::<usize>().expect("agent"),
            r[col("worst_step")].parse::<usize>().expect("step"),
        );
        assert!(agent < 6);
        assert!(step > 0, "the obstacles disturb every controller");
        let folder = out.join(format!("paper-example-{}", &r[col("controller")]));
        let mut traj = csv::Reader::from_path(folder.join("trajectory.csv")).expect("trajectory");
        let th = traj.headers().expect("headers").clone();
        let tcol = |name: &str| th.iter().position(|h| h == name).expect(name);
        let worst = traj
            .records()
            .map(|t| t.expect("row"))
            .find(|t| t[tcol("step")] == step.to_string() && t[tcol("agent")] == agent.to_string())
            .expect("the worst record");
        let dev: f64 = worst[tcol("deviation_m")].parse().expect("deviation");
        let max: f64 = r[col("max_deviation_m")].parse().expect("max");
        assert!((dev - max).abs() <= 1e-9 * (1.0 + max), "{dev} vs {max}");
    }
    assert!(md.contains("| turns | max move (m) | steps/s |"));
}

/// What `coordinator compare scenarios/paper-top-speed.toml ARGS --out DIR` wrote and
/// printed; it must succeed.
struct Compared {
    /// Holds the output folder while the test looks at it.
    _dir: tempfile::TempDir,
    out: std::path::PathBuf,
    headers: csv::StringRecord,
    rows: Vec<csv::StringRecord>,
    stderr: String,
}

impl Compared {
    /// The index of column `name` of compare.csv.
    fn col(&self, name: &str) -> usize {
        self.headers.iter().position(|h| h == name).expect(name)
    }

    /// Every run within the top speed of 0.5 m and without a collision.
    fn assert_safe_within_the_top_speed(&self) {
        for r in &self.rows {
            assert_eq!(&r[self.col("collisions")], "0", "{r:?}");
            let max_move: f64 = r[self.col("max_move_m")].parse().expect("max move");
            assert!(max_move <= 0.5 + 1e-6, "the top speed holds: {max_move}");
        }
    }
}

fn compare_paper_top_speed(args: &[&str]) -> Compared {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    let scenario = support::repo_root()
        .join("scenarios")
        .join("paper-top-speed.toml");
    let output = Command::new(support::coordinator_bin())
        .arg("compare")
        .arg(&scenario)
        .args(args)
        .arg("--out")
        .arg(&out)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .output()
        .expect("coordinator compare");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{stderr}");
    let mut reader = csv::Reader::from_path(out.join("compare.csv")).expect("compare.csv");
    let headers = reader.headers().expect("headers").clone();
    let rows = reader.records().map(|r| r.expect("row")).collect();
    Compared {
        _dir: dir,
        out,
        headers,
        rows,
        stderr,
    }
}

#[test]
fn compare_runs_every_controller_in_every_turn_mode_asked_for() {
    let c = compare_paper_top_speed(&[
        "--controllers",
        "best-point,cbf",
        "--turns",
        "sequential,parallel",
    ]);
    let got: Vec<(&str, &str)> = c
        .rows
        .iter()
        .map(|r| (&r[c.col("turns")], &r[c.col("controller")]))
        .collect();
    let want = [
        ("sequential", "best-point"),
        ("sequential", "cbf"),
        ("parallel", "best-point"),
        ("parallel", "cbf"),
    ];
    assert_eq!(got, want);
    c.assert_safe_within_the_top_speed();
    // Each run in a folder naming its mode, its resolved scenario in that mode.
    for (mode, controller) in [("sequential", "cbf"), ("parallel", "best-point")] {
        let run = c.out.join(format!("paper-top-speed-{controller}-{mode}"));
        let text = std::fs::read_to_string(run.join("scenario.toml")).expect("scenario.toml");
        assert!(text.contains(&format!("mode = \"{mode}\"")), "{mode}");
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(run.join("summary.json")).expect("summary"))
                .expect("summary.json parses");
        let groups = summary["mean_groups_per_step"].as_f64().expect("groups");
        if mode == "parallel" {
            assert!(groups < 6.0, "parallel groups: {groups}");
        } else {
            assert_eq!(groups, 6.0);
        }
    }
    assert!(
        c.stderr
            .contains("with best-point, parallel turns: completed"),
        "{}",
        c.stderr
    );
}

/// `--turn-order agent,front-first`: one run in each order (a repeated one runs once),
/// in a folder naming it, its resolved scenario in that order; both safe and within the
/// top speed.
#[test]
fn compare_runs_each_turn_order_asked_for() {
    let c = compare_paper_top_speed(&[
        "--controllers",
        "best-point",
        "--turn-order",
        "agent,front-first,agent",
    ]);
    let orders: Vec<&str> = c.rows.iter().map(|r| &r[c.col("turn_order")]).collect();
    assert_eq!(orders, ["agent", "front-first"]);
    assert!(c.rows.iter().all(|r| &r[c.col("turns")] == "sequential"));
    c.assert_safe_within_the_top_speed();
    for order in ["agent", "front-first"] {
        let run = c.out.join(format!("paper-top-speed-best-point-{order}"));
        let text = std::fs::read_to_string(run.join("scenario.toml")).expect("scenario.toml");
        assert!(text.contains(&format!("order = \"{order}\"")), "{order}");
    }
    assert!(
        c.stderr
            .contains("with best-point, front-first order: completed"),
        "{}",
        c.stderr
    );
}

#[test]
fn compare_refuses_parallel_turns_without_a_top_speed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    let paper = support::repo_root().join("scenarios").join("paper.toml");
    let output = Command::new(support::coordinator_bin())
        .arg("compare")
        .arg(&paper)
        .args(["--turns", "parallel", "--out"])
        .arg(&out)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .output()
        .expect("coordinator compare");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("turns.mode"), "{stderr}");
    assert!(!out.exists(), "nothing created");
}

/// The lines `compare` may print for `runs` runs: one per run, the table (header, rule,
/// one row per run), the output folder, and a few to spare.
fn line_budget(runs: usize) -> usize {
    runs + (2 + runs) + 1 + 3
}

#[test]
fn compare_prints_one_line_per_run_and_keeps_the_refusals_in_the_run_summaries() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    let paper = support::repo_root().join("scenarios").join("paper.toml");
    let output = Command::new(support::coordinator_bin())
        .arg("compare")
        .arg(&paper)
        .args(["--controllers", "zcbf-logsumexp,best-point", "--out"])
        .arg(&out)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        // Warnings on, as a user has them by default: still no line per refused move.
        .env("RUST_LOG", "warn")
        .output()
        .expect("coordinator compare");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(
        lines.len() <= line_budget(2),
        "{} lines on stderr, at most {} expected; first ones:\n{}",
        lines.len(),
        line_budget(2),
        lines[..lines.len().min(20)].join("\n")
    );
    for controller in ["zcbf-logsumexp", "best-point"] {
        let line = format!("paper-example with {controller}: completed, 0 collisions, ");
        assert_eq!(
            lines.iter().filter(|l| l.starts_with(&line)).count(),
            1,
            "one result line for {controller}:\n{stderr}"
        );
    }

    // The refusals are in the run's own summary, as many as the table counts.
    let mut reader = csv::Reader::from_path(out.join("compare.csv")).expect("compare.csv");
    let headers = reader.headers().expect("headers").clone();
    let col = |name: &str| headers.iter().position(|h| h == name).expect(name);
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    let zcbf = rows
        .iter()
        .find(|r| &r[col("controller")] == "zcbf-logsumexp")
        .expect("zcbf row");
    let refused: usize = zcbf[col("unsafe_moves")].parse().expect("count");
    assert!(refused > 0, "the smoothed max overshoots");
    let run_dir = out.join("paper-example-zcbf-logsumexp");
    let summary: serde_json::Value = serde_json::from_slice(
        &std::fs::read(run_dir.join("summary.json")).expect("the run's summary.json"),
    )
    .expect("summary.json parses");
    let rejected = summary["faults"]
        .as_array()
        .expect("faults")
        .iter()
        .filter(|f| f["kind"] == "rejected")
        .count();
    assert_eq!(rejected, refused);
    // The run's folder holds the resolved scenario, with the controller as run.
    let text = std::fs::read_to_string(run_dir.join("scenario.toml")).expect("scenario.toml");
    let resolved =
        shared::world::scenario::Scenario::parse(&text, "scenario.toml").expect("resolved loads");
    let original = shared::world::scenario::Scenario::load(&paper).expect("paper.toml");
    assert_eq!(
        resolved,
        original.with_controller(shared::control::vocabulary::ControllerKind::ZcbfLogsumexp)
    );
    assert!(!text.contains("random"));
}

#[test]
fn compare_refuses_a_folder_holding_something_unless_forced() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    std::fs::create_dir(&out).expect("mkdir");
    std::fs::write(out.join("old.md"), b"old").expect("write");
    let compare = |force: bool| {
        let mut c = Command::new(support::coordinator_bin());
        c.args(["compare", "--controllers", "best-point", "--out"])
            .arg(&out)
            .env("FORMATION_AGENT_BIN", support::agent_bin());
        if force {
            c.arg("--force");
        }
        c.output().expect("coordinator compare")
    };
    let refused = compare(false);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains(&out.display().to_string()), "{stderr}");
    assert_eq!(
        std::fs::read(out.join("old.md")).expect("untouched"),
        b"old"
    );

    let forced = compare(true);
    let stderr = String::from_utf8_lossy(&forced.stderr);
    assert!(forced.status.success(), "{stderr}");
    assert!(!out.join("old.md").exists(), "replaced whole");
    assert!(out.join("compare.csv").is_file());
    assert!(
        out.join("paper-example-best-point")
            .join("summary.json")
            .is_file()
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .expect("read_dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(left, ["cmp"], "no temporary folder left");
}

/// Agents with a heading: every controller's move is driven through the agent's
/// kinematics (a unicycle turns in place and drives, a car drives arcs), so the baselines
/// run on the same robots; the monitor keeps every one of them safe.
#[test]
fn compare_runs_the_baselines_on_cars_through_their_kinematics() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    let scenario = support::repo_root().join("scenarios/paper-car.toml");
    let output = Command::new(support::coordinator_bin())
        .args(["compare", "--controllers", "best-point,orca", "--out"])
        .arg(&out)
        .arg(&scenario)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .output()
        .expect("coordinator compare");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut reader = csv::Reader::from_path(out.join("compare.csv")).expect("compare.csv");
    let headers = reader.headers().expect("headers").clone();
    let col = |name: &str| headers.iter().position(|h| h == name).expect(name);
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    assert_eq!(rows.len(), 2, "two controllers");
    for r in &rows {
        assert_eq!(&r[col("collisions")], "0");
        assert_eq!(&r[col("completed")], "true");
        // A car moves no farther than its top speed along its arcs, so its chords too.
        assert!(r[col("max_move_m")].parse::<f64>().expect("max move") <= 0.5 + 1e-9);
    }
    // Each run's trajectory carries the headings.
    let trajectory = std::fs::read_to_string(out.join("paper-car-orca").join("trajectory.csv"))
        .expect("trajectory.csv of the ORCA run");
    assert!(
        trajectory
            .lines()
            .next()
            .expect("header")
            .contains("heading_rad")
    );
}
