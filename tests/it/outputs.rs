//! The output folder of `coordinator run`: its `scenario.toml` is the resolved scenario
//! (loads to the same scenario bit for bit, every obstacle listed), a folder that holds
//! something is refused without `--force` (nothing touched) and replaced whole with it.

use crate::support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::SystemTime;

use shared::control::vocabulary::ControllerKind;
use shared::world::scenario::Scenario;

fn coordinator(args: &[&str]) -> Command {
    let mut c = Command::new(support::coordinator_bin());
    c.args(args)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

fn run(args: &[&str], out: &Path) -> Output {
    coordinator(&["run", "--quiet", support::TRUSTED])
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("coordinator run")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Every file below `dir` with its bytes and modification time.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, (Vec<u8>, SystemTime)> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, (Vec<u8>, SystemTime)>) {
        for e in std::fs::read_dir(dir).expect("read_dir") {
            let path = e.expect("entry").path();
            let meta = std::fs::symlink_metadata(&path).expect("metadata");
            let rel = path.strip_prefix(root).expect("below root").to_path_buf();
            if meta.is_dir() {
                out.insert(rel, (Vec::new(), meta.modified().expect("mtime")));
                walk(root, &path, out);
            } else {
                let bytes = std::fs::read(&path).expect("read");
                out.insert(rel, (bytes, meta.modified().expect("mtime")));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// The names in `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("read_dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The refusal of an output folder: exit code 2, one line naming the folder and
/// `--force`, and no run (no summary line).
fn assert_refused(o: &Output, out: &Path) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(err.contains(&out.display().to_string()), "{err}");
    assert!(err.contains("--force"), "{err}");
}

#[test]
fn a_folder_holding_a_run_is_refused_without_force_and_replaced_whole_with_it() {
    let work = tempfile::tempdir().expect("tempdir");
    let out = work.path().join("run");
    let first = run(&[], &out);
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(out.join("plots").join("field.png").is_file());
    let before = snapshot(&out);

    // Without --force: refused before anything runs; not a byte or a time changed.
    let again = run(&["--no-plots"], &out);
    assert_refused(&again, &out);
    assert_eq!(snapshot(&out), before, "the old run is untouched");
    assert_eq!(names(work.path()), ["run"], "nothing created beside it");

    // With --force: the new run whole, nothing of the old one (no plots/ with
    // --no-plots), no temporary folder left beside it.
    let forced = run(&["--no-plots", "--force", "--controller", "cbf"], &out);
    assert!(forced.status.success(), "{}", stderr(&forced));
    assert!(!out.join("plots").exists(), "old plots/ survived");
    assert_eq!(
        names(&out),
        [
            "moves.csv",
            "obstacles.csv",
            "path.csv",
            "plans.csv",
            "run.mcap",
            "scenario.toml",
            "summary.json",
            "trajectory.csv"
        ]
    );
    assert_eq!(names(work.path()), ["run"], "no temporary folder left");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary"))
            .expect("summary.json parses");
    assert_eq!(summary["completed"], true);
    // The start-up's phases, each measured, are parts of the start-up: together no longer
    // than it. (How much of it they cover depends on how loaded the machine is, with
    // trusted agents' start-up a few tens of milliseconds: the bench reports it.)
    let phases = &summary["startup_phases_s"];
    let phase = |k: &str| {
        phases[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k}: {phases}"))
    };
    let sum: f64 = ["prepare", "spawn", "handshakes", "intruder_scan"]
        .iter()
        .map(|k| phase(k))
        .sum();
    let startup = summary["startup_s"].as_f64().expect("startup_s");
    assert!(phase("spawn") > 0.0 && phase("prepare") > 0.0);
    assert!(sum > 0.0 && sum <= startup + 1e-9, "{sum} of {startup}");
    // The controller as run is the one in the folder's scenario.
    let text = std::fs::read_to_string(out.join("scenario.toml")).expect("scenario.toml");
    let resolved = Scenario::parse(&text, "scenario.toml").expect("resolved scenario loads");
    assert_eq!(resolved.controller.kind, ControllerKind::Cbf);

    // The replaced folder still renders.
    let render = coordinator(&["render"])
        .arg(&out)
        .output()
        .expect("coordinator render");
    assert!(render.status.success(), "{}", stderr(&render));
    assert!(out.join("plots").join("animation.gif").is_file());
}

#[test]
fn the_run_folder_scenario_lists_every_obstacle_and_loads_to_the_same_scenario() {
    let work = tempfile::tempdir().expect("tempdir");
    // A missing parent chain is created.
    let out = work.path().join("a").join("b").join("run");
    let paper = support::repo_root().join("scenarios").join("paper.toml");
    let o = coordinator(&["run", "--quiet", "--no-plots", support::TRUSTED])
        .arg(&paper)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("coordinator run");
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("scenario.toml")).expect("scenario.toml");
    assert!(!text.contains("random"), "{text}");
    assert!(text.contains("paper.toml"), "names its source: {text}");
    let resolved = Scenario::parse(&text, "scenario.toml").expect("resolved scenario loads");
    let original = Scenario::load(&paper).expect("paper.toml");
    assert_eq!(resolved, original);
    assert_eq!(
        format!("{resolved:?}"),
        format!("{original:?}"),
        "bit for bit"
    );
    assert_eq!(resolved.obstacles.len(), 30);
    assert_eq!(names(work.path()), ["a"]);
    assert_eq!(names(&work.path().join("a").join("b")), ["run"]);
}

#[test]
fn unrelated_folders_and_files_are_never_replaced_without_force() {
    let work = tempfile::tempdir().expect("tempdir");
    let mine = work.path().join("mine");
    std::fs::create_dir(&mine).expect("mkdir");
    std::fs::write(mine.join("notes.txt"), b"keep me").expect("write");
    let before = snapshot(&mine);
    assert_refused(&run(&["--no-plots"], &mine), &mine);
    assert_eq!(snapshot(&mine), before);

    let file = work.path().join("file");
    std::fs::write(&file, b"a file").expect("write");
    assert_refused(&run(&["--no-plots"], &file), &file);
    assert_eq!(std::fs::read(&file).expect("read"), b"a file");

    // Below a file: nothing can be created there; refused before the run.
    let below = file.join("run");
    let o = run(&["--no-plots"], &below);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(stderr(&o).lines().count(), 1, "{}", stderr(&o));

    // An empty folder is used as it is.
    let empty = work.path().join("empty");
    std::fs::create_dir(&empty).expect("mkdir");
    let o = run(&["--no-plots"], &empty);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(empty.join("summary.json").is_file());

    // --force replaces even an unrelated folder, whole.
    let o = run(&["--no-plots", "--force"], &mine);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!mine.join("notes.txt").exists());
    assert!(mine.join("summary.json").is_file());
    assert_eq!(names(work.path()), ["empty", "file", "mine"]);
}

/// With agents that have a heading, `moves.csv` gives each waypoint's primitive: driving
/// the arc it names from the waypoint before lands on the waypoint, a car never turns in
/// place nor bends tighter than its turning radius, and a unicycle drives straight.
#[test]
fn moves_csv_gives_the_exact_arc_that_reaches_each_waypoint() {
    use shared::control::vocabulary::Kinematics;
    for name in [
        "paper-car.toml",
        "narrow-reversing-car.toml",
        "paper-unicycle.toml",
    ] {
        let file = support::repo_root().join("scenarios").join(name);
        let scenario = Scenario::load(&file).expect("shipped scenario");
        let run = shared::run::simulate::simulate(&scenario).expect("simulate");
        let bytes = runner::output::moves_csv(&scenario, &run).expect("moves.csv");
        let mut reader = csv::Reader::from_reader(bytes.as_slice());
        let headers = reader.headers().expect("headers").clone();
        let col = |n: &str| headers.iter().position(|h| h == n).expect(n);
        let (x, y, h, d, k) = (
            col("x"),
            col("y"),
            col("heading_rad"),
            col("drive_m"),
            col("curvature_per_m"),
        );
        let num = |r: &csv::StringRecord, c: usize| r[c].parse::<f64>().expect("a number");
        let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
        let (mut arcs, mut curved, mut reversed) = (0, 0, 0);
        for w in rows.windows(2) {
            let (before, row) = (&w[0], &w[1]);
            if &row[col("index")] == "0" {
                assert!(
                    row[d].is_empty() && row[k].is_empty(),
                    "{name}: no arc at index 0"
                );
                continue;
            }
            let agent: usize = row[col("agent")].parse().expect("agent");
            let (drive_m, curvature_per_m) = (num(row, d), num(row, k));
            let length_m = drive_m.abs();
            let start_rad = num(row, h) - curvature_per_m * length_m;
            let half_rad = 0.5 * curvature_per_m * length_m;
            let sinc = if half_rad.abs() < 1e-8 {
                1.0
            } else {
                half_rad.sin() / half_rad
            };
            let along = drive_m * sinc;
            let (ex, ey) = (
                num(before, x) + along * (start_rad + half_rad).cos(),
                num(before, y) + along * (start_rad + half_rad).sin(),
            );
            let off_m = (ex - num(row, x)).hypot(ey - num(row, y));
            assert!(
                off_m < 1e-9,
                "{name}: the arc lands {off_m} m off its waypoint"
            );
            let turned_in_place = shared::geometry::wrap_angle_rad(start_rad - num(before, h));
            match scenario.agents[agent].kinematics {
                Kinematics::Car {
                    turning_radius_m, ..
                } => {
                    assert!(
                        turned_in_place.abs() < 1e-6,
                        "{name}: a car turned in place"
                    );
                    assert!(curvature_per_m.abs() <= (1.0 + 1e-6) / turning_radius_m);
                }
                Kinematics::Unicycle { .. } => assert_eq!(curvature_per_m, 0.0),
                Kinematics::Holonomic => unreachable!("every agent has a heading"),
            }
            arcs += 1;
            curved += usize::from(curvature_per_m != 0.0);
            reversed += usize::from(drive_m < 0.0);
        }
        assert!(arcs > 100, "{name}: {arcs} arcs");
        if name.contains("car") {
            assert!(curved > 0, "{name}: the cars drive arcs");
        }
        if name == "narrow-reversing-car.toml" || name == "paper-car.toml" {
            assert!(reversed > 0, "{name}: the cars reverse");
        }
    }
}
