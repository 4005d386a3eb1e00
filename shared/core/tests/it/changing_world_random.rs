//! A changing world drawn at random: open fields with random moving, static and unknown
//! obstacles.
//!
//! - A property: at every step the agents keep clear of the static obstacles, of one
//!   another and of the field's edge, no move is longer than the top speed, no move enters
//!   a moving obstacle where it stands, and every strike of a moving obstacle (checked here
//!   with plain geometry, independent of the recorder) is recorded in its step, as a fault
//!   `struck`, and counted in the summary's collisions.
//! - A regression test: 48 fixed fields of moving obstacles in which no agent is ever
//!   struck (strikes are not ruled out in every field), and 30 seeded fields of twenty.
//! - With limited sensing, a turn depends only on the bodies the agent senses.
//! - A moving obstacle faster than the agents is refused.

use proptest::prelude::*;
use shared::control::safety::SAFETY_TOLERANCE_M;
use shared::control::turn::TurnRequest;
use shared::geometry::{Point, distance_polyline_polyline, polyline_length_m};
use shared::run::record::{FaultKind, Run};
use shared::run::simulate::simulate;
use shared::world::moving_obstacle::{MovingObstacle, Route};
use shared::world::scenario::{Scenario, moving_obstacle_table};

/// A random moving obstacle: radius, waypoints, speed, and whether its route loops.
type MoverSpec = (f64, Vec<(f64, f64)>, f64, bool);

/// `tests/data/open-field.toml` (an open field 30 x 20 m, a formation of four crossing it
/// with a top speed of 0.5 m per step) with `movers`, random moving obstacles slower than
/// that.
fn open_field(movers: &[MoverSpec]) -> Scenario {
    open_field_with(movers, &[], false, false)
}

/// [`open_field`] with `statics` too (static obstacles, known or found on the way), its
/// turns taken in parallel groups if `parallel`, and if `short_sighted` the agents sensing
/// no farther than validation requires (as in `tests/data/strike.toml`: their step, their
/// radius and an obstacle's step), so they cannot look ahead along an obstacle's route.
fn open_field_with(
    movers: &[MoverSpec],
    statics: &[StaticSpec],
    parallel: bool,
    short_sighted: bool,
) -> Scenario {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/open-field.toml");
    let mut text =
        std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    if short_sighted {
        assert!(
            text.contains("max_step_m = 0.5\n"),
            "open-field.toml's top speed changed"
        );
        text = text.replace(
            "max_step_m = 0.5\n",
            "max_step_m = 0.5\nsensing_radius_m = 1.3\n",
        );
    }
    if parallel {
        text += "\n[turns]\nmode = \"parallel\"\n";
    }
    let disk = |&((x, y), r, _): &StaticSpec| format!("{{ x_m = {x}, y_m = {y}, radius_m = {r} }}");
    let known: Vec<String> = statics.iter().filter(|s| !s.2).map(disk).collect();
    if !known.is_empty() {
        text += &format!("\n[obstacles]\ndisk = [{}]\n", known.join(", "));
    }
    for ((x, y), r, _) in statics.iter().filter(|s| s.2) {
        text += &format!("\n[[obstacles.unknown]]\nx_m = {x}\ny_m = {y}\nradius_m = {r}\n");
    }
    for (radius_m, waypoints, speed, looped) in movers {
        let route = if *looped {
            Route::Loop
        } else {
            Route::BackAndForth
        };
        let points = waypoints.iter().map(|&(x, y)| Point::new(x, y)).collect();
        text += &moving_obstacle_table(&MovingObstacle::new(*radius_m, points, *speed, route));
    }
    Scenario::parse(&text, "open-field.toml").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// A moving obstacle of radius 0.4 to 1 m on 2 or 3 waypoints inside the field, at 0.05 to
/// 0.45 m per step (slower than the agents' 0.5 m), starting at least 2.5 m from the formation's start and 1.5 m from the
/// goal.
fn mover() -> impl Strategy<Value = MoverSpec> {
    (
        0.4..1.0f64,
        prop::collection::vec((1.0..29.0f64, 1.0..19.0f64), 2..=3),
        0.05..0.45f64,
        any::<bool>(),
    )
        .prop_filter("clear of the start and goal", |(r, w, _, _)| {
            let (x, y) = w[0];
            (x - 3.0).hypot(y - 10.0) > r + 2.5 && (x - 27.0).hypot(y - 10.0) > r + 1.5
        })
}

/// The independent geometry of a run: the smallest gap (minus both radii) between any
/// agent move and any moving obstacle standing during it (for a struck agent's move,
/// starting inside the obstacle: how much closer it comes than it started), and every `(step, obstacle,
/// agent)` whose obstacle motion came within reach of the agent standing (a strike).
fn moves_gap_and_strikes(scenario: &Scenario, run: &Run) -> (f64, Vec<(usize, usize, usize)>) {
    let mut gap = f64::INFINITY;
    let mut strikes = Vec::new();
    for (k, step) in run.steps.iter().enumerate().skip(1) {
        let before = &run.steps[k - 1];
        for (m, obstacle) in scenario.moving.iter().enumerate() {
            let at = obstacle.position_at(step.step);
            let sweep = obstacle.sweep(step.step);
            for (a, agent) in step.agents.iter().enumerate() {
                let reach_m = obstacle.radius_m + scenario.agents[a].radius_m;
                // A move that goes somewhere (one left standing where a strike caught it
                // is the strike's doing, counted there). A struck agent, starting inside
                // the obstacle, may only leave: never closer than it started.
                if agent.waypoints.len() > 1 {
                    let closest_m = distance_polyline_polyline(&agent.waypoints, &[at]);
                    let start_m = (agent.waypoints[0] - at).norm();
                    gap = gap.min(if start_m < reach_m - SAFETY_TOLERANCE_M {
                        closest_m - start_m
                    } else {
                        closest_m - reach_m
                    });
                }
                let struck = distance_polyline_polyline(&sweep, &[before.agents[a].position])
                    < reach_m - SAFETY_TOLERANCE_M;
                if before.agents[a].alive && struck {
                    strikes.push((step.step, m, a));
                }
            }
        }
    }
    (gap, strikes)
}

proptest! {
    // A fixed seed: the same 48 fields on every run (after the regression file's past
    // failures).
    #![proptest_config(ProptestConfig {
        cases: 48,
        rng_seed: proptest::test_runner::RngSeed::Fixed(15),
        ..ProptestConfig::default()
    })]

    /// Regression test, not a property: 48 fields drawn once (a fixed seed), of random
    /// moving obstacles slower than the agents (up to 0.9 of their top speed) in the open
    /// field, in which no agent move ever enters an obstacle where it stands and no
    /// obstacle's motion ever comes within reach of an agent standing (a strike): no agent
    /// ever comes within the radii of any obstacle. The record is checked to hold exactly
    /// the strikes the plain geometry here finds (none).
    ///
    /// Strikes are not ruled out in every field (an agent caught between obstacles
    /// closing in from several sides, or boxed in by its mates, can find no way out; the
    /// docs/measurements.md says how often, about 1 field in 5 000): these 48 have none, and
    /// [`every_random_field_keeps_the_invariants_and_books_every_strike`] states what
    /// holds in every field. Without the sweep of where an agent can go on to
    /// ([`shared::control::survival_grid`]) this fails (one of them: three obstacles closing on
    /// the rear agent); without looking ahead at all, two of the regression file's fields
    /// are struck.
    #[test]
    fn regression_no_agent_is_struck_in_48_fixed_fields_of_moving_obstacles(
        movers in prop::collection::vec(mover(), 1..=6)
    ) {
        let scenario = open_field(&movers);
        let run = simulate(&scenario).expect("simulate");
        let (gap, strikes) = moves_gap_and_strikes(&scenario, &run);
        prop_assert!(gap >= -SAFETY_TOLERANCE_M, "a move enters a moving obstacle: {} m", gap);
        let recorded: Vec<(usize, usize, usize)> = run
            .steps
            .iter()
            .flat_map(|s| s.struck.iter().map(move |&(m, a, _)| (s.step, m, a)))
            .collect();
        prop_assert_eq!(&recorded, &strikes);
        prop_assert!(strikes.is_empty(), "struck (step, obstacle, agent): {:?}", strikes);
        prop_assert_eq!(run.summary().collisions, 0);
    }
}

/// A large moving obstacle of radius 1 to 1.5 m driven along the formation's line (two
/// waypoints 2 m either side of it at most) at 0.3 to 0.499 m per step, nearly the agents'
/// top speed: with short-sighted agents it strikes some now and then.
fn hunter() -> impl Strategy<Value = MoverSpec> {
    (
        1.0..1.5f64,
        prop::collection::vec((6.0..26.0f64, 8.0..12.0f64), 2),
        0.3..0.499f64,
        any::<bool>(),
    )
        .prop_filter("clear of the start and goal", |(r, w, _, _)| {
            let (x, y) = w[0];
            (x - 3.0).hypot(y - 10.0) > r + 2.5 && (x - 27.0).hypot(y - 10.0) > r + 1.5
        })
}

/// A random static obstacle: centre, radius, and whether the centre's planner knows it
/// from the start (`[obstacles.disk]`) or finds it on the way (`[[obstacles.unknown]]`).
type StaticSpec = ((f64, f64), f64, bool);

/// A static obstacle of radius 0.4 to 1 m inside the field, clear of the formation at
/// the start and at the goal (slots 1 m from the centre, agents of 0.3 m).
fn static_obstacle() -> impl Strategy<Value = StaticSpec> {
    ((2.0..28.0f64, 1.5..18.5f64), 0.4..1.0f64, any::<bool>()).prop_filter(
        "clear of the start and goal",
        |((x, y), r, _)| {
            (x - 3.0).hypot(y - 10.0) > r + 2.0 && (x - 27.0).hypot(y - 10.0) > r + 2.0
        },
    )
}

/// Whether `p`, a body of `radius_m`, and the disk `(centre, reach_m - radius_m)` are
/// closer than their radii sum `reach_m`, beyond the tolerance.
fn overlaps(p: Point, centre: Point, reach_m: f64) -> bool {
    (p - centre).norm() < reach_m - SAFETY_TOLERANCE_M
}

proptest! {
    // Few cases: most fields take a few hundredths of a second, but the odd one where the
    // centre replans again and again takes seconds.
    #![proptest_config(ProptestConfig { cases: 10, ..ProptestConfig::default() })]

    /// In every field (random moving obstacles slower than the agents, large ones nearly
    /// as fast on the formation's line, random static obstacles known or found on the
    /// way, sequential or parallel turns, agents that see far or only as far as
    /// validation requires), checked with plain geometry on the record:
    ///
    /// - every move starts where the agent stood and ends where it then stands, no longer
    ///   than its top speed;
    /// - at the end of every step every agent is inside the field and clear of every
    ///   static obstacle and of every other agent (the safety invariant: moving obstacles
    ///   aside, nothing can push an agent);
    /// - every moving obstacle stands where its route puts it, and no move enters one
    ///   where it stands (a struck agent, starting inside it, never comes closer);
    /// - every strike (an obstacle's motion coming within reach of a live agent standing)
    ///   is recorded in its step, and as a fault `struck` of that agent at that step, in
    ///   the same order, and nothing else is recorded as struck;
    /// - an agent that ends a step overlapping a moving obstacle was struck at that step,
    ///   and the summary's collisions are the strikes plus those overlaps.
    ///
    /// Strikes themselves may happen (see the regression test above).
    #[test]
    fn every_random_field_keeps_the_invariants_and_books_every_strike(
        movers in prop::collection::vec(mover(), 0..=4),
        hunters in prop::collection::vec(hunter(), 0..=1),
        statics in prop::collection::vec(static_obstacle(), 0..=2),
        parallel in any::<bool>(),
        short_sighted in any::<bool>(),
    ) {
        let movers: Vec<MoverSpec> = movers.into_iter().chain(hunters).collect();
        let scenario = open_field_with(&movers, &statics, parallel, short_sighted);
        let run = simulate(&scenario).expect("simulate");
        let field = scenario.field;
        let obstacles = scenario.static_obstacles();
        prop_assert_eq!(obstacles.len(), statics.len());
        let mut overlapping = 0;
        for (k, step) in run.steps.iter().enumerate() {
            prop_assert_eq!(step.step, k);
            for (m, obstacle) in scenario.moving.iter().enumerate() {
                prop_assert_eq!(step.moving[m], obstacle.position_at(k));
            }
            for (a, agent) in step.agents.iter().enumerate() {
                let r = scenario.agents[a].radius_m;
                let p = agent.position;
                prop_assert_eq!(agent.waypoints.last(), Some(&p), "step {} agent {}", k, a);
                if k > 0 {
                    let stood = run.steps[k - 1].agents[a].position;
                    prop_assert!((agent.waypoints[0] - stood).norm() <= SAFETY_TOLERANCE_M);
                    if let Some(max_m) = scenario.agents[a].max_step_m {
                        let length_m = polyline_length_m(&agent.waypoints);
                        prop_assert!(length_m <= max_m + SAFETY_TOLERANCE_M, "step {} agent {}: {} m", k, a, length_m);
                    }
                }
                prop_assert!(
                    p.x >= r - SAFETY_TOLERANCE_M
                        && p.y >= r - SAFETY_TOLERANCE_M
                        && p.x <= field.width_m - r + SAFETY_TOLERANCE_M
                        && p.y <= field.height_m - r + SAFETY_TOLERANCE_M,
                    "step {} agent {} outside the field at {:?}", k, a, p
                );
                for o in &obstacles {
                    prop_assert!(!overlaps(p, o.centre, o.radius_m + r), "step {} agent {} in {:?}", k, a, o);
                }
                for (b, other) in step.agents.iter().enumerate().skip(a + 1) {
                    let reach_m = r + scenario.agents[b].radius_m;
                    prop_assert!(!overlaps(p, other.position, reach_m), "step {}: agents {} and {}", k, a, b);
                }
                for (m, obstacle) in scenario.moving.iter().enumerate() {
                    if overlaps(p, step.moving[m], obstacle.radius_m + r) {
                        overlapping += 1;
                        prop_assert!(
                            step.struck.iter().any(|&(_, s, _)| s == a),
                            "step {}: agent {} in moving obstacle {} unstruck", k, a, m
                        );
                    }
                }
            }
        }
        let (gap, strikes) = moves_gap_and_strikes(&scenario, &run);
        prop_assert!(gap >= -SAFETY_TOLERANCE_M, "a move enters a moving obstacle: {} m", gap);
        let recorded: Vec<(usize, usize, usize)> = run
            .steps
            .iter()
            .flat_map(|s| s.struck.iter().map(move |&(m, a, _)| (s.step, m, a)))
            .collect();
        prop_assert_eq!(&recorded, &strikes);
        let struck_faults: Vec<(usize, usize)> = run
            .faults
            .iter()
            .filter(|f| f.kind == FaultKind::Struck)
            .map(|f| (f.step, f.agent))
            .collect();
        let struck: Vec<(usize, usize)> = strikes.iter().map(|&(s, _, a)| (s, a)).collect();
        prop_assert_eq!(struck_faults, struck);
        let summary = run.summary();
        prop_assert_eq!(summary.collisions, strikes.len() + overlapping);
        prop_assert!(summary.max_move_m <= 0.5 + SAFETY_TOLERANCE_M);
    }
}

#[test]
fn a_moving_obstacle_faster_than_the_agents_is_refused() {
    let too_fast = open_field(&[(0.5, vec![(15.0, 2.0), (15.0, 18.0)], 0.4, false)]);
    assert_eq!(too_fast.moving.len(), 1);
    let mut text = too_fast.to_resolved_toml("x").expect("resolved");
    text = text.replace("speed_m_per_step = 0.4", "speed_m_per_step = 0.6");
    let e = Scenario::parse(&text, "fast.toml").unwrap_err();
    assert_eq!(e.field(), "obstacles.moving[0].speed_m_per_step", "{e}");
    // The one it was built from moves as its route says.
    let m = MovingObstacle::new(
        0.5,
        vec![Point::new(15.0, 2.0), Point::new(15.0, 18.0)],
        0.4,
        Route::BackAndForth,
    );
    assert_eq!(too_fast.moving[0], m);
}

/// Fields like the shipped `moving-field` (50 x 40 m, 20 moving obstacles of 0.5 to 1 m
/// at 0.1 to 0.3 m per step on random patrols and loops, six agents at 0.5 m per step),
/// drawn from 30 seeds: every run reaches the goal with no collision.
#[test]
fn random_fields_of_twenty_moving_obstacles_cause_no_collision() {
    use rand::{Rng, SeedableRng};
    let mut replans = 0;
    for seed in 0..30u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut text = String::from(
            "name = \"f20\"\n[field]\nwidth_m = 50.0\nheight_m = 40.0\n[obstacles]\nradius_m = 0.8\n",
        );
        let mut n = 0;
        while n < 20 {
            let r: f64 = [0.5, 0.6, 0.8, 1.0][rng.random_range(0..4)];
            let looped = rng.random_bool(0.5);
            let k = if looped { 3 } else { 2 };
            let (cx, cy) = (rng.random_range(8.0..42.0), rng.random_range(4.0..36.0));
            let pts: Vec<(f64, f64)> = (0..k)
                .map(|_| {
                    let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                    let d: f64 = rng.random_range(3.0..9.0);
                    (
                        (cx + d * a.cos()).clamp(1.5, 48.5),
                        (cy + d * a.sin()).clamp(1.5, 38.5),
                    )
                })
                .collect();
            let (x0, y0) = pts[0];
            if (x0 - 4.0).hypot(y0 - 20.0) < r + 6.0 || (x0 - 46.0).hypot(y0 - 20.0) < r + 3.0 {
                continue;
            }
            let sp: f64 = rng.random_range(0.1..0.3);
            let p: Vec<String> = pts.iter().map(|(x, y)| format!("[{x}, {y}]")).collect();
            text += &format!(
                "[[obstacles.moving]]\nradius_m = {r}\nwaypoints_m = [{}]\nspeed_m_per_step = {sp}\nroute = \"{}\"\n",
                p.join(", "),
                if looped { "loop" } else { "back-and-forth" }
            );
            n += 1;
        }
        text += "[formation]\nagent_radius_m = 0.3\nmax_step_m = 0.5\nslots = [ { r_m = 0.0, theta_deg = 0.0 }, { r_m = 1.2, theta_deg = 0.0 }, { r_m = 1.2, theta_deg = 90.0 }, { r_m = 1.2, theta_deg = 180.0 }, { r_m = 1.2, theta_deg = -90.0 }, { r_m = 2.0, theta_deg = 135.0 } ]\n[path]\nstart = { x_m = 4.0, y_m = 20.0, heading_deg = 0.0 }\ngoal = { x_m = 46.0, y_m = 20.0, heading_deg = 0.0 }\nturning_radius_m = 2.0\nstep_m = 0.25\ncentre_clearance_m = 0.5\n";
        let s = Scenario::parse(&text, "f20.toml").unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let run = simulate(&s).expect("simulate");
        let summary = run.summary();
        assert!(run.completed, "seed {seed}");
        assert_eq!(summary.collisions, 0, "seed {seed}");
        let (gap, strikes) = moves_gap_and_strikes(&s, &run);
        assert!(
            gap >= -SAFETY_TOLERANCE_M && strikes.is_empty(),
            "seed {seed}"
        );
        replans += summary.replans.len();
    }
    assert!(
        replans > 0,
        "no moving obstacle ever crossed the centre's path"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// With limited sensing, an agent's turn among moving obstacles (escapes included)
    /// depends only on the bodies it senses: given every body or only those, the move is
    /// the same, bit for bit (the coordinator sends an agent process only what it
    /// senses, the reference simulation has them all).
    #[test]
    fn a_turn_among_moving_obstacles_depends_only_on_what_the_agent_senses(
        near in (-1.2..1.2f64, -1.2..1.2f64),
        crowd in prop::collection::vec((0.0..std::f64::consts::TAU, 0.6..2.2f64), 0..14),
        step in 0usize..400,
        slot in (-2.5..2.5f64, -2.5..2.5f64),
    ) {
        let text = r#"
name = "sensing-turns"
[field]
width_m = 30.0
height_m = 20.0
[[obstacles.moving]]
radius_m = 0.6
waypoints_m = [[4.0, 4.0], [26.0, 16.0], [26.0, 4.0]]
speed_m_per_step = 0.3
route = "loop"
[formation]
agent_radius_m = 0.25
max_step_m = 0.5
sensing_radius_m = 1.1
slots = [
  { r_m = 0.0, theta_deg = 0.0 },
  { r_m = 1.0, theta_deg = 90.0 },
]
[path]
start = { x_m = 3.0, y_m = 10.0, heading_deg = 0.0 }
goal = { x_m = 27.0, y_m = 10.0, heading_deg = 0.0 }
turning_radius_m = 2.0
step_m = 0.25
centre_clearance_m = 0.5
"#;
        let scenario = Scenario::parse(text, "sensing-turns.toml").expect("scenario");
        let controller = &shared::run::simulate::agent_controllers(&scenario).expect("controllers")[0];
        // The agent near the obstacle (so it often has to escape), others around it.
        let obstacle = scenario.moving[0].position_at(step);
        let me = Point::new(
            (obstacle.x + near.0).clamp(0.5, 29.5),
            (obstacle.y + near.1).clamp(0.5, 19.5),
        );
        let spec = scenario.agents[0];
        let others: Vec<shared::control::vocabulary::Body> = crowd
            .iter()
            .map(|(angle, d)| shared::control::vocabulary::Body {
                position: Point::new(me.x + d * angle.cos(), me.y + d * angle.sin()),
                radius_m: 0.25,
            })
            .filter(|b| (b.position - me).norm() >= 0.5 + 1e-3 && (b.position - obstacle).norm() >= 0.85)
            .collect();
        // Bodies that overlap one another are left out, not the case.
        let others: Vec<shared::control::vocabulary::Body> = others
            .iter()
            .enumerate()
            .filter(|(i, a)| others[..*i].iter().all(|b| (a.position - b.position).norm() >= 0.5))
            .map(|(_, b)| *b)
            .collect();
        prop_assume!((me - obstacle).norm() >= 0.85 + 1e-3);
        let sensed: Vec<shared::control::vocabulary::Body> = others
            .iter()
            .filter(|b| spec.senses(&me, &b.position, b.radius_m))
            .copied()
            .collect();
        // Agent 0's slot is the centre itself: somewhere around, often past the others.
        let centre = shared::geometry::Pose::new(
            (me.x + slot.0).clamp(0.5, 29.5),
            (me.y + slot.1).clamp(0.5, 19.5),
            0.0,
        );
        let all = controller.plan(&TurnRequest::new(centre, me, &others).at_step(step));
        let seen = controller.plan(&TurnRequest::new(centre, me, &sensed).at_step(step));
        prop_assert_eq!(all, seen);
    }
}
