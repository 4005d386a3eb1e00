//! Parallel turns: the live agents of a step split into groups whose members cannot meet
//! within the step, so a group's agents may plan against one snapshot and move at once.
//!
//! Agents `i` and `j` may share a group only if
//! `||p_i - p_j|| > max_step_i + max_step_j + r_i + r_j`: each moves at most its top
//! speed, so every point of `i`'s move stays more than `r_i + r_j` from every point of
//! `j`'s. The split is a greedy colouring in turn order (each agent joins the first group
//! holding no agent it could meet), so it depends on the positions alone and the
//! reference simulation and the coordinator find the same groups. The turn order is agent
//! order, or front to back along the centre's heading ([`TurnOrder`],
//! [`turn_groups_ordered`]).
//!
//! A group's moves are still checked against each other before any is taken
//! ([`group_meetings`]): the check is written once here and given the distance between
//! two moves as a closure, so the coordinator's monitor (parry) and the recorder (plain
//! geometry) differ in their geometry only.

use std::collections::BTreeMap;

use crate::control::safety::SAFETY_TOLERANCE_M;
use crate::control::vocabulary::{AgentSpec, Body, TurnMode, TurnOrder};
use crate::geometry::{Point, polyline_length_m};

/// The groups of one step, in turn order, each listing its agents in agent order. Dead
/// agents take no turn and are in no group.
///
/// `Sequential` gives one group per live agent, in agent order (the paper's turns).
/// `Parallel` needs a top speed for every agent (the scenario checks see to it); without
/// one for every live agent it falls back to one group per agent.
///
/// ```
/// use shared::control::formation::Slot;
/// use shared::geometry::Point;
/// use shared::world::groups::turn_groups;
/// use shared::control::vocabulary::{AgentSpec, Body, TurnMode};
/// let mut spec = AgentSpec::new(Slot::new(0.0, 0.0), 0.5);
/// spec.max_step_m = Some(1.0);
/// let specs = [spec; 3];
/// let at = |x: f64| Body { position: Point::new(x, 0.0), radius_m: 0.5 };
/// // 0 and 1 are 2 m apart (they could meet: 1 + 1 + 0.5 + 0.5 = 3 m); 2 is far.
/// let bodies = [at(0.0), at(2.0), at(10.0)];
/// let groups = turn_groups(TurnMode::Parallel, &specs, &bodies, &[true; 3]);
/// assert_eq!(groups, vec![vec![0, 2], vec![1]]);
/// let one_by_one = turn_groups(TurnMode::Sequential, &specs, &bodies, &[true, false, true]);
/// assert_eq!(one_by_one, vec![vec![0], vec![2]]);
/// ```
pub fn turn_groups(
    mode: TurnMode,
    specs: &[AgentSpec],
    bodies: &[Body],
    alive: &[bool],
) -> Vec<Vec<usize>> {
    turn_groups_ordered(mode, TurnOrder::Agent, 0.0, specs, bodies, alive)
}

/// [`turn_groups`] with the live agents taken in `order`: for
/// [`TurnOrder::FrontFirst`], from front to back along `centre_heading_rad`, the heading of
/// the formation centre this step (agents level with each other in agent order). The
/// groups follow the order of their first agents; a group still lists its agents in
/// agent order.
///
/// ```
/// use shared::control::formation::Slot;
/// use shared::geometry::Point;
/// use shared::world::groups::turn_groups_ordered;
/// use shared::control::vocabulary::{AgentSpec, Body, TurnMode, TurnOrder};
/// let specs = [AgentSpec::new(Slot::new(0.0, 0.0), 0.5); 3];
/// let at = |x: f64| Body { position: Point::new(x, 0.0), radius_m: 0.5 };
/// // A column heading east, numbered from the back: the front one moves first.
/// let bodies = [at(0.0), at(1.0), at(2.0)];
/// let (mode, alive) = (TurnMode::Sequential, [true; 3]);
/// let east = turn_groups_ordered(mode, TurnOrder::FrontFirst, 0.0, &specs, &bodies, &alive);
/// assert_eq!(east, vec![vec![2], vec![1], vec![0]]);
/// let west = std::f64::consts::PI;
/// let back = turn_groups_ordered(mode, TurnOrder::FrontFirst, west, &specs, &bodies, &alive);
/// assert_eq!(back, vec![vec![0], vec![1], vec![2]]);
/// ```
pub fn turn_groups_ordered(
    mode: TurnMode,
    order: TurnOrder,
    centre_heading_rad: f64,
    specs: &[AgentSpec],
    bodies: &[Body],
    alive: &[bool],
) -> Vec<Vec<usize>> {
    // Moving all at once, the agents take no turns: agent order, nothing to sort.
    let order = match mode {
        TurnMode::Simultaneous => TurnOrder::Agent,
        _ => order,
    };
    let live = turn_order(order, centre_heading_rad, bodies, alive);
    match mode {
        TurnMode::Sequential => live.into_iter().map(|i| vec![i]).collect(),
        TurnMode::Parallel => {
            let mut groups = parallel_groups(specs, bodies, live.into_iter());
            for group in &mut groups {
                group.sort_unstable();
            }
            groups
        }
        TurnMode::Simultaneous => {
            if live.is_empty() {
                Vec::new()
            } else {
                vec![live]
            }
        }
    }
}

/// The live agents of `bodies` in turn `order` (see [`turn_groups_ordered`]).
fn turn_order(
    order: TurnOrder,
    centre_heading_rad: f64,
    bodies: &[Body],
    alive: &[bool],
) -> Vec<usize> {
    let mut live: Vec<usize> = (0..bodies.len())
        .filter(|&i| alive.get(i).copied().unwrap_or(false))
        .collect();
    if order == TurnOrder::FrontFirst {
        let (sin, cos) = centre_heading_rad.sin_cos();
        let ahead_m = |i: usize| {
            let p = bodies[i].position;
            // `+ 0.0` makes -0.0 level with 0.0 for `total_cmp`.
            p.x * cos + p.y * sin + 0.0
        };
        // A stable sort: agents level with each other keep agent order.
        live.sort_by(|&a, &b| ahead_m(b).total_cmp(&ahead_m(a)));
    }
    live
}

/// How far agent `i` reaches within a step: its top speed plus its radius (`None`
/// without a top speed: it could reach anything).
fn reach_m(spec: &AgentSpec) -> Option<f64> {
    spec.max_step_m.map(|s| s + spec.radius_m)
}

/// Whether agents `a` and `b` (reaches `ra`, `rb`) could meet within the step.
fn could_meet(a: &Point, ra: f64, b: &Point, rb: f64) -> bool {
    (a - b).norm() <= ra + rb
}

fn parallel_groups(
    specs: &[AgentSpec],
    bodies: &[Body],
    live: impl Iterator<Item = usize>,
) -> Vec<Vec<usize>> {
    let live: Vec<usize> = live.collect();
    if live.iter().any(|&i| reach_m(&specs[i]).is_none()) {
        return live.into_iter().map(|i| vec![i]).collect();
    }
    // A uniform grid of cells twice the largest reach: two agents that could meet lie in
    // the same or in neighbouring cells.
    let largest_m = live
        .iter()
        .filter_map(|&i| reach_m(&specs[i]))
        .fold(0.0_f64, f64::max);
    let cell_m = (2.0 * largest_m).max(1e-6);
    let cell_of = |p: &Point| -> (i64, i64) {
        ((p.x / cell_m).floor() as i64, (p.y / cell_m).floor() as i64)
    };
    let mut groups: Vec<Vec<usize>> = Vec::new();
    // For each cell, the agents placed so far with their groups.
    let mut placed: BTreeMap<(i64, i64), Vec<(usize, usize)>> = BTreeMap::new();
    for i in live {
        let reach_i = reach_m(&specs[i]).unwrap_or(f64::INFINITY);
        let p = bodies[i].position;
        let (cx, cy) = cell_of(&p);
        let mut taken: Vec<usize> = Vec::new();
        for dx in -1..=1 {
            for dy in -1..=1 {
                for &(j, g) in placed.get(&(cx + dx, cy + dy)).into_iter().flatten() {
                    let reach_j = reach_m(&specs[j]).unwrap_or(f64::INFINITY);
                    if could_meet(&p, reach_i, &bodies[j].position, reach_j) {
                        taken.push(g);
                    }
                }
            }
        }
        let group = (0..groups.len())
            .find(|g| !taken.contains(g))
            .unwrap_or(groups.len());
        if group == groups.len() {
            groups.push(Vec::new());
        }
        groups[group].push(i);
        placed.entry((cx, cy)).or_default().push((i, group));
    }
    groups
}

/// One move of a group of turns, as [`group_meetings`] looks at it.
#[derive(Clone, Copy, Debug)]
pub struct GroupMove<'a> {
    /// The moving agent's radius, in metres.
    pub radius_m: f64,
    /// Its move, from where it stands.
    pub waypoints: &'a [Point],
    /// Already refused on its own: it will not be taken. [`group_meetings`] then looks
    /// at it no more; [`simultaneous_meetings`] takes its agent as standing at the first
    /// of `waypoints`.
    pub refused: bool,
}

/// Two moves of one group that come within their radii sum of each other.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Meeting {
    /// The other move's index in the group.
    pub mate: usize,
    /// The smallest distance between the two moves, in metres.
    pub distance_m: f64,
    /// The two agents' radii sum, in metres.
    pub reach_m: f64,
}

/// For each move of a group (agents that planned against one snapshot and move at once),
/// the first group mate whose whole move comes within their radii sum of it, less
/// [`SAFETY_TOLERANCE_M`]; `None` for a move that meets no mate. Both moves of a meeting
/// are refused, so a move refused already (on its own, or by an earlier meeting) is not
/// looked at again. Pairs are taken in the order `(1, 0), (2, 0), (2, 1), (3, 0), ...`.
///
/// `distance_m(a, b)`: the smallest distance between two polylines. Every point of a
/// move lies within its length of its start, so pairs whose starts are farther apart
/// than both lengths and the radii sum are never measured.
///
/// ```
/// use shared::geometry::{Point, distance_polyline_polyline};
/// use shared::world::groups::{GroupMove, group_meetings};
/// let a = [Point::new(0.0, 0.0), Point::new(2.0, 0.0)];
/// let b = [Point::new(4.0, 0.0), Point::new(2.5, 0.0)];
/// let far = [Point::new(20.0, 0.0)];
/// let mv = |waypoints| GroupMove { radius_m: 0.5, waypoints, refused: false };
/// let meets = group_meetings(&[mv(&a), mv(&b), mv(&far)], distance_polyline_polyline);
/// assert_eq!(meets[0].map(|m| m.mate), Some(1));
/// assert_eq!(meets[1].map(|m| m.mate), Some(0));
/// assert_eq!(meets[2], None);
/// ```
pub fn group_meetings(
    moves: &[GroupMove<'_>],
    distance_m: impl Fn(&[Point], &[Point]) -> f64,
) -> Vec<Option<Meeting>> {
    let lengths_m: Vec<f64> = moves
        .iter()
        .map(|m| polyline_length_m(m.waypoints))
        .collect();
    let mut meetings: Vec<Option<Meeting>> = vec![None; moves.len()];
    let out = |i: usize, meetings: &[Option<Meeting>]| moves[i].refused || meetings[i].is_some();
    for i in 0..moves.len() {
        for j in 0..i {
            if out(i, &meetings) || out(j, &meetings) {
                continue;
            }
            let (a, b) = (&moves[i], &moves[j]);
            let (Some(start_a), Some(start_b)) = (a.waypoints.first(), b.waypoints.first()) else {
                continue;
            };
            let reach_m = a.radius_m + b.radius_m;
            if (start_a - start_b).norm() > lengths_m[i] + lengths_m[j] + reach_m {
                continue;
            }
            let d_m = distance_m(a.waypoints, b.waypoints);
            if d_m < reach_m - SAFETY_TOLERANCE_M {
                meetings[i] = Some(Meeting {
                    mate: j,
                    distance_m: d_m,
                    reach_m,
                });
                meetings[j] = Some(Meeting {
                    mate: i,
                    distance_m: d_m,
                    reach_m,
                });
            }
        }
    }
    meetings
}

/// For each move of a group made at once (every agent moving at a constant speed along
/// its move over the same time: [`TurnMode::Simultaneous`], ORCA's own model), the
/// first mate it comes within their radii sum of, less [`SAFETY_TOLERANCE_M`], at the
/// same time; `None` for a move that is taken.
///
/// A move marked `refused` is not taken: its agent stands, and `waypoints` must hold
/// just where it stands. So are the moves found here: in rounds, every move still
/// taken that comes within reach of a standing agent is refused, and of two taken moves
/// that come within reach of each other, the one whose agent standing would let the
/// other pass (a queue: the follower), the later in the list if either would, both if
/// neither would. The refused stand from the next round on, until a round refuses
/// none. Each round looks at the standing and the taken as the round found them, so
/// the moves refused do not depend on the order of the list, but for that tie (and
/// which mate is named: the first in the list).
///
/// `distance_m(a, b)`: the smallest distance between two agents moving along `a` and
/// `b` at the same time (a single point stands). Pairs whose starts are farther apart
/// than both lengths and the radii sum are never measured.
///
/// ```
/// use shared::geometry::{Point, distance_at_the_same_time_m};
/// use shared::world::groups::{GroupMove, simultaneous_meetings};
/// // A queue: the follower moves into where the leader stood, while the leader leaves.
/// let leader = [Point::new(1.0, 0.0), Point::new(2.0, 0.0)];
/// let follower = [Point::new(0.0, 0.0), Point::new(1.0, 0.0)];
/// let mv = |waypoints, refused| GroupMove { radius_m: 0.4, waypoints, refused };
/// let taken = simultaneous_meetings(
///     &[mv(&leader, false), mv(&follower, false)],
///     distance_at_the_same_time_m,
/// );
/// assert_eq!(taken, vec![None, None]);
/// // The leader refused (it stands): the follower would run into it, and is refused too.
/// let stands = [Point::new(1.0, 0.0)];
/// let cascade = simultaneous_meetings(
///     &[mv(&stands, true), mv(&follower, false)],
///     distance_at_the_same_time_m,
/// );
/// assert_eq!(cascade[0], None);
/// assert_eq!(cascade[1].map(|m| m.mate), Some(0));
/// ```
pub fn simultaneous_meetings(
    moves: &[GroupMove<'_>],
    distance_m: impl Fn(&[Point], &[Point]) -> f64,
) -> Vec<Option<Meeting>> {
    let n = moves.len();
    let lengths_m: Vec<f64> = moves
        .iter()
        .map(|m| polyline_length_m(m.waypoints))
        .collect();
    let mut standing: Vec<bool> = moves.iter().map(|m| m.refused).collect();
    let mut meetings: Vec<Option<Meeting>> = vec![None; n];
    loop {
        let mut found: Vec<Option<Meeting>> = vec![None; n];
        for i in 0..n {
            for j in 0..i {
                if standing[i] && standing[j] {
                    continue;
                }
                let (a, b) = (&moves[i], &moves[j]);
                let (Some(start_a), Some(start_b)) = (a.waypoints.first(), b.waypoints.first())
                else {
                    continue;
                };
                let reach_m = a.radius_m + b.radius_m;
                let length_m = |k: usize| if standing[k] { 0.0 } else { lengths_m[k] };
                if (start_a - start_b).norm() > length_m(i) + length_m(j) + reach_m {
                    continue;
                }
                let (path_a, path_b) = (
                    if standing[i] {
                        &a.waypoints[..1]
                    } else {
                        a.waypoints
                    },
                    if standing[j] {
                        &b.waypoints[..1]
                    } else {
                        b.waypoints
                    },
                );
                let d_m = distance_m(path_a, path_b);
                if d_m < reach_m - SAFETY_TOLERANCE_M {
                    // Two moves taken: one agent standing may let the other pass (a
                    // queue: the follower stands, the leader goes on); refuse just that
                    // one (the later in the list if either would do), else both.
                    let mut refuse = [i, j];
                    if !standing[i] && !standing[j] {
                        let lets_pass = |mv: &[Point], stands: &Point| {
                            distance_m(mv, std::slice::from_ref(stands))
                                >= reach_m - SAFETY_TOLERANCE_M
                        };
                        match (
                            lets_pass(b.waypoints, start_a),
                            lets_pass(a.waypoints, start_b),
                        ) {
                            (true, _) => refuse = [i, i],
                            (false, true) => refuse = [j, j],
                            (false, false) => {}
                        }
                    }
                    for (k, mate) in [(i, j), (j, i)] {
                        if refuse.contains(&k)
                            && !standing[k]
                            && found[k].is_none_or(|m| mate < m.mate)
                        {
                            found[k] = Some(Meeting {
                                mate,
                                distance_m: d_m,
                                reach_m,
                            });
                        }
                    }
                }
            }
        }
        if found.iter().all(Option::is_none) {
            return meetings;
        }
        for (k, meeting) in found.into_iter().enumerate() {
            if meeting.is_some() {
                standing[k] = true;
                meetings[k] = meeting;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::formation::Slot;

    #[test]
    fn no_two_agents_of_a_group_could_meet_and_every_live_agent_has_one_group() {
        let mut spec = AgentSpec::new(Slot::new(0.0, 0.0), 0.3);
        spec.max_step_m = Some(0.4);
        let n = 300;
        let specs = vec![spec; n];
        // A dense pseudo-random cloud.
        let bodies: Vec<Body> = (0..n)
            .map(|i| {
                let t = i as f64;
                Body {
                    position: Point::new((t * 7.31).sin() * 8.0, (t * 3.17).cos() * 8.0),
                    radius_m: 0.3,
                }
            })
            .collect();
        let alive: Vec<bool> = (0..n).map(|i| i % 17 != 3).collect();
        for order in TurnOrder::ALL {
            let groups =
                turn_groups_ordered(TurnMode::Parallel, order, 0.7, &specs, &bodies, &alive);
            check_groups(&groups, &bodies, &alive);
        }
    }

    /// Every live agent in one group, none of two that could meet (top speed 0.4 m,
    /// radius 0.3 m) in the same, agent order within each, and fewer groups than agents.
    fn check_groups(groups: &[Vec<usize>], bodies: &[Body], alive: &[bool]) {
        let n = bodies.len();
        let mut seen = vec![0; n];
        for g in groups {
            assert!(g.windows(2).all(|w| w[0] < w[1]), "agent order in {g:?}");
            for (k, &i) in g.iter().enumerate() {
                seen[i] += 1;
                for &j in &g[..k] {
                    let d = (bodies[i].position - bodies[j].position).norm();
                    assert!(
                        d > 0.4 + 0.4 + 0.3 + 0.3,
                        "{i} and {j} share a group at {d} m"
                    );
                }
            }
        }
        for i in 0..n {
            assert_eq!(seen[i], usize::from(alive[i]), "agent {i}");
        }
        assert!(
            groups.len() < alive.iter().filter(|a| **a).count(),
            "some parallelism"
        );
    }

    #[test]
    fn front_first_turns_go_from_front_to_back_and_level_agents_in_agent_order() {
        let mut spec = AgentSpec::new(Slot::new(0.0, 0.0), 0.3);
        spec.max_step_m = Some(0.4);
        let specs = vec![spec; 6];
        let at = |x: f64, y: f64| Body {
            position: Point::new(x, y),
            radius_m: 0.3,
        };
        // Heading east: agent 4 is furthest ahead, then 1 and 3 level (at -0.0 and 0.0 m
        // along the heading), then 0; agent 2 is dead and 5 is last.
        let bodies = [
            at(-1.0, 0.0),
            at(-0.0, -1.0),
            at(9.0, 9.0),
            at(0.0, 1.0),
            at(2.0, 0.0),
            at(-3.0, 0.5),
        ];
        let alive = [true, true, false, true, true, true];
        let heading_rad = 0.0;
        let order = |mode| {
            turn_groups_ordered(
                mode,
                TurnOrder::FrontFirst,
                heading_rad,
                &specs,
                &bodies,
                &alive,
            )
        };
        let one_by_one: Vec<usize> = order(TurnMode::Sequential).concat();
        assert_eq!(one_by_one, vec![4, 1, 3, 0, 5]);
        // All at once: one group, in agent order.
        assert_eq!(order(TurnMode::Simultaneous), vec![vec![0, 1, 3, 4, 5]]);
        // In parallel the front agent opens the first group.
        let parallel = order(TurnMode::Parallel);
        assert!(parallel[0].contains(&4), "{parallel:?}");
        check_groups(&parallel, &bodies, &alive);
        // Agent order is unchanged by the heading.
        let agent_order = turn_groups_ordered(
            TurnMode::Sequential,
            TurnOrder::Agent,
            heading_rad,
            &specs,
            &bodies,
            &alive,
        );
        assert_eq!(
            agent_order,
            turn_groups(TurnMode::Sequential, &specs, &bodies, &alive)
        );
        assert_eq!(agent_order.concat(), vec![0, 1, 3, 4, 5]);
    }

    #[test]
    fn a_move_refused_or_met_already_meets_no_one() {
        use crate::geometry::distance_polyline_polyline;
        let a = [Point::new(0.0, 0.0), Point::new(2.0, 0.0)];
        let b = [Point::new(4.0, 0.0), Point::new(2.5, 0.0)];
        let c = [Point::new(1.0, 3.0), Point::new(1.0, 0.2)];
        let mv = |waypoints, refused| GroupMove {
            radius_m: 0.5,
            waypoints,
            refused,
        };
        // b and c both come near a; a meets b first, so c (which meets only a) goes.
        let meets = group_meetings(&[mv(&a, false), mv(&b, false), mv(&c, false)], |p, q| {
            distance_polyline_polyline(p, q)
        });
        assert_eq!(
            meets.iter().map(|m| m.map(|m| m.mate)).collect::<Vec<_>>(),
            [Some(1), Some(0), None]
        );
        // a refused on its own: nobody meets it.
        let meets = group_meetings(
            &[mv(&a, true), mv(&b, false), mv(&c, false)],
            distance_polyline_polyline,
        );
        assert_eq!(meets, vec![None; 3]);
        // The distance is the closure's: a closure that says "far" finds no meeting.
        let meets = group_meetings(&[mv(&a, false), mv(&b, false)], |_, _| 10.0);
        assert_eq!(meets, vec![None; 2]);
    }
}
