//! An agent escaping from a moving obstacle keeps clear of the polygon obstacles: with a
//! wall right behind it, the straight way out of the obstacle's reach would run into the
//! wall, and the escape goes round instead.

use shared::control::safety::check_move_against_polygons;
use shared::control::turn::TurnRequest;
use shared::geometry::{Point, Pose};
use shared::run::simulate::agent_controllers;
use shared::world::scenario::Scenario;

/// One agent (radius 0.3 m, at most 0.8 m a step) with a wall 0.15 m to its right and a
/// moving obstacle coming at it from the left.
const SCENARIO: &str = r#"
name = "escape-wall"

[field]
width_m = 20.0
height_m = 12.0

[[obstacles.polygon]]
vertices_m = [[10.45, 2.0], [11.5, 2.0], [11.5, 10.0], [10.45, 10.0]]

[[obstacles.moving]]
radius_m = 0.5
waypoints_m = [[2.3, 6.0], [10.3, 6.0]]
speed_m_per_step = 0.5

[formation]
agent_radius_m = 0.3
max_step_m = 0.8
slots = [ { r_m = 0.0, theta_deg = 0.0 } ]

[path]
start = { x_m = 3.0, y_m = 1.0, heading_deg = 0.0 }
goal = { x_m = 17.0, y_m = 1.0, heading_deg = 0.0 }
turning_radius_m = 1.0
step_m = 0.5
centre_clearance_m = 0.3
"#;

#[test]
fn an_escape_from_a_moving_obstacle_goes_round_a_wall_not_into_it() {
    let scenario = Scenario::parse(SCENARIO, "escape-wall.toml").expect("a valid scenario");
    let controllers = agent_controllers(&scenario).expect("controllers");
    let mover = &scenario.moving[0];
    // The agent beside the wall, the obstacle already on it: at step 14 it is at
    // (9.3, 6.0), 0.7 m from the agent (their radii make 0.8), and comes on at 0.5 m a
    // step: the straight way out runs into the wall.
    let me = Point::new(10.0, 6.0);
    let step = 14;
    let now = mover.disk_at(step);
    assert!((now.centre - Point::new(9.3, 6.0)).norm() < 1e-9, "{now:?}");
    let centre = Pose::new(3.0, 1.0, 0.0);
    let mv = controllers[0].plan(&TurnRequest::new(centre, me, &[]).at_step(step));
    let radius_m = scenario.agents[0].radius_m;
    check_move_against_polygons(&scenario.polygons, radius_m, &mv.waypoints)
        .unwrap_or_else(|v| panic!("the move enters the wall: {v:?}, {mv:?}"));
    // And it got away: where it ends, the obstacle (next step) does not reach it.
    let end = *mv.waypoints.last().expect("a move");
    let next = mover.disk_at(step + 1);
    assert!(
        (end - next.centre).norm() >= next.radius_m + radius_m,
        "still in the obstacle's way at {end:?}: {mv:?}"
    );
    assert!(mv.waypoints.len() >= 2, "the agent moved: {mv:?}");
}
