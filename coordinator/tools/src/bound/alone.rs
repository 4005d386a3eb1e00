//! Each agent alone among the static obstacles (`coordinator bound --alone`): how the
//! method does with no mate (the reference simulation of the scenario with that agent's
//! slot only, along the same centre path), and the best track a search over a lattice
//! finds ([`best_track_on_lattice`]). The least deviation alone lies between the cone
//! bound and the best track found; the gap between the whole formation and the agents
//! alone is what the mates cost.

use serde::Serialize;
use shared::control::best_point::nearest_free_point;
use shared::control::tracking::{Lattice, best_track_on_lattice};
use shared::control::turn::PLANNING_MARGIN_M;
use shared::control::vocabulary::AgentSpec;
use shared::geometry::{
    Disk, DiskGrid, Field, FreeSpace, InflatedPolygon, Point, PolygonLayer, Pose, Vector,
    distance_point_segment,
};
use shared::run::simulate::{SimulateError, simulate_along};
use shared::world::scenario::Scenario;

/// Lattice points per top-speed move of the searches (`bound --alone`, `--together`)
/// unless `--lattice-per-move` says otherwise: on large (a top speed of 1 m) 10 found a
/// formation together 12 % lower than 5, in five times the time.
pub const DEFAULT_POINTS_PER_MOVE: u32 = 5;

/// The lattice of the search for an agent with top speed `max_step_m` whose largest
/// deviation is at least `max_bound_m` (its bound): points `per_move` to the top speed
/// apart ([`DEFAULT_POINTS_PER_MOVE`]), up to 3 m from the slot (more than any agent
/// alone strays in the capped scenarios measured, 2.6 m at most) or half as far again as
/// the bound where that is more.
pub fn lattice_for(max_step_m: f64, max_bound_m: f64, per_move: u32) -> Lattice {
    let spacing_m = max_step_m / f64::from(per_move.max(1));
    Lattice {
        spacing_m,
        first_spacing_m: spacing_m,
        window_m: (1.5 * max_bound_m).max(3.0),
    }
}

/// The static world as one agent of radius `radius_m` sees it, in the frame the best
/// point is found in (the field inset by the radius, from (0, 0); every obstacle grown by
/// the radius).
pub struct StaticSpace {
    /// Where the frame's origin lies in the scenario's frame.
    pub offset: Vector,
    field: Field,
    obstacles: DiskGrid,
    polygons: PolygonLayer,
}

impl StaticSpace {
    /// The static world of `scenario` for `spec`.
    pub fn new(scenario: &Scenario, spec: &AgentSpec) -> Self {
        let r = spec.radius_m;
        let offset = Vector::new(r, r);
        Self {
            offset,
            field: Field::new(
                (scenario.field.width_m - 2.0 * r).max(0.0),
                (scenario.field.height_m - 2.0 * r).max(0.0),
            ),
            obstacles: DiskGrid::new(
                scenario
                    .static_obstacles()
                    .iter()
                    .map(|d| Disk {
                        centre: d.centre - offset,
                        radius_m: d.radius_m + r,
                    })
                    .collect(),
            ),
            polygons: PolygonLayer::new(
                scenario
                    .polygons
                    .iter()
                    .map(|p| InflatedPolygon::from_polygon(p.translated(&-offset), r))
                    .collect(),
            ),
        }
    }

    /// Call `with` on the free space of the agent's centre (in this frame).
    pub fn with_free_space<T>(&self, with: impl FnOnce(&FreeSpace) -> T) -> T {
        let layers = [&self.obstacles];
        let space = FreeSpace::new(self.field, &layers).with_polygons(&self.polygons);
        with(&space)
    }
}

/// One agent alone.
#[derive(Clone, Debug, Serialize)]
pub struct AgentAlone {
    /// The agent.
    pub agent: usize,
    /// The method's mean deviation with this agent alone, in metres.
    pub mean_deviation_m: f64,
    /// The mean deviation of the best track the lattice search found (`null`: without a
    /// top speed, or no track found), in metres.
    pub searched_mean_deviation_m: Option<f64>,
}

/// Agent `agent` of `scenario` alone along `centre_path`; `max_bound_m` is the bound of
/// its largest deviation (it sizes the search's window), `per_move` the search's lattice
/// points per top-speed move (`lattice_for`).
pub fn agent_alone(
    scenario: &Scenario,
    centre_path: &[Pose],
    agent: usize,
    max_bound_m: f64,
    per_move: u32,
) -> Result<AgentAlone, SimulateError> {
    let spec = &scenario.agents[agent];
    let mut one = scenario.clone();
    one.agents = vec![*spec];
    let mean_deviation_m = simulate_along(&one, centre_path)?
        .summary()
        .mean_deviation_m;
    let searched_mean_deviation_m = spec.max_step_m.and_then(|cap| {
        searched_track_m(
            scenario,
            spec,
            centre_path,
            lattice_for(cap, max_bound_m, per_move),
            cap,
        )
    });
    Ok(AgentAlone {
        agent,
        mean_deviation_m,
        searched_mean_deviation_m,
    })
}

/// The mean deviation of the best track the lattice search finds for `spec` alone.
fn searched_track_m(
    scenario: &Scenario,
    spec: &AgentSpec,
    centre_path: &[Pose],
    lattice: Lattice,
    max_step_m: f64,
) -> Option<f64> {
    let steps = centre_path.len().checked_sub(1)?;
    if steps == 0 {
        return Some(0.0);
    }
    searched_track(scenario, spec, centre_path, lattice, max_step_m, &[], &[])
        .map(|(sum_m, _)| sum_m / steps as f64)
}

/// Where a mate goes: its body's radius and its position at each step of the centre path
/// (`positions[k]` at step `k`, from 0; the scenario's frame).
#[derive(Clone, Debug)]
pub struct MateTrack {
    /// The mate's body radius, in metres.
    pub radius_m: f64,
    /// Its position at each step.
    pub positions: Vec<Point>,
}

/// The best track the lattice search finds for `spec` along `centre_path` among the
/// static obstacles and its mates: its summed deviation and its positions at steps 1 ..= T
/// (the scenario's frame); `None` when no track through the lattice exists. Alone: both
/// lists of mates empty.
///
/// The agents take their turns in one order every step (the order they are searched in):
/// - `before`: the mates that move before this agent in every step, with their tracks.
///   Its move keeps `r + r_mate` (and the run's planning margin) from where each stands
///   after its own move of that step, and each place it stands keeps as far from the
///   mates' moves of the next step.
/// - `after`: the mates that move after it, not searched yet (only their places at step
///   0 count): its first move keeps as far from them. Each of them keeps clear of this
///   agent when its turn comes (it has this agent among its `before`).
pub fn searched_track(
    scenario: &Scenario,
    spec: &AgentSpec,
    centre_path: &[Pose],
    lattice: Lattice,
    max_step_m: f64,
    before: &[MateTrack],
    after: &[MateTrack],
) -> Option<(f64, Vec<Point>)> {
    let (first, rest) = centre_path.split_first()?;
    let world = StaticSpace::new(scenario, spec);
    // In the best point's frame.
    let to_frame = |p: Point| p - world.offset;
    let start = to_frame(spec.slot.ideal_position(first));
    let slots: Vec<Point> = rest
        .iter()
        .map(|c| to_frame(spec.slot.ideal_position(c)))
        .collect();
    let keep_m = |m: &MateTrack| m.radius_m + spec.radius_m + PLANNING_MARGIN_M;
    // Where each mate stands during this agent's move k, and what it sweeps while this
    // agent stands at the end of that move (a segment; a point when it does not move):
    // (keep, the point, the sweep's ends). This frame.
    let bodies_of_move = |k: usize| -> Vec<(f64, Point, Point, Point)> {
        let moved = before.iter().filter_map(|m| {
            let stands = to_frame(*m.positions.get(k + 1)?);
            let next = m.positions.get(k + 2).map_or(stands, |p| to_frame(*p));
            Some((keep_m(m), stands, stands, next))
        });
        let waiting = after.iter().filter(|_| k == 0).filter_map(|m| {
            let at = to_frame(*m.positions.first()?);
            Some((keep_m(m), at, at, at))
        });
        moved.chain(waiting).collect()
    };
    world.with_free_space(|space| {
        // The slot and its nearest free point are candidates too: the lattice alone
        // would round every position by up to half its spacing.
        let anchors: Vec<Vec<Point>> = slots
            .iter()
            .map(|s| {
                std::iter::once(*s)
                    .chain(nearest_free_point(space, s).ok())
                    .collect()
            })
            .collect();
        // The mates that may come near a candidate of move k (every candidate lies
        // within the window of the slot or an anchor, the start by the first slot) or
        // within a top speed of it (the clearance is cut there).
        let near: Vec<Vec<(f64, Point, Point, Point)>> = (0..slots.len())
            .map(|k| {
                let from_slot_m = |a: &Point| (a - slots[k]).norm();
                let reach_m = max_step_m
                    + lattice.window_m
                    + anchors[k].iter().map(from_slot_m).fold(0.0, f64::max)
                    + if k == 0 { from_slot_m(&start) } else { 0.0 };
                bodies_of_move(k)
                    .into_iter()
                    .filter(|(keep_m, _, a, b)| {
                        distance_point_segment(&slots[k], a, b) <= reach_m + keep_m
                    })
                    .collect()
            })
            .collect();
        let clearance_m = |k: usize, p: &Point| {
            if !space.is_free(p, 0.0) {
                return None;
            }
            let mut clear_m = space.clearance_m(p, max_step_m).max(0.0);
            for (keep_m, _, a, b) in near.get(k).into_iter().flatten() {
                let d = distance_point_segment(p, a, b);
                if d <= *keep_m {
                    return None;
                }
                clear_m = clear_m.min(d - keep_m);
            }
            Some(clear_m)
        };
        let segment_free = |k: usize, a: &Point, b: &Point| {
            space.is_segment_free(a, b, 0.0)
                && near
                    .get(k)
                    .into_iter()
                    .flatten()
                    .all(|(keep_m, stands, _, _)| distance_point_segment(stands, a, b) > *keep_m)
        };
        best_track_on_lattice(
            &start,
            &slots,
            &anchors,
            max_step_m,
            lattice,
            clearance_m,
            segment_free,
        )
        .map(|(sum_m, track)| {
            let track = track.iter().map(|p| p + world.offset).collect();
            (sum_m, track)
        })
    })
}
