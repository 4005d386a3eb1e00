//! Properties of time in the model (top speed, limited sensing, parallel turn groups) for
//! [`TurnController`] with the paper's best-point controller, on random small worlds, checked
//! with the plain-geometry safety invariant against every body, seen or not:
//!
//! - no move is longer than the agent's top speed;
//! - a move never comes within the radii of any body, sensed or not;
//! - bodies beyond the sensing radius change nothing: moving them elsewhere beyond it, or
//!   removing them, gives the same move to the bit;
//! - the agents of one parallel group ([`turn_groups`]), planned against one snapshot,
//!   never come within their radii sum of each other during the step, and each move is
//!   safe against the snapshot.

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shared::control::formation::Slot;
use shared::control::safety::check_move;
use shared::control::turn::{PLANNING_MARGIN_M, TurnController, TurnRequest};
use shared::control::vocabulary::{AgentSpec, Body, ControllerSpec, MAX_WAYPOINTS, Move, TurnMode};
use shared::geometry::{
    Disk, DiskGrid, Field, Point, Pose, Vector, distance_polyline_polyline, polyline_length_m,
};
use shared::world::groups::turn_groups;

/// Slack on lengths and distances, in metres.
const TOLERANCE_M: f64 = 1e-9;

/// A random small world: a field, obstacles (true radii), agents (the first is "me" in the
/// single-agent properties), one spec per agent and the formation centre.
#[derive(Clone, Debug)]
struct World {
    field: Field,
    obstacles: Vec<Disk>,
    /// Every agent's body, in agent order.
    bodies: Vec<Body>,
    specs: Vec<AgentSpec>,
    centre: Pose,
}

/// The gap between a new body and the ones already placed: mostly comfortable, sometimes
/// within the planning margin (agents end their moves that close to others).
fn gap_m(rng: &mut ChaCha8Rng) -> f64 {
    if rng.random_bool(0.15) {
        rng.random_range(0.0..2e-3)
    } else {
        rng.random_range(0.01..0.5)
    }
}

/// A random spec: radius, slot, top speed in (0.1, 2), sensing radius at least the top
/// speed plus the radius.
fn spec(rng: &mut ChaCha8Rng) -> AgentSpec {
    let radius_m = rng.random_range(0.15..0.6);
    let mut spec = AgentSpec::new(
        Slot::new(
            rng.random_range(0.0..6.0),
            rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
        ),
        radius_m,
    );
    let max_step_m = rng.random_range(0.1..2.0);
    spec.max_step_m = Some(max_step_m);
    spec.sensing_radius_m = Some(max_step_m + radius_m + rng.random_range(0.0..5.0));
    spec
}

/// A world of about 20 m x 20 m with `agents` agents (never overlapping anything) and a
/// handful of obstacles (they may overlap each other, never an agent).
fn world(seed: u64, agents: usize) -> World {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let field = Field::new(rng.random_range(15.0..25.0), rng.random_range(15.0..25.0));
    let obstacles: Vec<Disk> = (0..rng.random_range(0..10))
        .map(|_| {
            Disk::new(
                rng.random_range(0.0..field.width_m),
                rng.random_range(0.0..field.height_m),
                rng.random_range(0.2..2.5),
            )
        })
        .collect();
    let mut bodies: Vec<Body> = Vec::new();
    let mut specs = Vec::new();
    let mut obstacles_kept = obstacles.clone();
    while bodies.len() < agents {
        let s = spec(&mut rng);
        // The agent stands inside the field with room for its planning margin.
        let inset_m = s.radius_m + 2e-3;
        let mut placed = None;
        for _ in 0..200 {
            let mut p = Point::new(
                rng.random_range(inset_m..field.width_m - inset_m),
                rng.random_range(inset_m..field.height_m - inset_m),
            );
            let mut gap = gap_m(&mut rng);
            // Where agents end their moves: on the boundary of a body inflated by the
            // planning margin, or up to half of it inside (a chord), or on the inset edge.
            if rng.random_bool(0.3) {
                let disks: Vec<Disk> = obstacles_kept
                    .iter()
                    .copied()
                    .chain(bodies.iter().map(|b| Disk {
                        centre: b.position,
                        radius_m: b.radius_m,
                    }))
                    .collect();
                let margin_m = if rng.random_bool(0.75) {
                    PLANNING_MARGIN_M
                } else {
                    0.5 * PLANNING_MARGIN_M
                };
                if !disks.is_empty() && rng.random_bool(0.8) {
                    let d = disks[rng.random_range(0..disks.len())];
                    let a = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
                    p = d.centre
                        + (d.radius_m + s.radius_m + margin_m) * Vector::new(a.cos(), a.sin());
                } else {
                    p.x = s.radius_m + margin_m;
                }
                gap = 0.0;
            }
            let clear_of_obstacles = obstacles_kept
                .iter()
                .all(|o| (o.centre - p).norm() >= o.radius_m + s.radius_m + gap);
            let clear_of_agents = bodies
                .iter()
                .all(|b| (b.position - p).norm() >= b.radius_m + s.radius_m + gap);
            let inside = p.x >= s.radius_m
                && p.y >= s.radius_m
                && p.x <= field.width_m - s.radius_m
                && p.y <= field.height_m - s.radius_m;
            if inside && clear_of_obstacles && clear_of_agents {
                placed = Some(p);
                break;
            }
        }
        match placed {
            Some(p) => {
                bodies.push(Body {
                    position: p,
                    radius_m: s.radius_m,
                });
                specs.push(s);
            }
            // A crowded field: thin the obstacles out and try again.
            None => {
                obstacles_kept.pop();
            }
        }
    }
    World {
        field,
        obstacles: obstacles_kept,
        bodies,
        specs,
        centre: Pose::new(
            rng.random_range(-2.0..field.width_m + 2.0),
            rng.random_range(-2.0..field.height_m + 2.0),
            rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
        ),
    }
}

/// Every body but agent `i`'s.
fn others(bodies: &[Body], i: usize) -> Vec<Body> {
    bodies
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != i)
        .map(|(_, b)| *b)
        .collect()
}

fn controller(w: &World, obstacles: &[Disk], i: usize) -> TurnController {
    TurnController::new(&ControllerSpec::default(), w.field, obstacles, &w.specs[i])
        .expect("the best-point controller takes any spec")
}

/// Agent `i`'s move among the world's bodies.
fn plan(w: &World, i: usize) -> Move {
    controller(w, &w.obstacles, i).plan(&TurnRequest::new(
        w.centre,
        w.bodies[i].position,
        &others(&w.bodies, i),
    ))
}

/// The safety invariant against every obstacle and every other agent of the snapshot.
fn check_safe(w: &World, i: usize, mv: &Move) -> Result<(), TestCaseError> {
    let verdict = check_move(
        &w.field,
        &DiskGrid::new(w.obstacles.clone()),
        &others(&w.bodies, i),
        w.bodies[i].radius_m,
        &w.bodies[i].position,
        &mv.waypoints,
        MAX_WAYPOINTS,
    );
    prop_assert!(
        verdict.is_ok(),
        "agent {i}'s move {:?} ({:?}) is unsafe: {:?}",
        mv.waypoints,
        mv.status,
        verdict
    );
    Ok(())
}

fn check_top_speed(w: &World, i: usize, mv: &Move) -> Result<(), TestCaseError> {
    let max_m = w.specs[i].max_step_m.expect("a top speed");
    let length_m = polyline_length_m(&mv.waypoints);
    prop_assert!(
        length_m <= max_m + TOLERANCE_M,
        "agent {i}'s move is {length_m} m long, top speed {max_m} m ({:?})",
        mv.status
    );
    Ok(())
}

/// Whether agent `spec` standing at `me` senses a disk at `centre` of `radius_m`.
fn beyond(spec: &AgentSpec, me: &Point, centre: &Point, radius_m: f64) -> bool {
    !spec.senses(me, centre, radius_m)
}

/// A place for a disk of `radius_m` in (or near) the field beyond `spec`'s sensing from
/// `me`, if one is found.
fn far_place(
    rng: &mut ChaCha8Rng,
    w: &World,
    spec: &AgentSpec,
    me: &Point,
    radius_m: f64,
) -> Option<Point> {
    (0..100)
        .map(|_| {
            Point::new(
                rng.random_range(-5.0..w.field.width_m + 5.0),
                rng.random_range(-5.0..w.field.height_m + 5.0),
            )
        })
        .find(|p| beyond(spec, me, p, radius_m))
}

/// Agent 0's move, checked to be the same with the bodies beyond its sensing radius moved
/// elsewhere beyond it, removed, or partly removed and partly moved.
fn beyond_sensing_changes_nothing(w: &World, rng: &mut ChaCha8Rng) -> Result<Move, TestCaseError> {
    let (spec, me) = (w.specs[0], w.bodies[0].position);
    let mv = plan(w, 0);
    // Moved elsewhere beyond the sensing radius (kept when no such place is found).
    let mut moved = w.clone();
    for o in &mut moved.obstacles {
        if beyond(&spec, &me, &o.centre, o.radius_m)
            && let Some(p) = far_place(rng, w, &spec, &me, o.radius_m)
        {
            o.centre = p;
        }
    }
    for b in &mut moved.bodies[1..] {
        if beyond(&spec, &me, &b.position, b.radius_m)
            && let Some(p) = far_place(rng, w, &spec, &me, b.radius_m)
        {
            b.position = p;
        }
    }
    prop_assert_eq!(&plan(&moved, 0), &mv, "far bodies moved");
    // Removed.
    let mut removed = w.clone();
    removed
        .obstacles
        .retain(|o| !beyond(&spec, &me, &o.centre, o.radius_m));
    let kept: Vec<usize> = (0..w.bodies.len())
        .filter(|&i| i == 0 || !beyond(&spec, &me, &w.bodies[i].position, w.bodies[i].radius_m))
        .collect();
    removed.bodies = kept.iter().map(|&i| w.bodies[i]).collect();
    removed.specs = kept.iter().map(|&i| w.specs[i]).collect();
    prop_assert_eq!(&plan(&removed, 0), &mv, "far bodies removed");
    // Some far obstacles removed, the others moved.
    let mut mixed = moved;
    mixed
        .obstacles
        .retain(|o| !(beyond(&spec, &me, &o.centre, o.radius_m) && rng.random_bool(0.5)));
    prop_assert_eq!(
        &plan(&mixed, 0),
        &mv,
        "far obstacles partly removed, partly moved"
    );
    Ok(mv)
}

/// The formation centre one step on: a short random stride and turn, so the slots move
/// as they do along a path.
fn next_centre(rng: &mut ChaCha8Rng, centre: &Pose) -> Pose {
    let a = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
    let stride_m = rng.random_range(0.0..1.0);
    Pose::new(
        centre.x_m + stride_m * a.cos(),
        centre.y_m + stride_m * a.sin(),
        centre.heading_rad + rng.random_range(-0.3..0.3),
    )
}

/// Turns each property walks through (each from where the last one ended).
const TURNS: usize = 4;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// A move is no longer than the top speed and safe against every body, seen or not,
    /// turn after turn from where the last move ended.
    #[test]
    fn a_move_keeps_its_top_speed_and_clear_of_every_body(seed in any::<u64>()) {
        let mut w = world(seed, 1 + (seed % 6) as usize);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x7017);
        for _ in 0..TURNS {
            let mv = plan(&w, 0);
            prop_assert_eq!(mv.waypoints[0], w.bodies[0].position);
            check_top_speed(&w, 0, &mv)?;
            check_safe(&w, 0, &mv)?;
            w.bodies[0].position = mv.end();
            w.centre = next_centre(&mut rng, &w.centre);
        }
    }

    /// Bodies beyond the sensing radius change nothing, wherever they go (beyond it) and
    /// whether they are there at all.
    #[test]
    fn bodies_beyond_sensing_change_nothing(seed in any::<u64>()) {
        let mut w = world(seed, 1 + (seed % 7) as usize);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5e45_1e55);
        for _ in 0..TURNS {
            let mv = beyond_sensing_changes_nothing(&w, &mut rng)?;
            w.bodies[0].position = mv.end();
            w.centre = next_centre(&mut rng, &w.centre);
        }
    }

    /// The agents of one parallel group, each planned against the same snapshot, keep
    /// clear of each other over their whole moves and of every body of the snapshot; step
    /// after step, the groups taken in turn as the reference simulation takes them.
    #[test]
    fn a_parallel_group_never_meets_within_the_step(seed in any::<u64>()) {
        let mut w = world(seed, 4 + (seed % 9) as usize);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9a7a);
        let n = w.bodies.len();
        for _ in 0..TURNS {
            let groups = turn_groups(TurnMode::Parallel, &w.specs, &w.bodies, &vec![true; n]);
            let mut seen = vec![0; n];
            for group in &groups {
                let moves: Vec<(usize, Move)> =
                    group.iter().map(|&i| (i, plan(&w, i))).collect();
                for (i, mv) in &moves {
                    seen[*i] += 1;
                    check_top_speed(&w, *i, mv)?;
                    check_safe(&w, *i, mv)?;
                }
                for (k, (i, mi)) in moves.iter().enumerate() {
                    for (j, mj) in &moves[..k] {
                        let reach_m = w.bodies[*i].radius_m + w.bodies[*j].radius_m;
                        let d = distance_polyline_polyline(&mi.waypoints, &mj.waypoints);
                        prop_assert!(
                            d >= reach_m - TOLERANCE_M,
                            "agents {i} and {j} of group {group:?} come {d} m apart (radii {reach_m} m)"
                        );
                    }
                }
                // The group moves at once.
                for (i, mv) in &moves {
                    w.bodies[*i].position = mv.end();
                }
            }
            prop_assert!(seen.iter().all(|s| *s == 1), "one group per agent: {groups:?}");
            w.centre = next_centre(&mut rng, &w.centre);
        }
    }
}
