//! The ORCA controller ([`OrcaController`]): exact free moves, safety of every move along its
//! whole segment (by the plain-geometry check with the true radii), the step bound, and
//! the independence from bodies beyond the sensing radius.

use crate::support;

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shared::control::formation::Slot;
use shared::control::orca::OrcaController;
use shared::control::safety::check_move;
use shared::control::vocabulary::{AgentSpec, Body, MAX_WAYPOINTS, Move, MoveStatus};
use shared::geometry::{Disk, DiskGrid, Field, Point, Pose, Vector};

/// The agent's slot is the formation centre itself.
fn spec(radius_m: f64) -> AgentSpec {
    AgentSpec::new(Slot::new(0.0, 0.0), radius_m)
}

fn at(p: &Point) -> Pose {
    Pose::new(p.x, p.y, 0.0)
}

/// The bits of a move's points and its status.
fn bits(mv: &Move) -> (Vec<(u64, u64)>, MoveStatus) {
    let points = [mv.slot, mv.best]
        .iter()
        .chain(&mv.waypoints)
        .map(|p| (p.x.to_bits(), p.y.to_bits()))
        .collect();
    (points, mv.status)
}

#[test]
fn a_free_agent_moves_straight_towards_its_slot_by_at_most_one_step() {
    let field = Field::new(20.0, 20.0);
    let controller = OrcaController::new(field, &[], &spec(0.5), 0.7, Some(3.0));
    let me = Point::new(2.0, 3.0);

    // Far slot: one full step along the straight line.
    let slot = Point::new(12.0, 9.0);
    let mv = controller.plan_move(&at(&slot), &me, &[]);
    assert_eq!(mv.status, MoveStatus::Deviated);
    assert_eq!(mv.waypoints, vec![me, mv.best]);
    let step = mv.best - me;
    assert!((step.norm() - 0.7).abs() <= 1e-12, "step {}", step.norm());
    let towards = (slot - me).normalize();
    assert!((step.normalize() - towards).norm() <= 1e-12);

    // Near slot: onto it, exactly.
    let slot = Point::new(2.3, 3.4);
    let mv = controller.plan_move(&at(&slot), &me, &[]);
    assert_eq!(mv.status, MoveStatus::AtSlot);
    assert_eq!(mv.best, slot);
    assert_eq!(mv.waypoints, vec![me, slot]);

    // At the slot: stays.
    let mv = controller.plan_move(&at(&me), &me, &[]);
    assert_eq!(mv.status, MoveStatus::AtSlot);
    assert_eq!(mv.waypoints, vec![me]);

    // A sensed body off the line, not in the way, changes nothing.
    let aside = Body {
        position: Point::new(2.0, 5.0),
        radius_m: 0.5,
    };
    let slot = Point::new(12.0, 3.0);
    let free = controller.plan_move(&at(&slot), &me, &[]);
    let beside = controller.plan_move(&at(&slot), &me, &[aside]);
    assert_eq!(bits(&free), bits(&beside));
    assert_eq!(beside.best, Point::new(2.7, 3.0));
}

#[test]
fn an_agent_goes_around_an_obstacle_on_its_way_to_the_slot() {
    let field = Field::new(12.0, 10.0);
    // A little off the straight line: exactly head-on, ORCA against a static body is
    // symmetric and only slows the agent down (it stops in front of the obstacle).
    let obstacles = [Disk::new(6.0, 5.1, 1.0)];
    let grid = DiskGrid::new(obstacles.to_vec());
    let controller = OrcaController::new(field, &obstacles, &spec(0.3), 0.25, Some(2.0));
    let slot = Point::new(10.0, 5.0);
    let mut me = Point::new(2.0, 5.0);
    for _ in 0..100 {
        let mv = controller.plan_move(&at(&slot), &me, &[]);
        check_move(&field, &grid, &[], 0.3, &me, &mv.waypoints, MAX_WAYPOINTS)
            .unwrap_or_else(|v| panic!("{v} moving {me} -> {}", mv.best));
        assert!((mv.best - me).norm() <= 0.25 + 1e-9);
        me = mv.best;
        if mv.status == MoveStatus::AtSlot {
            return;
        }
    }
    panic!("did not reach the slot, stopped at {me}");
}

#[test]
fn an_agent_never_leaves_the_field_and_slides_along_its_edge() {
    let field = Field::new(10.0, 10.0);
    let controller = OrcaController::new(field, &[], &spec(0.5), 1.0, None);
    let grid = DiskGrid::new(Vec::new());
    let slot = Point::new(-5.0, 4.0);
    let mut me = Point::new(3.0, 6.0);
    for _ in 0..200 {
        let mv = controller.plan_move(&at(&slot), &me, &[]);
        check_move(&field, &grid, &[], 0.5, &me, &mv.waypoints, MAX_WAYPOINTS)
            .unwrap_or_else(|v| panic!("{v} moving {me} -> {}", mv.best));
        assert!(mv.best.y <= me.y, "{me} -> {}", mv.best);
        me = mv.best;
    }
    // On the inset edge, then along it to the point nearest the slot (the clamped step
    // closes a constant fraction of the gap each turn).
    assert_eq!(me.x, 0.5);
    assert!((me.y - 4.0).abs() <= 1e-9, "{me}");
}

#[test]
fn an_overlapping_agent_stays_put() {
    let field = Field::new(10.0, 10.0);
    let obstacles = [Disk::new(5.0, 5.0, 1.0)];
    let controller = OrcaController::new(field, &obstacles, &spec(0.5), 1.0, Some(3.0));
    let me = Point::new(6.0, 5.0);
    let mv = controller.plan_move(&Pose::new(9.0, 5.0, 0.0), &me, &[]);
    assert_eq!(mv.status, MoveStatus::Stayed);
    assert_eq!(mv.waypoints, vec![me]);
}

#[test]
fn bodies_that_are_not_finite_do_not_make_orca_panic() {
    let field = Field::new(10.0, 10.0);
    let controller = OrcaController::new(field, &[], &spec(0.5), 1.0, None);
    let me = Point::new(3.0, 3.0);
    let others = [
        Body {
            position: Point::new(f64::NAN, 3.0),
            radius_m: 0.5,
        },
        Body {
            position: Point::new(f64::INFINITY, 3.0),
            radius_m: 0.5,
        },
        Body {
            position: Point::new(4.0, 4.5),
            radius_m: f64::NAN,
        },
    ];
    let mv = controller.plan_move(&Pose::new(8.0, 3.0, 0.0), &me, &others);
    assert_eq!(mv.waypoints[0], me);
    assert!(mv.best.x.is_finite() && mv.best.y.is_finite());
}

/// A random world with one moving agent in a safe state.
#[derive(Debug)]
struct World {
    field: Field,
    obstacles: Vec<Disk>,
    others: Vec<Body>,
    radius_m: f64,
    max_step_m: f64,
    sensing_radius_m: Option<f64>,
    start: Point,
}

/// Clearance of a body of radius `radius_m` at `p` (negative when overlapping).
fn point_clearance_m(w: &World, p: &Point) -> f64 {
    let mut c = w.field.signed_inset_m(p) - w.radius_m;
    for d in &w.obstacles {
        c = c.min((p - d.centre).norm() - d.radius_m - w.radius_m);
    }
    for o in &w.others {
        c = c.min((p - o.position).norm() - o.radius_m - w.radius_m);
    }
    c
}

/// A random field, obstacles, other agents, step and sensing radius (longer than a step
/// by at least 1 cm, or none), and a safe start: a random free point, often one touching
/// an obstacle, another agent or an edge exactly. When the bodies leave no room (rare),
/// they are dropped and the agent starts mid-field.
fn world(seed: u64) -> World {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let field = Field::new(rng.random_range(4.0..30.0), rng.random_range(4.0..30.0));
    let radius_m = rng.random_range(0.1..1.0);
    let (obstacles, others) = support::random_bodies(&mut rng, &field);
    let max_step_m = rng.random_range(0.05..2.0);
    let sensing_radius_m = if rng.random_range(0..5) == 0 {
        None
    } else {
        Some(max_step_m + 0.01 + rng.random_range(0.0..4.0))
    };
    let mut w = World {
        field,
        obstacles,
        others,
        radius_m,
        max_step_m,
        sensing_radius_m,
        start: Point::origin(),
    };
    // Safe, as the invariant has it (touching within rounding is safe).
    let start = support::draw_start(&mut rng, &field, &w.obstacles, &w.others, radius_m, |p| {
        point_clearance_m(&w, p) >= -1e-12
    });
    if let Some(p) = start {
        w.start = p;
        return w;
    }
    w.obstacles.clear();
    w.others.clear();
    w.start = Point::new(0.5 * field.width_m, 0.5 * field.height_m);
    w
}

fn controller(w: &World, obstacles: &[Disk]) -> OrcaController {
    OrcaController::new(
        w.field,
        obstacles,
        &spec(w.radius_m),
        w.max_step_m,
        w.sensing_radius_m,
    )
}

/// A random formation centre around the field.
fn random_centre(rng: &mut ChaCha8Rng, field: &Field) -> Pose {
    Pose::new(
        rng.random_range(-5.0..field.width_m + 5.0),
        rng.random_range(-5.0..field.height_m + 5.0),
        0.0,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// From a random safe state, fifteen consecutive moves towards random slots pass the
    /// safety check with the true radii, start at the agent, end at `best`, and are no
    /// longer than one step.
    #[test]
    fn orca_moves_are_safe_and_at_most_one_step(seed in any::<u64>()) {
        let w = world(seed);
        let controller = controller(&w, &w.obstacles);
        let grid = DiskGrid::new(w.obstacles.clone());
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0dca);
        let mut me = w.start;
        for step in 0..15 {
            let centre = random_centre(&mut rng, &w.field);
            let mv = controller.plan_move(&centre, &me, &w.others);
            prop_assert_eq!(mv.waypoints[0], me);
            prop_assert_eq!(mv.waypoints.last().copied(), Some(mv.best));
            let verdict = check_move(&w.field, &grid, &w.others, w.radius_m, &me,
                &mv.waypoints, MAX_WAYPOINTS);
            prop_assert!(verdict.is_ok(), "step {}: {:?} moving {} -> {}",
                step, verdict, me, mv.best);
            let step_m = (mv.best - me).norm();
            prop_assert!(step_m <= w.max_step_m + 1e-9, "step {step}: {step_m} m");
            // Same inputs, same bits.
            prop_assert_eq!(bits(&mv), bits(&controller.plan_move(&centre, &me, &w.others)));
            me = mv.best;
        }
    }

    /// Bodies whose disks lie beyond `sensing_radius_m + radius_m` of the agent do not
    /// change its move, to the bit: adding a far obstacle and a far agent, and removing
    /// every far body of the world.
    #[test]
    fn far_bodies_do_not_change_the_move(seed in any::<u64>()) {
        let w = world(seed);
        let Some(sensing_m) = w.sensing_radius_m else {
            return Ok(());
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xfa5);
        let centre = random_centre(&mut rng, &w.field);
        let me = w.start;
        let far_m = sensing_m + w.radius_m;
        let is_far = |c: &Point, r: f64| (c - me).norm() - r > far_m;
        let mv = controller(&w, &w.obstacles).plan_move(&centre, &me, &w.others);

        let mut away = |r: f64| {
            let angle = rng.random_range(0.0..std::f64::consts::TAU);
            let gap_m = far_m + rng.random_range(1e-3..5.0);
            me + (r + gap_m) * Vector::new(angle.cos(), angle.sin())
        };
        let far_obstacle = Disk { centre: away(1.5), radius_m: 1.5 };
        let far_other = Body { position: away(0.4), radius_m: 0.4 };
        let mut more_obstacles = w.obstacles.clone();
        more_obstacles.insert(rng.random_range(0..=w.obstacles.len()), far_obstacle);
        let mut more_others = w.others.clone();
        more_others.insert(rng.random_range(0..=w.others.len()), far_other);
        let more = controller(&w, &more_obstacles).plan_move(&centre, &me, &more_others);
        prop_assert_eq!(bits(&mv), bits(&more), "adding far bodies changed the move");

        let near_obstacles: Vec<Disk> = w.obstacles.iter().copied()
            .filter(|d| !is_far(&d.centre, d.radius_m)).collect();
        let near_others: Vec<Body> = w.others.iter().copied()
            .filter(|b| !is_far(&b.position, b.radius_m)).collect();
        let fewer = controller(&w, &near_obstacles).plan_move(&centre, &me, &near_others);
        prop_assert_eq!(bits(&mv), bits(&fewer), "removing far bodies changed the move");
    }
}

/// ORCA's own model reads RVO2's settings from `[orca]` (defaults 5 steps, 20
/// neighbours), and they reach the agents: another time horizon gives another run, as
/// safe.
#[test]
fn the_orca_table_sets_rvo2s_parameters_of_its_own_model() {
    let file = std::path::PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/dense-orca.toml"
    ));
    let text = std::fs::read_to_string(&file).expect("dense-orca.toml");
    let default =
        shared::world::scenario::Scenario::parse(&text, "dense-orca.toml").expect("loads");
    assert_eq!(default.controller.orca.time_horizon_steps, 5.0);
    assert_eq!(default.controller.orca.max_neighbours, 20);
    let short = format!("{text}\n[orca]\ntime_horizon_steps = 2.0\nmax_neighbours = 3\n");
    let short = shared::world::scenario::Scenario::parse(&short, "short.toml").expect("loads");
    assert_eq!(short.controller.orca.time_horizon_steps, 2.0);
    assert_eq!(short.controller.orca.max_neighbours, 3);
    let (a, b) = (
        shared::run::simulate::simulate(&default).expect("runs"),
        shared::run::simulate::simulate(&short).expect("runs"),
    );
    assert_eq!(a.summary().collisions, 0);
    assert_eq!(b.summary().collisions, 0);
    assert_ne!(a.steps, b.steps, "the horizon changed nothing");
}

/// In ORCA's own model every agent moves at once, at a constant speed along its move:
/// at every instant of every step of dense-orca, every two agents stand at least their
/// radii apart (the recorder refuses moves that would meet at the same time).
#[test]
fn in_its_own_model_no_two_agents_meet_at_any_instant() {
    let file = std::path::PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/dense-orca.toml"
    ));
    let scenario = shared::world::scenario::Scenario::load(&file).expect("dense-orca.toml");
    assert_eq!(
        scenario.turns,
        shared::control::vocabulary::TurnMode::Simultaneous
    );
    let run = shared::run::simulate::simulate(&scenario).expect("runs");
    let mut crossings = 0;
    for step in &run.steps[1..] {
        for (i, a) in step.agents.iter().enumerate() {
            for (j, b) in step.agents.iter().enumerate().take(i) {
                let reach_m = scenario.agents[i].radius_m + scenario.agents[j].radius_m;
                let d = shared::geometry::distance_at_the_same_time_m(&a.waypoints, &b.waypoints);
                assert!(
                    d >= reach_m - shared::control::safety::SAFETY_TOLERANCE_M,
                    "step {}: agents {i} and {j} come within {d} m at once",
                    step.step
                );
                if shared::geometry::distance_polyline_polyline(&a.waypoints, &b.waypoints)
                    < reach_m
                {
                    crossings += 1;
                }
            }
        }
    }
    // The check is the one of the model, not the stricter one of parallel groups.
    assert!(crossings > 0, "no two moves of the run crossed paths");
}
