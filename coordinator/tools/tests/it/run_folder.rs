//! A run folder written by `runner::output::write_run` reads back through
//! `coordinator render`'s reader (`RunData::load`) to the run that was written, bit for
//! bit: the scenario, the centre path, every agent at every step with its move, the
//! plans, the moving and unknown obstacles and the faults. The writer and the reader share
//! one row type per file; this checks they also agree on every value.

use std::path::{Path, PathBuf};

use shared::run::record::{Fault, FaultKind, Run};
use shared::world::scenario::Scenario;
use tools::render::RunData;

/// A scratch folder of this test, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("run-folder-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        Self(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn bits(v: f64) -> u64 {
    v.to_bits()
}

/// `a` and `b` the same number to the bit (any NaN matches any NaN).
fn assert_bits(a: f64, b: f64, what: &str) {
    assert!(
        bits(a) == bits(b) || (a.is_nan() && b.is_nan()),
        "{what}: wrote {a:?}, read {b:?}"
    );
}

/// Write `run` of `scenario` (planned along `first_plan`) and read it back.
fn write_and_load(
    dir: &Path,
    scenario: &Scenario,
    run: &Run,
    first_plan: &[shared::geometry::Pose],
) -> RunData {
    runner::output::write_run(
        dir,
        scenario,
        "test",
        run,
        first_plan,
        &runner::output::Timing::default(),
    )
    .expect("write run");
    RunData::load(dir).unwrap_or_else(|e| panic!("{e}"))
}

fn check_round_trip(file: &str) -> (usize, usize, usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(file);
    let scenario = Scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let first_plan = shared::run::simulate::plan_centre_path(&scenario).expect("a centre path");
    let mut run = shared::run::simulate::simulate(&scenario).expect("simulate");
    // Faults of every kind, so their names are read back too.
    run.faults = FaultKind::ALL
        .iter()
        .enumerate()
        .map(|(i, &kind)| Fault {
            agent: i % scenario.agents.len(),
            step: i,
            kind,
            detail: format!("detail, \"{i}\""),
            detection_ms: None,
        })
        .collect();
    let scratch = Scratch::new(file);
    let data = write_and_load(&scratch.0, &scenario, &run, &first_plan);

    assert_eq!(data.scenario, scenario, "{file}");
    assert_eq!(
        format!("{:?}", data.scenario),
        format!("{scenario:?}"),
        "{file}"
    );
    assert_eq!(data.completed, Some(run.completed), "{file}");

    assert_eq!(data.centre.len(), run.centre_path.len(), "{file}");
    for (k, (c, p)) in data.centre.iter().zip(&run.centre_path).enumerate() {
        assert_eq!(c.step, k, "{file}");
        assert_bits(c.pose.x_m, p.x_m, "path.csv x_m");
        assert_bits(c.pose.y_m, p.y_m, "path.csv y_m");
        assert_bits(c.pose.heading_rad, p.heading_rad, "path.csv heading_rad");
    }

    assert_eq!(data.steps.len(), run.steps.len(), "{file}");
    for (read, step) in data.steps.iter().zip(&run.steps) {
        assert_eq!(read.step, step.step, "{file}");
        assert_eq!(read.agents.len(), step.agents.len(), "{file}");
        for (r, a) in read.agents.iter().zip(&step.agents) {
            for (x, y, what) in [
                (r.position.x, a.position.x, "x"),
                (r.position.y, a.position.y, "y"),
                (r.slot.x, a.slot.x, "slot_x"),
                (r.slot.y, a.slot.y, "slot_y"),
                (r.best.x, a.best.x, "best_x"),
                (r.best.y, a.best.y, "best_y"),
                (r.deviation_m, a.deviation_m, "deviation_m"),
                (r.clearance_m, a.clearance_m, "clearance_m"),
            ] {
                assert_bits(x, y, what);
            }
            assert_eq!((r.status, r.alive), (a.status, a.alive), "{file}");
            assert_eq!(r.waypoints.len(), a.waypoints.len(), "{file}");
            for (p, q) in r.waypoints.iter().zip(&a.waypoints) {
                assert_bits(p.x, q.x, "moves.csv x");
                assert_bits(p.y, q.y, "moves.csv y");
            }
        }
    }

    let taken: Vec<_> = run.course.replans.iter().filter(|r| r.found).collect();
    assert_eq!(data.plans.len(), 1 + taken.len(), "{file}");
    assert_eq!(data.plans[0].reason.name(), "first");
    assert_eq!(data.plans[0].poses, first_plan, "{file}");
    for (plan, replan) in data.plans[1..].iter().zip(&taken) {
        assert_eq!(plan.step, replan.step, "{file}");
        assert_eq!(plan.reason.name(), replan.reason.name(), "{file}");
        assert_eq!(plan.poses.len(), replan.path.len(), "{file}");
        for (p, q) in plan.poses.iter().zip(&replan.path) {
            assert_bits(p.x_m, q.x_m, "plans.csv x_m");
            assert_bits(p.y_m, q.y_m, "plans.csv y_m");
            assert_bits(p.heading_rad, q.heading_rad, "plans.csv heading_rad");
        }
    }

    if scenario.moving.is_empty() {
        assert!(data.moving.is_empty(), "{file}");
    } else {
        assert_eq!(data.moving.len(), run.steps.len(), "{file}");
        for (m, step) in data.moving.iter().zip(&run.steps) {
            assert_eq!(m.step, step.step, "{file}");
            assert_eq!(m.positions, step.moving, "{file}");
        }
    }
    assert_eq!(data.unknown.len(), scenario.unknown.len(), "{file}");
    for (i, (u, disk)) in data.unknown.iter().zip(&scenario.unknown).enumerate() {
        assert_eq!(u.disk, *disk, "{file}");
        assert_eq!(
            u.known_from_step,
            run.course.found_at.get(i).copied().flatten(),
            "{file}"
        );
    }

    assert_eq!(data.faults.len(), run.faults.len(), "{file}");
    for (r, f) in data.faults.iter().zip(&run.faults) {
        assert_eq!(
            (r.agent, r.step, r.kind, &r.detail),
            (f.agent, f.step, f.kind, &f.detail)
        );
    }
    (data.plans.len(), data.moving.len(), data.unknown.len())
}

#[test]
fn a_static_run_reads_back_as_written() {
    let (plans, moving, unknown) = check_round_trip("paper.toml");
    assert_eq!((plans, moving, unknown), (1, 0, 0));
}

#[test]
fn a_run_among_moving_obstacles_reads_back_as_written() {
    let (_, moving, _) = check_round_trip("patrol.toml");
    assert!(moving > 0, "patrol.toml has moving obstacles");
}

#[test]
fn a_run_that_finds_obstacles_and_replans_reads_back_as_written() {
    let (plans, _, unknown) = check_round_trip("clcbs-unknown.toml");
    assert!(unknown > 0, "clcbs-unknown.toml has unknown obstacles");
    assert!(plans > 1, "clcbs-unknown.toml replans");
}
