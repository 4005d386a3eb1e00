//! Scenarios of the CBF-QP mode: the head-on deadlock and the slide around an obstacle,
//! the paper's failed LogSumExp barrier breaking the invariant where the CBF does not,
//! and bit-for-bit determinism.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shared::control::cbf::{CbfController, ZcbfLogSumExpController, is_deadlocked, solve_qp_2d};
use shared::control::formation::Slot;
use shared::control::safety::check_move;
use shared::control::vocabulary::{
    AgentSpec, Body, CbfSettings, DEFAULT_LSE_SHARPNESS_PER_M, MAX_WAYPOINTS, Move, MoveStatus,
};
use shared::geometry::{Disk, DiskGrid, Field, Point, Pose, Vector, distance_point_segment};

/// An agent whose slot is the formation centre itself, so the centre pose is the slot.
fn spec(radius_m: f64) -> AgentSpec {
    AgentSpec::new(Slot::new(0.0, 0.0), radius_m)
}

fn at(p: Point) -> Pose {
    Pose::new(p.x, p.y, 0.0)
}

/// Smallest clearance (distance minus radii, or inset minus radius for the field edges)
/// along the segment `a`-`b`, by brute force over every disk and body: the exact
/// point-segment distance and 1000 samples.
fn segment_clearance_m(
    field: &Field,
    obstacles: &[Disk],
    others: &[Body],
    radius_m: f64,
    a: &Point,
    b: &Point,
) -> f64 {
    let disks = obstacles
        .iter()
        .map(|d| (d.centre, d.radius_m))
        .chain(others.iter().map(|o| (o.position, o.radius_m)));
    let mut worst = f64::INFINITY;
    for (c, r) in disks {
        worst = worst.min(distance_point_segment(&c, a, b) - r - radius_m);
        for i in 0..=1000 {
            let p = a + (i as f64 / 1000.0) * (b - a);
            worst = worst.min((p - c).norm() - r - radius_m);
        }
    }
    for p in [a, b] {
        worst = worst.min(field.signed_inset_m(p) - radius_m);
    }
    worst
}

fn move_clearance_m(
    field: &Field,
    obstacles: &[Disk],
    others: &[Body],
    radius_m: f64,
    mv: &Move,
) -> f64 {
    let segments: Vec<(Point, Point)> = if mv.waypoints.len() == 1 {
        vec![(mv.waypoints[0], mv.waypoints[0])]
    } else {
        mv.waypoints.windows(2).map(|w| (w[0], w[1])).collect()
    };
    segments
        .iter()
        .map(|(a, b)| segment_clearance_m(field, obstacles, others, radius_m, a, b))
        .fold(f64::INFINITY, f64::min)
}

/// The settings of the plain filter: the defaults without the deadlock escape.
fn plain() -> CbfSettings {
    CbfSettings {
        deadlock_escape: false,
        ..CbfSettings::default()
    }
}

/// The plain filter deadlocks head-on; with the deadlock escape (the default) the same
/// agent goes round the obstacle to its slot, as safely.
#[test]
fn head_on_the_cbf_agent_stops_in_front_of_the_obstacle_and_deadlocks() {
    let field = Field::new(30.0, 20.0);
    let obstacles = [Disk::new(15.0, 10.0, 1.0)];
    let radius_m = 0.3;
    let controller = CbfController::new(field, &obstacles, &spec(radius_m), plain())
        .expect("default settings are valid");
    let slot = Point::new(25.0, 10.0);
    let mut me = Point::new(5.0, 10.0);
    let mut deadlocked_at = None;
    for step in 0..60 {
        let mv = controller.plan_move(&at(slot), &me, &[]);
        assert!(move_clearance_m(&field, &obstacles, &[], radius_m, &mv) >= 0.0);
        check_move(
            &field,
            &DiskGrid::new(obstacles.to_vec()),
            &[],
            radius_m,
            &me,
            &mv.waypoints,
            MAX_WAYPOINTS,
        )
        .expect("the safety check passes");
        assert_eq!(mv.best.y, 10.0, "a head-on approach stays on the axis");
        if is_deadlocked(&mv, &me) && deadlocked_at.is_none() {
            deadlocked_at = Some(step);
        }
        me = mv.best;
    }
    let clearance_m = 15.0 - me.x - 1.0 - radius_m;
    assert!(
        me.x < 15.0 && (0.0..1e-5).contains(&clearance_m),
        "stopped just in front: x = {}, clearance {clearance_m}",
        me.x
    );
    let step = deadlocked_at.expect("the agent deadlocks");
    assert!(step < 30, "deadlocked at step {step}");
    let last = controller.plan_move(&at(slot), &me, &[]);
    assert!(is_deadlocked(&last, &me));
    assert_ne!(last.status, MoveStatus::AtSlot);

    let escaping =
        CbfController::new(field, &obstacles, &spec(radius_m), CbfSettings::default()).unwrap();
    let mut me = Point::new(5.0, 10.0);
    let reached = (0..60).any(|_| {
        let mv = escaping.plan_move(&at(slot), &me, &[]);
        assert!(move_clearance_m(&field, &obstacles, &[], radius_m, &mv) >= 0.0);
        me = mv.best;
        mv.status == MoveStatus::AtSlot
    });
    assert!(
        reached,
        "with the escape it reaches its slot, not stuck at {me}"
    );
}

#[test]
fn off_axis_the_cbf_agent_slides_around_the_obstacle_to_its_slot() {
    let field = Field::new(30.0, 20.0);
    let obstacles = [Disk::new(15.0, 10.0, 1.0)];
    let radius_m = 0.3;
    let controller =
        CbfController::new(field, &obstacles, &spec(radius_m), CbfSettings::default()).unwrap();
    let slot = Point::new(25.0, 10.2);
    let mut me = Point::new(5.0, 10.0);
    let mut min_clearance_m = f64::INFINITY;
    let mut reached = None;
    for step in 0..200 {
        let mv = controller.plan_move(&at(slot), &me, &[]);
        min_clearance_m =
            min_clearance_m.min(move_clearance_m(&field, &obstacles, &[], radius_m, &mv));
        me = mv.best;
        if mv.status == MoveStatus::AtSlot {
            reached = Some(step);
            break;
        }
    }
    assert!(min_clearance_m >= 0.0, "clearance {min_clearance_m}");
    assert!(reached.is_some(), "never reached the slot, stuck at {me}");
}

/// The paper's failure, on a plain stepping loop (no safety monitor): obstacles B and A
/// in a row, the agent between them, 0.3 m from B and 0.6 m from A, its slot beyond A.
/// With default settings (the ones that make the CBF safe), B dominates the LogSumExp
/// weights, so moving away from B pays for rushing at A: the single barrier constraint
/// allows the full-speed step of 1 m, which ends 0.4 m deep inside A.
#[test]
fn the_logsumexp_barrier_overshoots_into_an_obstacle_where_the_cbf_does_not() {
    let field = Field::new(30.0, 20.0);
    let obstacles = [Disk::new(10.0, 10.0, 1.0), Disk::new(13.5, 10.0, 1.0)];
    let radius_m = 0.3;
    let start = Point::new(11.6, 10.0);
    let slot = Point::new(20.0, 10.0);
    let settings = CbfSettings::default();
    let lse = ZcbfLogSumExpController::new(
        field,
        &obstacles,
        &spec(radius_m),
        settings,
        DEFAULT_LSE_SHARPNESS_PER_M,
    )
    .unwrap();
    // The plain filter, like for like with the LogSumExp barrier (which has no escape).
    let cbf = CbfController::new(field, &obstacles, &spec(radius_m), plain()).unwrap();

    let run = |plan: &dyn Fn(&Point) -> Move| -> (f64, Point) {
        let mut me = start;
        let mut min_clearance_m = f64::INFINITY;
        for _ in 0..30 {
            let mv = plan(&me);
            min_clearance_m =
                min_clearance_m.min(move_clearance_m(&field, &obstacles, &[], radius_m, &mv));
            me = mv.best;
        }
        (min_clearance_m, me)
    };
    let (lse_clearance_m, _) = run(&|me| lse.plan_move(&at(slot), me, &[]));
    let (cbf_clearance_m, cbf_end) = run(&|me| cbf.plan_move(&at(slot), me, &[]));
    assert!(
        lse_clearance_m < -0.1,
        "the LogSumExp barrier should enter obstacle A, min clearance {lse_clearance_m}"
    );
    assert!(
        cbf_clearance_m >= 0.0,
        "the CBF never does, min clearance {cbf_clearance_m}"
    );
    assert!(cbf_end.x < 13.5, "the CBF agent stays on the near side");

    // The first LogSumExp step on its own: full speed straight into A.
    let first = lse.plan_move(&at(slot), &start, &[]);
    assert!((first.best - Point::new(12.6, 10.0)).norm() < 1e-12);
    let (h, _) = lse.barrier(&first.best, &[]).unwrap();
    assert!(h < 0.0, "the barrier overshot zero: h = {h}");
}

/// How often the comparison sees it: agents cross random obstacle fields towards random
/// slots, each controller in a plain stepping loop; the LogSumExp barrier breaks the
/// invariant on some runs, the CBF on none.
#[test]
fn across_random_fields_only_the_logsumexp_barrier_breaks_the_invariant() {
    let mut rng = ChaCha8Rng::seed_from_u64(0xcbf);
    let field = Field::new(30.0, 20.0);
    let radius_m = 0.3;
    let settings = CbfSettings::default();
    let (mut runs, mut lse_violating_runs, mut cbf_steps) = (0, 0, 0);
    for _ in 0..40 {
        let obstacles: Vec<Disk> = (0..25)
            .map(|_| {
                Disk::new(
                    4.0 + 22.0 * rng.random::<f64>(),
                    2.0 + 16.0 * rng.random::<f64>(),
                    0.5 + rng.random::<f64>(),
                )
            })
            .collect();
        let free = |p: &Point| {
            obstacles
                .iter()
                .all(|d| (p - d.centre).norm() >= d.radius_m + radius_m + 0.01)
        };
        let start = Point::new(2.5, 3.0 + 14.0 * rng.random::<f64>());
        let slot = Point::new(29.0, 2.0 + 16.0 * rng.random::<f64>());
        if !free(&start) {
            continue;
        }
        runs += 1;
        let lse = ZcbfLogSumExpController::new(
            field,
            &obstacles,
            &spec(radius_m),
            settings,
            DEFAULT_LSE_SHARPNESS_PER_M,
        )
        .unwrap();
        let cbf = CbfController::new(field, &obstacles, &spec(radius_m), settings).unwrap();
        let (mut me_lse, mut me_cbf, mut violated) = (start, start, false);
        for _ in 0..60 {
            cbf_steps += 1;
            let mv = cbf.plan_move(&at(slot), &me_cbf, &[]);
            let c = move_clearance_m(&field, &obstacles, &[], radius_m, &mv);
            assert!(c >= 0.0, "the CBF broke the invariant: clearance {c}");
            me_cbf = mv.best;
            if !violated {
                let mv = lse.plan_move(&at(slot), &me_lse, &[]);
                if move_clearance_m(&field, &obstacles, &[], radius_m, &mv) < 0.0 {
                    // The monitor would reject it; stop following this run.
                    violated = true;
                }
                me_lse = mv.best;
            }
        }
        lse_violating_runs += violated as usize;
    }
    eprintln!(
        "LogSumExp barrier: {lse_violating_runs} of {runs} runs broke the invariant; \
         CBF: none in {cbf_steps} steps"
    );
    assert!(runs >= 20);
    assert!(lse_violating_runs > 0);
}

/// With a single neighbour in sight the LogSumExp barrier is the plain distance
/// `||x - s|| - R`, convex, and the first-order condition bounds it along the step: safe.
/// The failure needs two or more neighbours.
#[test]
fn with_a_single_neighbour_the_logsumexp_barrier_is_safe() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5afe);
    let field = Field::new(100.0, 100.0);
    let obstacles = [Disk::new(50.0, 50.0, 1.0)];
    let radius_m = 0.3;
    let lse = ZcbfLogSumExpController::new(
        field,
        &obstacles,
        &spec(radius_m),
        CbfSettings::default(),
        DEFAULT_LSE_SHARPNESS_PER_M,
    )
    .unwrap();
    for _ in 0..200 {
        let angle = std::f64::consts::TAU * rng.random::<f64>();
        let direction = Vector::new(angle.cos(), angle.sin());
        let mut me = Point::new(50.0, 50.0) + (1.3 + 3.0 * rng.random::<f64>()) * direction;
        let slot = Point::new(50.0, 50.0) - (1.5 + 3.0 * rng.random::<f64>()) * direction
            + Vector::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5);
        for _ in 0..30 {
            let mv = lse.plan_move(&at(slot), &me, &[]);
            let c = move_clearance_m(&field, &obstacles, &[], radius_m, &mv);
            assert!(c >= -1e-9, "clearance {c}");
            me = mv.best;
        }
    }
}

#[test]
fn same_inputs_give_bit_identical_outputs() {
    let field = Field::new(20.0, 15.0);
    let obstacles = [
        Disk::new(8.0, 7.0, 1.2),
        Disk::new(10.5, 8.7, 0.7),
        Disk::new(9.1, 4.9, 0.9),
    ];
    let others = [
        Body {
            position: Point::new(11.0, 6.0),
            radius_m: 0.3,
        },
        Body {
            position: Point::new(6.1, 9.2),
            radius_m: 0.4,
        },
    ];
    let bits = |p: &Point| (p.x.to_bits(), p.y.to_bits());
    let trace = || {
        let cbf =
            CbfController::new(field, &obstacles, &spec(0.3), CbfSettings::default()).unwrap();
        let lse = ZcbfLogSumExpController::new(
            field,
            &obstacles,
            &spec(0.3),
            CbfSettings::default(),
            DEFAULT_LSE_SHARPNESS_PER_M,
        )
        .unwrap();
        let mut out = Vec::new();
        let (mut a, mut b) = (Point::new(3.0, 7.5), Point::new(3.0, 7.5));
        for step in 0..40 {
            let centre = Pose::new(14.0 + 0.1 * step as f64, 7.7, 0.0);
            let ma = cbf.plan_move(&centre, &a, &others);
            let mb = lse.plan_move(&centre, &b, &others);
            out.push((
                ma.status,
                ma.waypoints.iter().map(bits).collect::<Vec<_>>(),
                mb.status,
                mb.waypoints.iter().map(bits).collect::<Vec<_>>(),
            ));
            a = ma.best;
            b = mb.best;
        }
        out
    };
    assert_eq!(trace(), trace());
    let rows = CbfController::new(field, &obstacles, &spec(0.3), CbfSettings::default())
        .unwrap()
        .constraints(&Point::new(9.0, 6.9), &others);
    let u = Vector::new(0.8, -0.3);
    let x = solve_qp_2d(&u, &rows).unwrap();
    let y = solve_qp_2d(&u, &rows).unwrap();
    assert_eq!(
        (x.x.to_bits(), x.y.to_bits()),
        (y.x.to_bits(), y.y.to_bits())
    );
}

/// `[cbf] substeps` reaches the agents (one piece and three give other runs, both safe),
/// and a count out of range is refused by the field's name.
#[test]
fn the_cbf_table_sets_the_pieces_of_a_turn() {
    let file = std::path::PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper.toml"
    ));
    let text = format!(
        "controller = \"cbf\"\n{}",
        std::fs::read_to_string(&file).expect("paper.toml")
    );
    let with = |substeps: u32| format!("{text}\n[cbf]\nsubsteps = {substeps}\n");
    let load = |t: &str| shared::world::scenario::Scenario::parse(t, "paper-cbf.toml");
    let default = load(&text).expect("loads");
    assert_eq!(
        default.controller.cbf.substeps,
        shared::control::vocabulary::DEFAULT_CBF_SUBSTEPS
    );
    let one = load(&with(1)).expect("loads");
    let three = load(&with(3)).expect("loads");
    assert_eq!(one.controller.cbf.substeps, 1);
    let (a, b) = (
        shared::run::simulate::simulate(&one).expect("runs"),
        shared::run::simulate::simulate(&three).expect("runs"),
    );
    assert_eq!(a.summary().collisions, 0);
    assert_eq!(b.summary().collisions, 0);
    assert_ne!(a.steps, b.steps, "the pieces changed nothing");
    for bad in [0, shared::control::vocabulary::MAX_CBF_SUBSTEPS + 1] {
        let e = load(&with(bad)).expect_err("out of range").to_string();
        assert!(e.contains("cbf.substeps"), "{e}");
    }
}

/// `[cbf] deadlock_escape` (on by default) reaches the agents: on the capped dense field
/// the plain filter leaves agents stopped at barriers for good, the escape takes them
/// round (a lower mean deviation), both without a collision.
#[test]
fn the_cbf_table_turns_the_deadlock_escape_off_and_on() {
    let file = std::path::PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/dense.toml"
    ));
    let text = std::fs::read_to_string(&file)
        .expect("dense.toml")
        .replacen("[formation]", "[formation]\nmax_step_m = 0.5", 1);
    let text = format!("controller = \"cbf\"\n{text}");
    let load =
        |t: &str| shared::world::scenario::Scenario::parse(t, "dense-cbf.toml").expect("loads");
    let escaping = load(&text);
    assert!(escaping.controller.cbf.deadlock_escape);
    let plain = load(&format!("{text}\n[cbf]\ndeadlock_escape = false\n"));
    assert!(!plain.controller.cbf.deadlock_escape);
    let (a, b) = (
        shared::run::simulate::simulate(&plain)
            .expect("runs")
            .summary(),
        shared::run::simulate::simulate(&escaping)
            .expect("runs")
            .summary(),
    );
    assert_eq!((a.collisions, b.collisions), (0, 0));
    assert!(
        b.mean_deviation_m < 0.5 * a.mean_deviation_m,
        "mean deviation {} m with the escape, {} m without",
        b.mean_deviation_m,
        a.mean_deviation_m
    );
}
