//! The formation searched together (`coordinator bound --together`): each agent's best
//! track on the lattice in turn, kept clear of the tracks of the agents before it
//! (prioritised planning, offline, knowing the whole centre path). Every track is
//! achievable and the tracks keep clear of each other whatever the order of the turns
//! within a step, so the least mean deviation any method can give the formation, mates
//! included, lies between the bound and this figure. It says how much of the gap between
//! a run and the bound (which counts no mate) the mates force.
//!
//! Prioritised planning is not optimal: an order can leave a later agent worse off than
//! another order would, or with no track at all. A few orders are tried and the best
//! kept ([`ORDERS`]).

use serde::Serialize;
use shared::geometry::{Point, Pose, Vector};
use shared::world::scenario::Scenario;

use super::AgentBound;
use super::alone::{MateTrack, lattice_for, searched_track};

/// The orders the agents are searched in.
pub const ORDERS: [Order; 4] = [
    Order::FrontFirst,
    Order::BackFirst,
    Order::LargestBoundFirst,
    Order::AsListed,
];

/// An order of the agents, for the search and for their turns within every step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// The agent whose slot lies farthest ahead of the centre at the start first (the
    /// runs' own turn order, there: an agent moves into the place the one ahead leaves).
    FrontFirst,
    /// The agent whose slot lies farthest behind the centre at the start first.
    BackFirst,
    /// The agent whose bound is largest first (the one with the hardest way picks it).
    LargestBoundFirst,
    /// The scenario's order.
    AsListed,
}

impl Order {
    /// The agents' indices in this order, `bounds` being their bounds and `start` the
    /// centre's first pose (ties keep the scenario's order).
    pub fn of(self, bounds: &[AgentBound], scenario: &Scenario, start: &Pose) -> Vec<usize> {
        let mut order: Vec<usize> = (0..bounds.len()).collect();
        let ahead_m = |a: usize| {
            let heading = Vector::new(start.heading_rad.cos(), start.heading_rad.sin());
            (scenario.agents[a].slot.ideal_position(start) - Point::new(start.x_m, start.y_m))
                .dot(&heading)
        };
        match self {
            Self::FrontFirst => order.sort_by(|a, b| ahead_m(*b).total_cmp(&ahead_m(*a))),
            Self::BackFirst => order.sort_by(|a, b| ahead_m(*a).total_cmp(&ahead_m(*b))),
            Self::LargestBoundFirst => order.sort_by(|a, b| {
                bounds[*b]
                    .mean_deviation_m
                    .total_cmp(&bounds[*a].mean_deviation_m)
            }),
            Self::AsListed => {}
        }
        order
    }
}

/// The formation searched together in one order.
#[derive(Clone, Debug, Serialize)]
pub struct Together {
    /// The order the agents were searched in.
    pub order: Order,
    /// The mean deviation of the tracks found, over the agents and steps, in metres.
    pub mean_deviation_m: f64,
    /// Each agent's mean deviation, by agent index, in metres.
    pub per_agent_mean_deviation_m: Vec<f64>,
    /// Each agent's track, by agent index: its position at steps 0 ..= T.
    #[serde(skip)]
    pub tracks: Vec<MateTrack>,
}

/// The formation of `scenario` along `centre_path` searched together in `order`;
/// `bounds` are the agents' bounds (they size each search's window), `per_move` the
/// lattice points per top-speed move ([`lattice_for`]). `None` when an agent has no top
/// speed (the search needs one), the path has no step, or the search finds no track for
/// an agent clear of those before it.
pub fn formation_together(
    scenario: &Scenario,
    centre_path: &[Pose],
    bounds: &[AgentBound],
    order: Order,
    per_move: u32,
) -> Option<Together> {
    let (first, rest) = centre_path.split_first()?;
    if rest.is_empty() || bounds.len() != scenario.agents.len() {
        return None;
    }
    let mut found: Vec<Option<(f64, MateTrack)>> = vec![None; scenario.agents.len()];
    let mut mates: Vec<MateTrack> = Vec::with_capacity(scenario.agents.len());
    let agents = order.of(bounds, scenario, first);
    for (i, &agent) in agents.iter().enumerate() {
        let spec = &scenario.agents[agent];
        let cap = spec.max_step_m?;
        let lattice = lattice_for(cap, bounds[agent].max_deviation_m, per_move);
        let after: Vec<MateTrack> = agents[i + 1..]
            .iter()
            .map(|&a| MateTrack {
                radius_m: scenario.agents[a].radius_m,
                positions: vec![scenario.agents[a].slot.ideal_position(first)],
            })
            .collect();
        let (sum_m, track) =
            searched_track(scenario, spec, centre_path, lattice, cap, &mates, &after)?;
        let positions: Vec<Point> = std::iter::once(spec.slot.ideal_position(first))
            .chain(track)
            .collect();
        let mate = MateTrack {
            radius_m: spec.radius_m,
            positions,
        };
        mates.push(mate.clone());
        found[agent] = Some((sum_m / rest.len() as f64, mate));
    }
    let found: Vec<(f64, MateTrack)> = found.into_iter().collect::<Option<_>>()?;
    let per_agent_mean_deviation_m: Vec<f64> = found.iter().map(|(m, _)| *m).collect();
    let mean_deviation_m =
        per_agent_mean_deviation_m.iter().sum::<f64>() / per_agent_mean_deviation_m.len() as f64;
    Some(Together {
        order,
        mean_deviation_m,
        per_agent_mean_deviation_m,
        tracks: found.into_iter().map(|(_, t)| t).collect(),
    })
}

/// The best of [`ORDERS`] (the least mean deviation), the orders shared between two
/// threads, `per_move` lattice points per top-speed move; `None` when no order gives
/// every agent a track.
pub fn best_formation_together(
    scenario: &Scenario,
    centre_path: &[Pose],
    bounds: &[AgentBound],
    per_move: u32,
) -> Option<Together> {
    let results: Vec<Option<Together>> = std::thread::scope(|scope| {
        let (mine, theirs) = ORDERS.split_at(ORDERS.len() / 2);
        let other = scope.spawn(|| {
            theirs
                .iter()
                .map(|o| formation_together(scenario, centre_path, bounds, *o, per_move))
                .collect::<Vec<_>>()
        });
        let mut results: Vec<Option<Together>> = mine
            .iter()
            .map(|o| formation_together(scenario, centre_path, bounds, *o, per_move))
            .collect();
        // A panic in the other thread is a bug; it is the caller's, as it would be here.
        match other.join() {
            Ok(more) => results.extend(more),
            Err(panic) => std::panic::resume_unwind(panic),
        }
        results
    });
    results
        .into_iter()
        .flatten()
        .min_by(|a, b| a.mean_deviation_m.total_cmp(&b.mean_deviation_m))
}

/// One row of [`tracks_csv`].
#[derive(Serialize)]
struct TrackRow {
    step: usize,
    agent: usize,
    x_m: f64,
    y_m: f64,
}

/// The tracks of `found` as CSV (`step`, `agent`, `x_m`, `y_m`), step by step.
pub fn tracks_csv(found: &Together) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let steps = found
        .tracks
        .iter()
        .map(|t| t.positions.len())
        .max()
        .unwrap_or(0);
    for step in 0..steps {
        for (agent, track) in found.tracks.iter().enumerate() {
            if let Some(p) = track.positions.get(step) {
                w.serialize(TrackRow {
                    step,
                    agent,
                    x_m: p.x,
                    y_m: p.y,
                })?;
            }
        }
    }
    Ok(w.into_inner()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bound::agent_bounds;
    use crate::bound::alone::{DEFAULT_POINTS_PER_MOVE, searched_track};
    use shared::control::safety::check_move;
    use shared::control::vocabulary::Body;
    use shared::geometry::DiskGrid;

    /// The paper example with every agent capped at twice the centre's step, its centre
    /// path and the agents' bounds.
    fn capped_paper() -> (Scenario, Vec<Pose>, Vec<AgentBound>) {
        let loaded = runner::loaded::load_and_plan(None).expect("the paper example");
        let mut scenario = loaded.scenario;
        for spec in &mut scenario.agents {
            spec.max_step_m = Some(0.5);
        }
        let path = loaded.centre_path;
        let bounds = agent_bounds(&scenario, &path, || {}).expect("bounds");
        (scenario, path, bounds)
    }

    /// The tracks found together, replayed step by step with the agents taking their
    /// turns in the search's order, pass the run's own safety check (every move within
    /// the field, clear of every obstacle and of every mate where it stands) and keep the
    /// top speed; each agent does no better than alone on the same lattice (its mates
    /// only take places away), and the formation no better than its bound.
    #[test]
    fn the_tracks_found_together_are_safe_in_turn_and_no_better_than_alone() {
        let (scenario, path, bounds) = capped_paper();
        let obstacles = DiskGrid::new(scenario.static_obstacles());
        let steps = (path.len() - 1) as f64;
        let alone_m: Vec<f64> = scenario
            .agents
            .iter()
            .zip(&bounds)
            .map(|(spec, bound)| {
                let lattice = lattice_for(0.5, bound.max_deviation_m, DEFAULT_POINTS_PER_MOVE);
                let (sum_m, _) = searched_track(&scenario, spec, &path, lattice, 0.5, &[], &[])
                    .expect("a track alone");
                sum_m / steps
            })
            .collect();
        let mut found_in = Vec::new();
        for order in ORDERS {
            let Some(found) =
                formation_together(&scenario, &path, &bounds, order, DEFAULT_POINTS_PER_MOVE)
            else {
                continue;
            };
            found_in.push(order);
            let turns = order.of(&bounds, &scenario, &path[0]);
            let mut at: Vec<Point> = found.tracks.iter().map(|t| t.positions[0]).collect();
            for k in 1..path.len() {
                for &agent in &turns {
                    let others: Vec<Body> = (0..at.len())
                        .filter(|&j| j != agent)
                        .map(|j| Body {
                            position: at[j],
                            radius_m: scenario.agents[j].radius_m,
                        })
                        .collect();
                    let to = found.tracks[agent].positions[k];
                    let from = at[agent];
                    assert!(
                        (to - from).norm() <= 0.5 + 1e-9,
                        "{order:?} agent {agent} step {k}"
                    );
                    let radius_m = scenario.agents[agent].radius_m;
                    let checked = check_move(
                        &scenario.field,
                        &obstacles,
                        &others,
                        radius_m,
                        &from,
                        &[from, to],
                        2,
                    );
                    assert!(
                        checked.is_ok(),
                        "{order:?} agent {agent} step {k}: {checked:?}"
                    );
                    at[agent] = to;
                }
            }
            for (agent, bound) in bounds.iter().enumerate() {
                let together_m = found.per_agent_mean_deviation_m[agent];
                assert!(
                    together_m >= alone_m[agent] - 1e-12,
                    "{order:?} agent {agent}"
                );
                assert!(together_m >= bound.mean_deviation_m * (1.0 - 1e-6));
            }
        }
        // The runs' own order, front first, gives every agent a track here.
        assert!(found_in.contains(&Order::FrontFirst), "{found_in:?}");
    }
}
