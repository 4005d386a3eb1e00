//! Car-like agents: what validation refuses, and the reference simulation checked from
//! the record alone with the geometry written out here: each move's segments are read
//! back as the arcs tangent to the heading that they stand for, and none bends tighter
//! than the turning radius, reverses where it may not, runs past the top speed or ends
//! facing other than its arcs leave it; every arc keeps clear of every obstacle and
//! agent (distance to the arc computed exactly) and the run completes with 0 collisions.

use std::f64::consts::PI;

use shared::control::vocabulary::Kinematics;
use shared::geometry::{Point, distance_point_segment};
use shared::run::simulate::simulate;
use shared::world::scenario::{Scenario, ScenarioError};

fn repository(path: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join(path)
}

/// A small scenario whose `[formation]` table carries `formation` (slots given here).
fn scenario_with(formation: &str) -> Result<Scenario, ScenarioError> {
    let text = format!(
        r#"name = "cars"
[field]
width_m = 20.0
height_m = 10.0
[obstacles]
radius_m = 0.5
[formation]
agent_radius_m = 0.25
{formation}
slots = [{{ r_m = 0.0, theta_deg = 0.0 }}, {{ r_m = 1.0, theta_deg = 90.0 }}]
[path]
start = {{ x_m = 2.0, y_m = 5.0, heading_deg = 0.0 }}
goal = {{ x_m = 18.0, y_m = 5.0, heading_deg = 0.0 }}
turning_radius_m = 1.0
step_m = 0.25
centre_clearance_m = 0.5
allow_reverse = false
"#
    );
    Scenario::parse(&text, "cars.toml")
}

/// The field a refusal names.
fn refused_field(formation: &str) -> String {
    match scenario_with(formation) {
        Err(ScenarioError::Invalid { field, .. }) => field,
        other => panic!("{formation}: expected a refusal, got {other:?}"),
    }
}

#[test]
fn validation_names_the_field_of_a_car_that_cannot_work() {
    let ok = scenario_with("max_step_m = 0.5\nkinematics = \"car\"\nturning_radius_m = 1.0")
        .expect("a valid car formation");
    assert_eq!(
        ok.agents[0].kinematics,
        Kinematics::Car {
            turning_radius_m: 1.0,
            reverse: false
        }
    );
    // No turning radius, no top speed, a turning circle wider than the field, a key of
    // the unicycle, a turning radius for unicycles.
    for (formation, field) in [
        (
            "max_step_m = 0.5\nkinematics = \"car\"",
            "formation.turning_radius_m",
        ),
        (
            "kinematics = \"car\"\nturning_radius_m = 1.0",
            "formation.kinematics",
        ),
        (
            "max_step_m = 0.5\nkinematics = \"car\"\nturning_radius_m = 6.0",
            "formation.turning_radius_m",
        ),
        (
            "max_step_m = 0.5\nkinematics = \"car\"\nturning_radius_m = -1.0",
            "formation.turning_radius_m",
        ),
        (
            "max_step_m = 0.5\nkinematics = \"car\"\nturning_radius_m = 1.0\nmax_turn_rad = 1.0",
            "formation.max_turn_rad",
        ),
        (
            "max_step_m = 0.5\nkinematics = \"unicycle\"\nmax_turn_rad = 1.0\nturning_radius_m = 1.0",
            "formation.turning_radius_m",
        ),
        (
            "max_step_m = 0.5\nturning_radius_m = 1.0",
            "formation.turning_radius_m",
        ),
        (
            "max_step_m = 0.5\nkinematics = \"boat\"",
            "formation.kinematics",
        ),
    ] {
        assert_eq!(refused_field(formation), field, "{formation}");
    }
}

/// `a - b` wrapped into (-pi, pi].
fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI { d - 2.0 * PI } else { d }
}

/// One segment read back as an arc: (reversed, turn, radius, length, centre).
fn arc_of(heading_rad: f64, a: &Point, b: &Point) -> (bool, f64, f64, f64, Option<Point>) {
    let d = b - a;
    let c = d.norm();
    let facing = Point::new(heading_rad.cos(), heading_rad.sin()).coords;
    let reversed = facing.dot(&d) < 0.0;
    let way = if reversed { -facing } else { facing };
    let half = (way.x * d.y - way.y * d.x).atan2(way.dot(&d));
    if half.abs() < 1e-9 || c < 1e-12 {
        return (reversed, 0.0, f64::INFINITY, c, None);
    }
    let radius = c / (2.0 * half.abs().sin());
    let left = Point::new(-way.y, way.x).coords * half.signum();
    (
        reversed,
        2.0 * half,
        radius,
        radius * 2.0 * half.abs(),
        Some(a + left * radius),
    )
}

/// The distance from `q` to the arc round `centre` from `a` to `b` (less than a half
/// turn): to the circle where `q`'s direction falls within the arc, else to an end.
fn distance_to_arc(q: &Point, centre: &Point, a: &Point, b: &Point) -> f64 {
    let (u, v, w) = (a - centre, b - centre, q - centre);
    let cross = |p: &nalgebra::Vector2<f64>, r: &nalgebra::Vector2<f64>| p.x * r.y - p.y * r.x;
    let turn = cross(&u, &v);
    let within =
        cross(&u, &w) * turn >= 0.0 && cross(&w, &v) * turn >= 0.0 && w.dot(&(u + v)) > 0.0;
    if within {
        (w.norm() - u.norm()).abs()
    } else {
        (q - a).norm().min((q - b).norm())
    }
}

fn check_every_car_move(file: &str, scenario: &Scenario) -> (f64, bool) {
    let scenario = scenario.clone();
    let run = simulate(&scenario).expect("simulate");
    assert!(run.completed, "{file}");
    assert_eq!(run.summary().collisions, 0, "{file}");
    assert!(run.faults.is_empty(), "{file}: {:?}", run.faults);
    let obstacles = scenario.static_obstacles();
    let mut turned_rad: f64 = 0.0;
    let mut reversed_any = false;
    for (i, spec) in scenario.agents.iter().enumerate() {
        let Kinematics::Car {
            turning_radius_m,
            reverse,
        } = spec.kinematics
        else {
            panic!("{file}: agent {i} is a car");
        };
        let max_step_m = spec.max_step_m.expect("a top speed");
        for pair in run.steps.windows(2) {
            let (before, after) = (&pair[0].agents[i], &pair[1].agents[i]);
            let step = pair[1].step;
            let mut heading = before.heading_rad.expect("a heading");
            let mut length_m = 0.0;
            for w in after.waypoints.windows(2) {
                let (reversed, turn, radius, len, centre) = arc_of(heading, &w[0], &w[1]);
                // It turns no more than an arc of the turning radius over this chord
                // would, to 1e-7 rad (a chord of a micrometre is known to a few 1e-15 m:
                // its radius is not, its turning is).
                let chord_m = (w[1] - w[0]).norm();
                let most_rad = 2.0 * (0.5 * chord_m / turning_radius_m).min(1.0).asin();
                assert!(
                    turn.abs() <= most_rad + 2e-7,
                    "{file}: step {step}, agent {i}: radius {radius} m"
                );
                assert!(
                    reverse || !reversed,
                    "{file}: step {step}, agent {i} reversed"
                );
                reversed_any |= reversed;
                turned_rad = turned_rad.max(turn.abs());
                // The obstacles, exactly along the arc (the agents: the recorder's count).
                let distance = |q: &Point| match centre {
                    Some(c) => distance_to_arc(q, &c, &w[0], &w[1]),
                    None => distance_point_segment(q, &w[0], &w[1]),
                };
                for o in &obstacles {
                    assert!(
                        distance(&o.centre) >= o.radius_m + spec.radius_m - 1e-9,
                        "{file}: step {step}, agent {i} meets an obstacle"
                    );
                }
                heading += turn;
                length_m += len;
            }
            assert!(
                length_m <= max_step_m + 1e-9,
                "{file}: step {step}: {length_m} m"
            );
            let end = after.heading_rad.expect("a heading");
            assert!(
                angle_between(end, heading).abs() < 1e-6,
                "{file}: step {step}, agent {i} turned in place"
            );
        }
    }
    (turned_rad, reversed_any)
}

#[test]
fn every_car_move_bends_no_tighter_than_the_turning_radius_and_keeps_clear() {
    let load = |file: &str| Scenario::load(&repository(file)).expect("load");
    let paper = load("scenarios/paper-car.toml");
    let (turned_rad, reversed) = check_every_car_move("paper-car", &paper);
    // The checks mean something only if the cars turned and reversed.
    assert!(
        turned_rad > 0.01,
        "the largest turn of a segment was {turned_rad} rad"
    );
    assert!(reversed, "the cars of paper-car reverse");
    // The same cars forwards only (Dubins paths): none reverses.
    let mut forwards = paper;
    for a in &mut forwards.agents {
        if let Kinematics::Car { reverse, .. } = &mut a.kinematics {
            *reverse = false;
        }
    }
    let (_, reversed) = check_every_car_move("paper-car forwards only", &forwards);
    assert!(!reversed);
    let (_, reversed) = check_every_car_move(
        "narrow-reversing-car",
        &load("scenarios/narrow-reversing-car.toml"),
    );
    assert!(reversed, "the cars of the narrow scenario reverse");
}
