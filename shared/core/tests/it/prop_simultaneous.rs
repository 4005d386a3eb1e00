//! Settling a group of moves made at once ([`simultaneous_meetings`], ORCA's own model):
//! whatever the moves, the moves taken and the agents left standing never come within
//! their radii sum of each other at the same instant; a move refused before stays
//! refused; and where no two agents meet, nothing is refused.

use proptest::prelude::*;
use shared::control::safety::SAFETY_TOLERANCE_M;
use shared::geometry::{Point, distance_at_the_same_time_m};
use shared::world::groups::{GroupMove, Meeting, simultaneous_meetings};

/// One agent of a group: where it stands, its radius, its move (relative offsets of the
/// waypoints after the first) and whether its move was refused before.
#[derive(Clone, Debug)]
struct Agent {
    start: Point,
    radius_m: f64,
    offsets: Vec<(f64, f64)>,
    refused: bool,
}

/// Up to 8 agents on a grid 1.2 m apart (so none overlaps another where it stands), each
/// with a move of up to three legs of up to `leg_m` each way.
fn group(leg_m: f64) -> impl Strategy<Value = Vec<Agent>> {
    let agent = (
        0.2..0.55_f64,
        prop::collection::vec((-leg_m..leg_m, -leg_m..leg_m), 0..4),
        prop::bool::weighted(0.2),
    );
    prop::collection::vec(agent, 2..9).prop_map(|agents| {
        agents
            .into_iter()
            .enumerate()
            .map(|(k, (radius_m, offsets, refused))| Agent {
                start: Point::new(1.2 * (k % 3) as f64, 1.2 * (k / 3) as f64),
                radius_m,
                offsets,
                refused,
            })
            .collect()
    })
}

/// Each agent's move: its start, then each leg added in turn.
fn waypoints(agent: &Agent) -> Vec<Point> {
    let mut points = vec![agent.start];
    for (dx, dy) in &agent.offsets {
        let last = *points.last().expect("a start");
        points.push(Point::new(last.x + dx, last.y + dy));
    }
    points
}

fn settle(agents: &[Agent], moves: &[Vec<Point>]) -> Vec<Option<Meeting>> {
    let group: Vec<GroupMove<'_>> = agents
        .iter()
        .zip(moves)
        .map(|(a, mv)| GroupMove {
            radius_m: a.radius_m,
            waypoints: if a.refused { &mv[..1] } else { mv },
            refused: a.refused,
        })
        .collect();
    simultaneous_meetings(&group, distance_at_the_same_time_m)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn what_is_taken_and_what_stands_never_meet_at_once(agents in group(1.0)) {
        let moves: Vec<Vec<Point>> = agents.iter().map(waypoints).collect();
        let meetings = settle(&agents, &moves);
        // Where each agent is over the step: along its move if taken, else where it stands.
        let paths: Vec<&[Point]> = agents
            .iter()
            .zip(&moves)
            .zip(&meetings)
            .map(|((a, mv), m)| if a.refused || m.is_some() { &mv[..1] } else { &mv[..] })
            .collect();
        for i in 0..agents.len() {
            if agents[i].refused {
                prop_assert!(meetings[i].is_none(), "a move refused before was named again");
            }
            for j in 0..i {
                let reach_m = agents[i].radius_m + agents[j].radius_m;
                let d_m = distance_at_the_same_time_m(paths[i], paths[j]);
                prop_assert!(
                    d_m >= reach_m - SAFETY_TOLERANCE_M,
                    "agents {} and {} come within {} m (reach {})", i, j, d_m, reach_m
                );
            }
        }
    }

    #[test]
    fn where_no_two_agents_meet_nothing_is_refused(agents in group(0.12)) {
        let moves: Vec<Vec<Point>> = agents.iter().map(waypoints).collect();
        let paths: Vec<&[Point]> = agents
            .iter()
            .zip(&moves)
            .map(|(a, mv)| if a.refused { &mv[..1] } else { &mv[..] })
            .collect();
        let clear = (0..agents.len()).all(|i| {
            (0..i).all(|j| {
                distance_at_the_same_time_m(paths[i], paths[j])
                    >= agents[i].radius_m + agents[j].radius_m - SAFETY_TOLERANCE_M
            })
        });
        prop_assume!(clear);
        prop_assert!(settle(&agents, &moves).iter().all(Option::is_none));
    }
}

/// A queue: the follower moves into where its leader stood while the leader leaves; both
/// are taken. Were the leader to stand, the follower would run into it: refused then.
/// Two agents swapping places head-on both stand.
#[test]
fn a_queue_moves_on_and_a_head_on_swap_stands() {
    let mv = |waypoints, refused| GroupMove {
        radius_m: 0.4,
        waypoints,
        refused,
    };
    let leader = [Point::new(1.0, 0.0), Point::new(2.0, 0.0)];
    let follower = [Point::new(0.0, 0.0), Point::new(1.0, 0.0)];
    assert_eq!(
        simultaneous_meetings(
            &[mv(&leader, false), mv(&follower, false)],
            distance_at_the_same_time_m
        ),
        vec![None, None]
    );
    // The leader's move refused: it stands, and the follower's move is refused after it.
    let stands = [Point::new(1.0, 0.0)];
    let cascade = simultaneous_meetings(
        &[mv(&stands, true), mv(&follower, false)],
        distance_at_the_same_time_m,
    );
    assert_eq!(cascade[0], None);
    assert_eq!(cascade[1].map(|m| m.mate), Some(0));
    // A follower too fast for its leader: it alone is refused (the leader, going away
    // from where the follower stands, goes on).
    let fast = [Point::new(0.0, 0.0), Point::new(1.9, 0.0)];
    let slow = [Point::new(1.0, 0.0), Point::new(1.5, 0.0)];
    let caught = simultaneous_meetings(
        &[mv(&slow, false), mv(&fast, false)],
        distance_at_the_same_time_m,
    );
    assert_eq!(caught[0], None);
    assert_eq!(caught[1].map(|m| m.mate), Some(0));
    // Head on: either standing blocks the other: both stand.
    let east = [Point::new(0.0, 0.0), Point::new(2.0, 0.0)];
    let west = [Point::new(2.0, 0.0), Point::new(0.0, 0.0)];
    let swap = simultaneous_meetings(
        &[mv(&east, false), mv(&west, false)],
        distance_at_the_same_time_m,
    );
    assert!(swap.iter().all(Option::is_some));
}
