//! Online replanning on the CL-CBS obstacle fields: [`Replanner`] after obstacles were
//! added on the path, against [`plan`] from scratch, its determinism and its errors; and
//! [`first_blocked_pose`] against a brute-force scan. Every returned path is checked by
//! brute force, independently of the planner's own collision checks.

use std::path::PathBuf;

use proptest::prelude::*;
use shared::geometry::{Disk, Field, Pose, distance_point_segment};
use shared::paths::hybrid_astar::{
    HybridAStarSettings, PlanError, Replanner, first_blocked_pose, path_length_m, plan,
};
use testkit::clcbs::{CLCBS_DIR_ENV, CLCBS_OBSTACLE_RADIUS_M, ClcbsInstance, default_clcbs_dir};

const TURNING_RADIUS_M: f64 = 2.5;
const CLEARANCE_M: f64 = 0.5;

/// (instance file, agent index): the hard cases of `benches/hybrid_astar.rs`, plus more.
const CASES: [(&str, usize); 5] = [
    ("map_50by50_obst25_agents10_ex0.yaml", 9),
    ("map_100by100_obst50_agents10_ex0.yaml", 5),
    ("map_100by100_obst50_agents50_ex7.yaml", 1),
    ("map_300by300_obst100_agents10_ex0.yaml", 4),
    ("map_300by300_obst100_agents100_ex2.yaml", 50),
];

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

fn settings() -> HybridAStarSettings {
    HybridAStarSettings::new(TURNING_RADIUS_M, CLEARANCE_M, true)
}

/// The path begins with `start` and ends with `goal` exactly, and every pose and chord
/// keeps the clearance from every obstacle and the field's edges.
fn check_path(field: &Field, obstacles: &[Disk], start: &Pose, goal: &Pose, path: &[Pose]) {
    assert!(path.len() >= 2, "path too short");
    assert_eq!(path[0], *start, "the path begins at the start");
    assert_eq!(path[path.len() - 1], *goal, "the path ends at the goal");
    let c = CLEARANCE_M;
    for (i, p) in path.iter().enumerate() {
        let q = p.position();
        assert!(
            q.x >= c - 1e-9
                && q.y >= c - 1e-9
                && q.x <= field.width_m - c + 1e-9
                && q.y <= field.height_m - c + 1e-9,
            "pose {i} {p:?} leaves the field inset by {c}"
        );
    }
    for (i, w) in path.windows(2).enumerate() {
        let (a, b) = (w[0].position(), w[1].position());
        for d in obstacles {
            let clearance = distance_point_segment(&d.centre, &a, &b) - d.radius_m;
            assert!(
                clearance >= c - 1e-9,
                "chord {i} is {clearance} m from {d:?}"
            );
        }
    }
}

/// The brute-force answer [`first_blocked_pose`] must give.
fn first_blocked_brute_force(
    field: &Field,
    path: &[Pose],
    obstacles: &[Disk],
    clearance_m: f64,
) -> Option<usize> {
    path.iter().position(|p| {
        let q = p.position();
        let inside = q.x >= clearance_m
            && q.y >= clearance_m
            && q.x <= field.width_m - clearance_m
            && q.y <= field.height_m - clearance_m;
        !inside
            || obstacles
                .iter()
                .any(|d| (q - d.centre).norm() < d.radius_m + clearance_m)
    })
}

/// `count` CL-CBS-sized obstacles centred on `path` evenly after pose `from`, none within
/// reach of the start pose `path[from]` or the goal.
fn obstacles_on_path(path: &[Pose], from: usize, count: usize) -> Vec<Disk> {
    let keep_off_m = CLCBS_OBSTACLE_RADIUS_M + CLEARANCE_M + 0.5;
    let (start, goal) = (path[from].position(), path[path.len() - 1].position());
    let remaining = path.len() - from;
    (1..=count)
        .map(|k| {
            let mut i = from + remaining * k / (count + 1);
            // Slide towards the middle until clear of the start and the goal.
            while (path[i].position() - start).norm() < keep_off_m {
                i += 1;
            }
            while (path[i].position() - goal).norm() < keep_off_m {
                i -= 1;
            }
            let p = path[i].position();
            Disk::new(p.x, p.y, CLCBS_OBSTACLE_RADIUS_M)
        })
        .collect()
}

#[test]
fn replan_after_obstacles_added_on_the_path_avoids_them() {
    let settings = settings();
    for (file, agent) in CASES {
        let instance = load(file);
        let agent = &instance.agents[agent];
        let what = format!("{file} agent {}", agent.name);
        let mut replanner = Replanner::new(instance.field, agent.goal, settings.clone())
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let first = replanner
            .plan_from(&agent.start, &instance.obstacles)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        check_path(
            &instance.field,
            &instance.obstacles,
            &agent.start,
            &agent.goal,
            &first,
        );
        assert_eq!(
            first_blocked_pose(&instance.field, &first, &instance.obstacles, CLEARANCE_M),
            None,
            "{what}: the first path is clear"
        );

        let here_index = first.len() / 3;
        let here = first[here_index];
        let added = obstacles_on_path(&first, here_index, 3);
        let mut obstacles = instance.obstacles.clone();
        obstacles.extend_from_slice(&added);
        let blocked = first_blocked_pose(&instance.field, &first, &obstacles, CLEARANCE_M)
            .unwrap_or_else(|| panic!("{what}: the added obstacles block the old path"));
        assert!(blocked > here_index, "{what}: blocked at {blocked}");

        let replanned = replanner
            .plan_from(&here, &obstacles)
            .unwrap_or_else(|e| panic!("{what}: replanning: {e}"));
        check_path(&instance.field, &obstacles, &here, &agent.goal, &replanned);
        assert_eq!(
            first_blocked_pose(&instance.field, &replanned, &obstacles, CLEARANCE_M),
            None,
            "{what}: the new path is clear"
        );
        // The incrementally updated heuristic gives the very path of a plan from scratch.
        let scratch = plan(&instance.field, &obstacles, &here, &agent.goal, &settings)
            .unwrap_or_else(|e| panic!("{what}: plan: {e}"));
        assert_eq!(replanned, scratch, "{what}: replan != plan from scratch");
        eprintln!(
            "{what}: {:.1} m first, {:.1} m replanned from pose {here_index}",
            path_length_m(&first),
            path_length_m(&replanned)
        );
    }
}

#[test]
fn replan_with_the_same_obstacles_as_plan_gives_the_same_path() {
    let settings = settings();
    for (file, _) in CASES {
        let instance = load(file);
        // One replanner per goal, asked from every other agent's start too.
        for goal_agent in instance.agents.iter().take(3) {
            let mut replanner =
                Replanner::new(instance.field, goal_agent.goal, settings.clone()).unwrap();
            for start_agent in instance.agents.iter().take(4) {
                let what = format!("{file}: {} to {}'s goal", start_agent.name, goal_agent.name);
                let expected = plan(
                    &instance.field,
                    &instance.obstacles,
                    &start_agent.start,
                    &goal_agent.goal,
                    &settings,
                );
                let got = replanner.plan_from(&start_agent.start, &instance.obstacles);
                match (&expected, &got) {
                    (Ok(e), Ok(g)) => {
                        check_path(
                            &instance.field,
                            &instance.obstacles,
                            &start_agent.start,
                            &goal_agent.goal,
                            g,
                        );
                        let (le, lg) = (path_length_m(e), path_length_m(g));
                        assert!(
                            (lg - le).abs() <= 0.03 * le,
                            "{what}: {lg} m replanned, {le} m planned"
                        );
                        assert_eq!(e, g, "{what}");
                    }
                    _ => assert_eq!(expected, got, "{what}"),
                }
            }
        }
    }
}

#[test]
fn replan_rebuilds_when_obstacles_are_removed_or_reordered() {
    let settings = settings();
    let (file, agent) = CASES[1];
    let instance = load(file);
    let agent = &instance.agents[agent];
    let mut replanner = Replanner::new(instance.field, agent.goal, settings.clone()).unwrap();
    let first = replanner
        .plan_from(&agent.start, &instance.obstacles)
        .unwrap();
    let here = first[first.len() / 3];
    let mut with_added = instance.obstacles.clone();
    with_added.extend(obstacles_on_path(&first, first.len() / 3, 3));
    let mut reversed = with_added.clone();
    reversed.reverse();
    let fewer = &with_added[..with_added.len() - 2];
    let removed_first = &with_added[1..];
    // Grow, then shrink, reorder, grow again: each answer is plan()'s.
    for obstacles in [
        &with_added[..],
        fewer,
        &reversed[..],
        removed_first,
        &with_added[..],
        &with_added[..],
    ] {
        let expected = plan(&instance.field, obstacles, &here, &agent.goal, &settings).unwrap();
        let got = replanner.plan_from(&here, obstacles).unwrap();
        check_path(&instance.field, obstacles, &here, &agent.goal, &got);
        assert_eq!(got, expected, "{} obstacles", obstacles.len());
    }
}

#[test]
fn repeated_calls_are_deterministic() {
    let settings = settings();
    let (file, agent) = CASES[3];
    let instance = load(file);
    let agent = &instance.agents[agent];
    let run = || {
        let mut replanner = Replanner::new(instance.field, agent.goal, settings.clone()).unwrap();
        let mut obstacles = instance.obstacles.clone();
        let mut path = replanner.plan_from(&agent.start, &obstacles).unwrap();
        let mut paths = vec![path.clone()];
        // Three rounds: move a sixth of the way, an obstacle appears ahead, replan.
        for _ in 0..3 {
            let here_index = path.len() / 6;
            obstacles.extend(obstacles_on_path(&path, here_index, 1));
            let here = path[here_index];
            path = replanner.plan_from(&here, &obstacles).unwrap();
            // The same question twice gives the same answer.
            assert_eq!(replanner.plan_from(&here, &obstacles).unwrap(), path);
            paths.push(path.clone());
        }
        paths
    };
    let (a, b) = (run(), run());
    assert_eq!(a.len(), 4);
    for (i, (pa, pb)) in a.iter().zip(&b).enumerate() {
        let bits = |p: &[Pose]| -> Vec<[u64; 3]> {
            p.iter()
                .map(|q| [q.x_m.to_bits(), q.y_m.to_bits(), q.heading_rad.to_bits()])
                .collect()
        };
        assert_eq!(bits(pa), bits(pb), "path {i} differs between runs");
    }
}

#[test]
fn walled_in_start_has_no_path() {
    let settings = settings();
    let (file, agent) = CASES[1];
    let instance = load(file);
    let agent = &instance.agents[agent];
    let mut replanner = Replanner::new(instance.field, agent.goal, settings.clone()).unwrap();
    let first = replanner
        .plan_from(&agent.start, &instance.obstacles)
        .unwrap();
    // A ring of overlapping disks, 4 m around a pose a third of the way.
    let here = first[first.len() / 3];
    let mut obstacles = instance.obstacles.clone();
    let ring_m = 4.0;
    let count = 48;
    obstacles.extend((0..count).map(|k| {
        let a = std::f64::consts::TAU * k as f64 / count as f64;
        Disk::new(
            here.x_m + ring_m * a.cos(),
            here.y_m + ring_m * a.sin(),
            CLCBS_OBSTACLE_RADIUS_M,
        )
    }));
    assert_eq!(
        replanner.plan_from(&here, &obstacles),
        Err(PlanError::NoPath)
    );
    assert_eq!(
        plan(&instance.field, &obstacles, &here, &agent.goal, &settings),
        Err(PlanError::NoPath)
    );
    // Still fine from outside the ring, with the same (updated) heuristic.
    let path = replanner.plan_from(&agent.start, &obstacles).unwrap();
    check_path(
        &instance.field,
        &obstacles,
        &agent.start,
        &agent.goal,
        &path,
    );
}

#[test]
fn replan_reports_blocked_start_goal_and_bad_input() {
    let field = Field::new(40.0, 30.0);
    let goal = Pose::new(35.0, 15.0, 0.0);
    let mut replanner = Replanner::new(field, goal, settings()).unwrap();
    let start = Pose::new(5.0, 15.0, 0.0);
    assert_eq!(
        replanner.plan_from(&start, &[Disk::new(5.0, 15.5, 0.8)]),
        Err(PlanError::StartBlocked)
    );
    assert_eq!(
        replanner.plan_from(&start, &[Disk::new(35.0, 14.0, 0.8)]),
        Err(PlanError::GoalBlocked)
    );
    assert!(matches!(
        replanner.plan_from(&start, &[Disk::new(f64::NAN, 1.0, 0.8)]),
        Err(PlanError::InvalidSettings(_))
    ));
    assert!(matches!(
        Replanner::new(field, goal, HybridAStarSettings::new(-1.0, 0.5, true)),
        Err(PlanError::InvalidSettings(_))
    ));
    assert!(matches!(
        Replanner::new(Field::new(0.0, 10.0), goal, settings()),
        Err(PlanError::InvalidSettings(_))
    ));
    assert_eq!(
        Replanner::new(field, Pose::new(f64::INFINITY, 1.0, 0.0), settings()).err(),
        Some(PlanError::GoalBlocked)
    );
    // Blocked once, fine again afterwards.
    let path = replanner.plan_from(&start, &[]).unwrap();
    assert_eq!((path[0], path[path.len() - 1]), (start, goal));
}

#[test]
fn first_blocked_pose_on_a_planned_path() {
    let (file, agent) = CASES[4];
    let instance = load(file);
    let agent = &instance.agents[agent];
    let path = plan(
        &instance.field,
        &instance.obstacles,
        &agent.start,
        &agent.goal,
        &settings(),
    )
    .unwrap();
    let field = &instance.field;
    assert_eq!(
        first_blocked_pose(field, &path, &instance.obstacles, CLEARANCE_M),
        None
    );
    let mut obstacles = instance.obstacles.clone();
    obstacles.extend(obstacles_on_path(&path, path.len() / 2, 2));
    let found = first_blocked_pose(field, &path, &obstacles, CLEARANCE_M);
    assert_eq!(
        found,
        first_blocked_brute_force(field, &path, &obstacles, CLEARANCE_M)
    );
    let found = found.expect("blocked");
    assert!(found > path.len() / 2 && found < path.len() - 1, "{found}");
    // The first pose is checked too, and so are the field's edges.
    assert_eq!(first_blocked_pose(field, &path, &obstacles, 1e6), Some(0));
}

/// A random walk of poses, which may leave the field, with random obstacles.
fn path_and_obstacles() -> impl Strategy<Value = (Vec<Pose>, Vec<Disk>, f64)> {
    let start = (-2.0..52.0f64, -2.0..32.0f64);
    let steps = prop::collection::vec((-0.6..0.6f64, 0.05..1.0f64), 0..200);
    let obstacles = prop::collection::vec((-5.0..55.0f64, -5.0..35.0f64, 0.0..3.0f64), 0..6);
    (start, steps, obstacles, 0.0..1.5f64).prop_map(|((x, y), steps, obstacles, clearance_m)| {
        let mut pose = Pose::new(x, y, 0.3);
        let mut path = Vec::with_capacity(steps.len());
        for (turn_rad, step_m) in steps {
            path.push(pose);
            let h = pose.heading_rad + turn_rad;
            pose = Pose::new(pose.x_m + step_m * h.cos(), pose.y_m + step_m * h.sin(), h);
        }
        let obstacles = obstacles
            .into_iter()
            .map(|(x, y, r)| Disk::new(x, y, r))
            .collect();
        (path, obstacles, clearance_m)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn first_blocked_pose_matches_brute_force((path, obstacles, clearance_m) in path_and_obstacles()) {
        let field = Field::new(50.0, 30.0);
        prop_assert_eq!(
            first_blocked_pose(&field, &path, &obstacles, clearance_m),
            first_blocked_brute_force(&field, &path, &obstacles, clearance_m)
        );
    }
}
