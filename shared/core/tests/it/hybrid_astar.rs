//! Hybrid A* on the CL-CBS obstacle fields and on hand-made cases, every returned path
//! checked by brute force, independently of the planner's own collision checks.

use std::path::PathBuf;
use std::time::Instant;

use shared::geometry::{Disk, Field, Pose, distance_point_segment, wrap_angle_rad};
use shared::paths::hybrid_astar::{
    HybridAStarSettings, PlanError, path_length_m, plan, plan_with_stats, resample,
};
use testkit::clcbs::{CLCBS_DIR_ENV, CLCBS_INSTANCE_FILES, ClcbsInstance, default_clcbs_dir};

const TURNING_RADIUS_M: f64 = 2.5;
const CLEARANCE_M: f64 = 0.5;

fn load(name: &str) -> ClcbsInstance {
    let path: PathBuf = default_clcbs_dir().join(name);
    ClcbsInstance::load(&path).unwrap_or_else(|e| {
        panic!(
            "cannot read CL-CBS instance {} ({e}); set {CLCBS_DIR_ENV} to the folder holding \
             the CL-CBS files (default: shared/core/tests/data/clcbs in this repository)",
            path.display()
        )
    })
}

fn same_pose(a: &Pose, b: &Pose) -> bool {
    (a.x_m - b.x_m).abs() <= 1e-9
        && (a.y_m - b.y_m).abs() <= 1e-9
        && wrap_angle_rad(a.heading_rad - b.heading_rad).abs() <= 1e-9
}

/// Every property a returned path must have, checked by brute force over all obstacles.
fn check_path(
    field: &Field,
    obstacles: &[Disk],
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
    path: &[Pose],
    what: &str,
) {
    let c = settings.clearance_m;
    assert!(path.len() >= 2, "{what}: path too short");
    assert!(
        same_pose(&path[0], start),
        "{what}: first pose {:?} != start {start:?}",
        path[0]
    );
    let last = path[path.len() - 1];
    assert!(
        same_pose(&last, goal),
        "{what}: last pose {last:?} != goal {goal:?}"
    );
    for (i, p) in path.iter().enumerate() {
        let q = p.position();
        assert!(
            q.x >= c - 1e-9
                && q.y >= c - 1e-9
                && q.x <= field.width_m - c + 1e-9
                && q.y <= field.height_m - c + 1e-9,
            "{what}: pose {i} {p:?} leaves the field inset by {c}"
        );
        for d in obstacles {
            let clearance = (q - d.centre).norm() - d.radius_m;
            assert!(
                clearance >= c - 1e-9,
                "{what}: pose {i} {p:?} is {clearance} m from {d:?}"
            );
        }
    }
    let curvature_limit = 1.0 / settings.turning_radius_m;
    for (i, w) in path.windows(2).enumerate() {
        let (a, b) = (w[0].position(), w[1].position());
        for d in obstacles {
            let clearance = distance_point_segment(&d.centre, &a, &b) - d.radius_m;
            assert!(
                clearance >= c - 1e-9,
                "{what}: chord {i} is {clearance} m from {d:?}"
            );
        }
        let step = b - a;
        let distance = step.norm();
        let turn = wrap_angle_rad(w[1].heading_rad - w[0].heading_rad).abs();
        assert!(
            distance <= settings.sample_spacing_m + 1e-9,
            "{what}: poses {i}, {} are {distance} m apart",
            i + 1
        );
        if distance < 1e-9 {
            assert!(turn < 1e-9, "{what}: turn on the spot at pose {i}");
            continue;
        }
        assert!(
            turn / distance <= curvature_limit * (1.0 + 1e-3) + 1e-9,
            "{what}: curvature {} at pose {i} exceeds {curvature_limit}",
            turn / distance
        );
        // The heading is tangent to the path: the chord makes half the turn with it.
        let heading = nalgebra::Vector2::new(w[0].heading_rad.cos(), w[0].heading_rad.sin());
        let along = step.dot(&heading) / distance;
        let off_rad = along.abs().min(1.0).acos();
        assert!(
            off_rad <= 0.5 * turn + 1e-6,
            "{what}: heading not tangent at pose {i}"
        );
        if !settings.allow_reverse {
            assert!(along > 0.0, "{what}: reverse motion at pose {i}");
        }
    }
}

/// Arc-length position of each resampled pose on `path`, walking forwards.
fn arc_positions(path: &[Pose], samples: &[Pose]) -> Vec<f64> {
    let mut cumulative = vec![0.0];
    for w in path.windows(2) {
        let last = cumulative[cumulative.len() - 1];
        cumulative.push(last + (w[1].position() - w[0].position()).norm());
    }
    let mut segment = 0;
    samples
        .iter()
        .map(|p| {
            let q = p.position();
            while segment + 1 < path.len()
                && distance_point_segment(
                    &q,
                    &path[segment].position(),
                    &path[segment + 1].position(),
                ) > 1e-9
            {
                segment += 1;
            }
            assert!(
                segment + 1 < path.len(),
                "resampled pose {p:?} is not on the path"
            );
            cumulative[segment] + (q - path[segment].position()).norm()
        })
        .collect()
}

fn check_resample(path: &[Pose], step_m: f64) {
    let samples = resample(path, step_m);
    assert!(same_pose(&samples[0], &path[0]));
    assert_eq!(
        samples[samples.len() - 1],
        path[path.len() - 1],
        "the goal is kept exactly"
    );
    let s = arc_positions(path, &samples);
    for (i, w) in s.windows(2).enumerate() {
        let gap = w[1] - w[0];
        if i + 2 < s.len() {
            assert!(
                (gap - step_m).abs() <= 1e-9,
                "step {i} is {gap} m, not {step_m}"
            );
        } else {
            assert!(gap > 0.0 && gap <= step_m + 1e-9, "last step {gap} m");
        }
    }
    let expected = (path_length_m(path) / step_m).ceil() as usize + 1;
    assert!(
        samples.len().abs_diff(expected) <= 1,
        "{} samples, expected about {expected}",
        samples.len()
    );
}

/// Plan for the first `agents` agents of an instance (all if fewer), checking each path.
fn plan_instance(name: &str, agents: usize, allow_reverse: bool) {
    let instance = load(name);
    assert!(instance.agents.len() >= 4, "{name} has too few agents");
    let agents = agents.min(instance.agents.len());
    let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, allow_reverse);
    for agent in &instance.agents[..agents] {
        let what = format!("{name} {}", agent.name);
        let started = Instant::now();
        let (path, stats) = plan_with_stats(
            &instance.field,
            &instance.obstacles,
            &agent.start,
            &agent.goal,
            &settings,
        )
        .unwrap_or_else(|e| panic!("{what}: {e}"));
        eprintln!(
            "{what}: {:.1} m, {} expansions, {} analytic tries, {:?}",
            stats.length_m,
            stats.expansions,
            stats.analytic_attempts,
            started.elapsed()
        );
        check_path(
            &instance.field,
            &instance.obstacles,
            &agent.start,
            &agent.goal,
            &settings,
            &path,
            &what,
        );
        check_resample(&path, 0.25);
    }
}

#[test]
fn every_clcbs_file_is_present_and_parses() {
    for name in CLCBS_INSTANCE_FILES {
        let instance = load(name);
        let size = instance.field.width_m;
        assert!([50.0, 100.0, 300.0].contains(&size), "{name}: size {size}");
        assert!(
            !instance.obstacles.is_empty() && !instance.agents.is_empty(),
            "{name}"
        );
        assert!(instance.obstacles.iter().all(|d| d.radius_m == 0.8));
    }
}

#[test]
fn clcbs_50_a() {
    plan_instance(CLCBS_INSTANCE_FILES[0], usize::MAX, true);
}

#[test]
fn clcbs_50_b() {
    plan_instance(CLCBS_INSTANCE_FILES[1], usize::MAX, true);
}

#[test]
fn clcbs_100_a() {
    plan_instance(CLCBS_INSTANCE_FILES[2], usize::MAX, true);
}

#[test]
fn clcbs_100_b() {
    plan_instance(CLCBS_INSTANCE_FILES[3], usize::MAX, true);
}

#[test]
fn clcbs_300_a() {
    plan_instance(CLCBS_INSTANCE_FILES[4], usize::MAX, true);
}

#[test]
fn clcbs_300_b() {
    plan_instance(CLCBS_INSTANCE_FILES[5], usize::MAX, true);
}

#[test]
fn clcbs_forward_only() {
    // Every agent of the three 10-agent instances plans forwards only as well.
    for name in [
        CLCBS_INSTANCE_FILES[0],
        CLCBS_INSTANCE_FILES[2],
        CLCBS_INSTANCE_FILES[4],
    ] {
        plan_instance(name, usize::MAX, false);
    }
}

#[test]
fn clcbs_forward_only_start_facing_a_wall_has_no_path() {
    // agent45 of ex7 starts 2 m from the top edge heading north: with a 2.5 m turning
    // radius and no reverse it cannot turn without leaving the field.
    let instance = load(CLCBS_INSTANCE_FILES[3]);
    let agent = &instance.agents[45];
    assert_eq!(agent.start, Pose::new(79.0, 98.0, 1.57));
    let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, false);
    let result = plan(
        &instance.field,
        &instance.obstacles,
        &agent.start,
        &agent.goal,
        &settings,
    );
    assert_eq!(result, Err(PlanError::NoPath));
}

#[test]
fn forward_only_paths_never_reverse() {
    let field = Field::new(40.0, 30.0);
    let obstacles = vec![
        Disk::new(12.0, 8.0, 1.0),
        Disk::new(20.0, 15.0, 1.5),
        Disk::new(28.0, 22.0, 1.0),
    ];
    let settings = HybridAStarSettings::new(2.0, 0.5, false);
    for (start, goal) in [
        (Pose::new(2.0, 2.0, 0.0), Pose::new(36.0, 26.0, 0.0)),
        (
            Pose::new(5.0, 15.0, 0.0),
            Pose::new(8.0, 15.0, std::f64::consts::PI),
        ),
        (Pose::new(30.0, 5.0, 1.0), Pose::new(10.0, 25.0, -2.0)),
    ] {
        let path =
            plan(&field, &obstacles, &start, &goal, &settings).unwrap_or_else(|e| panic!("{e}"));
        check_path(
            &field,
            &obstacles,
            &start,
            &goal,
            &settings,
            &path,
            "forward only",
        );
        check_resample(&path, 0.3);
    }
}

#[test]
fn planning_is_deterministic() {
    let instance = load(CLCBS_INSTANCE_FILES[0]);
    let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, true);
    let agent = &instance.agents[1];
    let a = plan(
        &instance.field,
        &instance.obstacles,
        &agent.start,
        &agent.goal,
        &settings,
    );
    let b = plan(
        &instance.field,
        &instance.obstacles,
        &agent.start,
        &agent.goal,
        &settings,
    );
    assert_eq!(a, b);
}

/// A goal walled in by a ring of overlapping obstacles.
fn ring_around(center_x: f64, center_y: f64, ring_radius_m: f64) -> Vec<Disk> {
    let count = (std::f64::consts::TAU * ring_radius_m).ceil() as usize;
    (0..count)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / count as f64;
            Disk::new(
                center_x + ring_radius_m * a.cos(),
                center_y + ring_radius_m * a.sin(),
                0.8,
            )
        })
        .collect()
}

/// The search ends with no path when the goal (or the start) is walled in, with and without
/// reverse. How long that takes is measured in `benches/hybrid_astar.rs`
/// (`hybrid_astar_no_path/enclosed-*`), not asserted here.
#[test]
fn an_enclosed_goal_gives_no_path_quickly() {
    let field = Field::new(100.0, 100.0);
    let obstacles = ring_around(70.0, 70.0, 6.0);
    let start = Pose::new(10.0, 10.0, 0.0);
    let goal = Pose::new(70.0, 70.0, 1.0);
    for allow_reverse in [true, false] {
        let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, allow_reverse);
        assert_eq!(
            plan(&field, &obstacles, &start, &goal, &settings),
            Err(PlanError::NoPath)
        );
        // The reverse: start walled in.
        assert_eq!(
            plan(&field, &obstacles, &goal, &start, &settings),
            Err(PlanError::NoPath)
        );
    }
}

#[test]
fn a_pocket_too_tight_to_turn_in_ends_the_search() {
    // Inside the ring there is room to stand but not to reach the goal heading forwards
    // only: the search must exhaust the pocket and stop. How long that takes is measured
    // in `benches/hybrid_astar.rs` (`hybrid_astar_no_path/tight-pocket-forward`).
    let field = Field::new(20.0, 20.0);
    let obstacles = ring_around(10.0, 10.0, 3.0);
    let settings = HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, false);
    let result = plan(
        &field,
        &obstacles,
        &Pose::new(10.0, 10.0, 0.0),
        &Pose::new(10.0, 10.5, 1.0),
        &settings,
    );
    assert_eq!(result, Err(PlanError::NoPath));
}

#[test]
fn blocked_endpoints_and_bad_settings_are_reported() {
    let field = Field::new(30.0, 30.0);
    let obstacles = vec![Disk::new(10.0, 10.0, 1.0)];
    let settings = HybridAStarSettings::new(2.0, 0.5, true);
    let free = Pose::new(25.0, 25.0, 0.0);
    let inside = Pose::new(10.2, 10.0, 0.0);
    let near = Pose::new(11.3, 10.0, 0.0); // 0.3 m from the boundary: within the clearance
    let outside = Pose::new(0.2, 15.0, 0.0); // within the clearance of the edge
    assert_eq!(
        plan(&field, &obstacles, &inside, &free, &settings),
        Err(PlanError::StartBlocked)
    );
    assert_eq!(
        plan(&field, &obstacles, &near, &free, &settings),
        Err(PlanError::StartBlocked)
    );
    assert_eq!(
        plan(&field, &obstacles, &outside, &free, &settings),
        Err(PlanError::StartBlocked)
    );
    assert_eq!(
        plan(&field, &obstacles, &free, &inside, &settings),
        Err(PlanError::GoalBlocked)
    );
    let nan = Pose::new(f64::NAN, 1.0, 0.0);
    assert_eq!(
        plan(&field, &obstacles, &nan, &free, &settings),
        Err(PlanError::StartBlocked)
    );

    let mut bad = settings.clone();
    bad.turning_radius_m = 0.0;
    assert!(matches!(
        plan(&field, &obstacles, &free, &free, &bad),
        Err(PlanError::InvalidSettings(_))
    ));
    let mut bad = settings.clone();
    bad.reverse_penalty = 0.5;
    assert!(matches!(
        plan(&field, &obstacles, &free, &free, &bad),
        Err(PlanError::InvalidSettings(_))
    ));
    let bad_field = Field::new(-1.0, 10.0);
    assert!(matches!(
        plan(&bad_field, &obstacles, &free, &free, &settings),
        Err(PlanError::InvalidSettings(_))
    ));
}

#[test]
fn the_expansion_limit_is_honoured() {
    let field = Field::new(40.0, 20.0);
    // A wall with a gap far up: the straight shot is blocked, so the search must expand.
    let obstacles: Vec<Disk> = (0..12).map(|i| Disk::new(20.0, i as f64, 0.8)).collect();
    let mut settings = HybridAStarSettings::new(2.0, 0.5, true);
    settings.max_expansions = 10;
    let result = plan(
        &field,
        &obstacles,
        &Pose::new(5.0, 5.0, 0.0),
        &Pose::new(35.0, 5.0, 0.0),
        &settings,
    );
    assert_eq!(result, Err(PlanError::ExpansionLimit { expansions: 10 }));
    settings.max_expansions = 300_000;
    let start = Pose::new(5.0, 5.0, 0.0);
    let goal = Pose::new(35.0, 5.0, 0.0);
    let path = plan(&field, &obstacles, &start, &goal, &settings).unwrap_or_else(|e| panic!("{e}"));
    check_path(&field, &obstacles, &start, &goal, &settings, &path, "wall");
}

#[test]
fn start_equal_to_goal_gives_a_trivial_path() {
    let field = Field::new(10.0, 10.0);
    let pose = Pose::new(5.0, 5.0, 0.3);
    let settings = HybridAStarSettings::new(1.0, 0.5, true);
    let path = plan(&field, &[], &pose, &pose, &settings).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        path.len() >= 2 && path.iter().all(|p| same_pose(p, &pose)),
        "{path:?}"
    );
    assert_eq!(resample(&path, 0.25).len(), 2);
}
