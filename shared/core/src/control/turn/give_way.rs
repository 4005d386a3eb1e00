//! Giving way to a mate far behind its slot.
//!
//! An agent on its slot may stand where a mate far behind has to pass: the mate's search
//! round the obstacles (`crate::control::tracking::first_move_round_obstacles`) sees it only for
//! the mate's first move, and the mate waits or goes the long way round. The agent
//! whose turn it is knows every mate's slot and where each stands, so it can tell which
//! mates lag far behind theirs ([`GIVE_WAY_MARGIN_M`] more than itself), predict the track
//! each would search (its first move round every body standing, this agent's included,
//! its later moves round the static obstacles), and keep its own later moves off those
//! tracks: it steps aside early, and the mate passes. Nothing new crosses between the
//! processes: each agent predicts from the world its turn brings, the same in the
//! reference simulation and in the agent process. The prediction only chooses among
//! safe moves; the move is still free of every body standing and within the top speed.

use crate::control::tracking;
use crate::control::vocabulary::{Body, Move};
use crate::geometry::{
    Disk, DiskGrid, Field, FreeSpace, Point, PolygonLayer, Pose, RegionGrid, Vector,
};

use super::{Controller, PLANNING_MARGIN_M, TurnController};

/// How much farther behind its slot than this agent a mate must be for this agent to give
/// way to it, in metres. Measured on the capped paper, dense, narrow and large scenarios
/// and 26 other fields (`docs/measurements.md`): with 0.5 m agents gave way to mates only
/// a little behind, and one field of dense obstacles doubled its mean deviation; with 1 m
/// no field's mean deviation rose by more than 0.3 %.
pub const GIVE_WAY_MARGIN_M: f64 = 1.0;

/// A mate as the world shows it to the agent whose turn it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MateView {
    /// The mate's agent index.
    pub agent: usize,
    /// Where it stands.
    pub position: Point,
    /// Whether it belongs to the formation (false: frozen as an obstacle).
    pub alive: bool,
}

/// A mate far behind its slot, which the agent whose turn it is gives way to
/// ([`super::Aim::lagging`]). It has the agent's radius.
#[derive(Clone, Debug, PartialEq)]
pub struct LaggingMate {
    /// Where it stands (world coordinates).
    pub position: Point,
    /// Its top speed, metres a step.
    pub max_step_m: f64,
    /// Its slot over the look-ahead (world coordinates), as [`super::Aim::slots`].
    pub slots: Vec<Point>,
}

impl TurnController {
    /// Whether this agent may give way to a mate: it looks ahead (the best-point
    /// controller, a top speed, a look-ahead, no heading) and knows the formation
    /// ([`Self::with_formation`]). Otherwise the mates given to
    /// [`Self::plan`] change nothing, and a caller need not list them.
    pub fn gives_way(&self) -> bool {
        matches!(self.controller, Controller::BestPoint(_))
            && self.spec.max_step_m.is_some()
            && self.spec.horizon_steps > 0
            && !self.spec.kinematics.has_heading()
            && !self.formation.is_empty()
    }

    /// The mates agent `agent` plans with ([`Self::plan`]): every view of
    /// `views` but its own, or none when it does not give way ([`Self::gives_way`]):
    /// listing them is a turn's cost at 200 agents, so `views` is only walked when used.
    pub fn mate_views(
        &self,
        agent: usize,
        views: impl IntoIterator<Item = MateView>,
    ) -> Vec<MateView> {
        if !self.gives_way() {
            return Vec::new();
        }
        views.into_iter().filter(|m| m.agent != agent).collect()
    }

    /// The mates of `mates` this agent (at `me`, its slots `slots`, the centre at
    /// `centre` then `ahead`) gives way to: alive, sensed, within the search's window
    /// ([`tracking::ROUND_WINDOW_RADII`] radii), of the same radius and with a top speed,
    /// and farther from their slot than this agent by more than [`GIVE_WAY_MARGIN_M`].
    /// Their slots are taken over this agent's look-ahead.
    pub(super) fn lagging_mates(
        &self,
        centre: &Pose,
        ahead: &[Pose],
        me: &Point,
        slots: &[Point],
        mates: &[MateView],
    ) -> Vec<LaggingMate> {
        let Some(my_slot) = slots.first() else {
            return Vec::new();
        };
        let my_deviation_m = (me - my_slot).norm();
        let window_m = tracking::ROUND_WINDOW_RADII * self.spec.radius_m;
        let horizon = slots.len().saturating_sub(1).min(ahead.len());
        mates
            .iter()
            .filter(|m| m.alive && (m.position - me).norm() <= window_m)
            .filter_map(|m| {
                let spec = self.formation.get(m.agent)?;
                let max_step_m = spec.max_step_m?;
                if spec.radius_m != self.spec.radius_m
                    || !self.spec.senses(me, &m.position, spec.radius_m)
                {
                    return None;
                }
                // Its slot now first: most mates are near theirs.
                let deviation_m = (m.position - spec.slot.ideal_position(centre)).norm();
                if deviation_m <= my_deviation_m + GIVE_WAY_MARGIN_M {
                    return None;
                }
                let slots: Vec<Point> = std::iter::once(centre)
                    .chain(&ahead[..horizon])
                    .map(|c| spec.slot.ideal_position(c))
                    .collect();
                Some(LaggingMate {
                    position: m.position,
                    max_step_m,
                    slots,
                })
            })
            .collect()
    }
}

/// What an agent that gives way plans with: its planning frame and its world, the static
/// obstacles and polygons grown by its radius and the planning margin.
pub(super) struct Planning<'a> {
    /// The field its centre may use (planning frame).
    pub field: Field,
    /// The planning frame's origin in world coordinates.
    pub offset: Vector,
    /// Its radius (and its lagging mates').
    pub radius_m: f64,
    /// The static obstacles it knows of, grown (planning frame).
    pub obstacles: &'a DiskGrid,
    /// The polygons, grown (planning frame).
    pub polygons: &'a PolygonLayer,
    /// The regions a map's blocked cells close off, if any.
    pub regions: Option<&'a RegionGrid>,
    /// The bodies standing, its own excluded (world coordinates, true radii).
    pub others: &'a [Body],
}

impl Planning<'_> {
    /// The free space with `extra` disks besides the static obstacles.
    fn space<'s>(&'s self, layers: &'s [&'s DiskGrid; 2]) -> FreeSpace<'s> {
        FreeSpace::new(self.field, layers)
            .with_polygons(self.polygons)
            .with_regions(self.regions)
    }
}

/// The tracks (planning frame) the `lagging` mates would search round the obstacles over
/// their look-ahead, as the agent at `me` predicts them: from where each stands, its first
/// move round every body standing (this agent's included), its later moves round the
/// static obstacles (`statics`); each track starts with the first move's end. Only the
/// tracks that come within the search's window of `me`.
pub(super) fn predicted_tracks(
    planning: &Planning<'_>,
    lagging: &[LaggingMate],
    statics: &FreeSpace<'_>,
    me: &Point,
) -> Vec<Vec<Point>> {
    let (offset, radius_m) = (planning.offset, planning.radius_m);
    let grow_m = radius_m + PLANNING_MARGIN_M;
    let window_m = tracking::ROUND_WINDOW_RADII * radius_m;
    let me_p = me - offset;
    lagging
        .iter()
        .filter_map(|mate| {
            // What the mate sees standing: every body but its own, this agent's too.
            let bodies = DiskGrid::new(
                planning
                    .others
                    .iter()
                    .filter(|b| b.position != mate.position)
                    .map(|b| (b.position - offset, b.radius_m))
                    .chain(std::iter::once((me_p, radius_m)))
                    .map(|(centre, r)| Disk {
                        centre,
                        radius_m: r + grow_m,
                    })
                    .collect(),
            );
            let layers = [planning.obstacles, &bodies];
            let now = planning.space(&layers);
            let slots_p: Vec<Point> = mate.slots.iter().map(|s| s - offset).collect();
            tracking::track_round_obstacles(
                &now,
                tracking::LaterSpaces::Shared(statics),
                &(mate.position - offset),
                &slots_p,
                &[],
                mate.max_step_m,
                tracking::round_lattice_for(radius_m),
            )
        })
        .filter(|track| track.iter().any(|p| (p - me_p).norm() <= window_m))
        .collect()
}

/// The end (planning frame) of the first move of the best track round the obstacles over
/// `slots` (world coordinates, as [`super::Aim::slots`]; `lead` the aim's lead point)
/// that keeps the later moves off the mates' predicted tracks (`yields`): later move `k`
/// keeps clear of where each mate is after its moves `k` and `k + 1`. `space` is this
/// turn's free space (every body standing), `followed` the agent's usual move. `None`
/// when no mate is to be given way to or no such track exists.
#[allow(clippy::too_many_arguments)]
pub(super) fn first_move_giving_way(
    planning: &Planning<'_>,
    slots: &[Point],
    lead: Point,
    space: &FreeSpace<'_>,
    yields: &[Vec<Point>],
    followed: &Move,
    me: &Point,
    max_step_m: f64,
) -> Option<Point> {
    if yields.is_empty() {
        return None;
    }
    let offset = planning.offset;
    let slots_p: Vec<Point> = slots.iter().map(|s| s - offset).collect();
    // The usual move and the lead are candidates too, when straight.
    let firsts: Vec<Point> = match followed.waypoints[..] {
        [_, end] => vec![end - offset, lead - offset],
        _ => vec![lead - offset],
    };
    let keep_m = 2.0 * planning.radius_m + PLANNING_MARGIN_M;
    let grids: Vec<DiskGrid> = (1..slots_p.len())
        .map(|k| {
            DiskGrid::new(
                yields
                    .iter()
                    .flat_map(|t| t.get(k).into_iter().chain(t.get(k + 1)))
                    .map(|p| Disk {
                        centre: *p,
                        radius_m: keep_m,
                    })
                    .collect(),
            )
        })
        .collect();
    let layer_sets: Vec<[&DiskGrid; 2]> = grids.iter().map(|g| [planning.obstacles, g]).collect();
    let later: Vec<FreeSpace<'_>> = layer_sets.iter().map(|l| planning.space(l)).collect();
    let track = tracking::track_round_obstacles(
        space,
        tracking::LaterSpaces::PerMove(&later),
        &(me - offset),
        &slots_p,
        &firsts,
        max_step_m,
        tracking::round_lattice_for(planning.radius_m),
    )?;
    track.first().copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::formation::Slot;
    use crate::control::safety::check_move;
    use crate::control::turn::TurnRequest;
    use crate::control::vocabulary::{AgentSpec, ControllerSpec};

    /// A wall across the field at x = 11 with a gap 1 m wide at y = 10, room for one agent.
    fn wall() -> Vec<Disk> {
        (0..40)
            .map(|i| 0.25 + 0.5 * i as f64)
            .filter(|y| (y - 10.0).abs() > 0.9)
            .map(|y| Disk {
                centre: Point::new(11.0, y),
                radius_m: 0.5,
            })
            .collect()
    }

    /// The controllers of agents 0 (its slot at the centre) and 1 (its slot 2 m ahead),
    /// radius 0.25 m, top speed 0.5 m, looking 10 steps ahead, before [`wall`].
    fn setup() -> (Vec<TurnController>, Field, Vec<Disk>) {
        let spec = |slot| AgentSpec {
            max_step_m: Some(0.5),
            horizon_steps: 10,
            ..AgentSpec::new(slot, 0.25)
        };
        let specs = [spec(Slot::new(0.0, 0.0)), spec(Slot::new(2.0, 0.0))];
        let field = Field::new(20.0, 20.0);
        let obstacles = wall();
        let controllers = specs
            .iter()
            .map(|s| {
                TurnController::new(&ControllerSpec::default(), field, &obstacles, s)
                    .expect("a controller")
                    .with_formation(&specs)
            })
            .collect();
        (controllers, field, obstacles)
    }

    /// Agent 0's slot is in the gap, where it stands; agent 1 stands 2 m behind it and
    /// its slot is 2 m beyond the wall. The centre stands still; the agents take turns,
    /// agent 0 first, each with the other as `mates` says (true: both see the other as a
    /// mate; false: neither does). Every move is checked against the wall and the other
    /// agent and the top speed. Returns where they stand after `steps` steps.
    fn run(steps: usize, mates: bool) -> [Point; 2] {
        let (controllers, field, obstacles) = setup();
        let grid = DiskGrid::new(obstacles);
        let centre = Pose::new(11.0, 10.0, 0.0);
        let ahead = [centre; 10];
        let mut at = [Point::new(11.0, 10.0), Point::new(9.0, 10.0)];
        for step in 1..=steps {
            for me in 0..2 {
                let other = Body {
                    position: at[1 - me],
                    radius_m: 0.25,
                };
                let view = MateView {
                    agent: 1 - me,
                    position: other.position,
                    alive: true,
                };
                let views: &[MateView] = if mates { &[view] } else { &[] };
                let mv = controllers[me].plan(&TurnRequest {
                    step,
                    centre,
                    ahead: &ahead,
                    me: at[me],
                    heading_rad: None,
                    others: &[other],
                    mates: views,
                    velocities: None,
                });
                let checked = check_move(&field, &grid, &[other], 0.25, &at[me], &mv.waypoints, 8);
                assert!(checked.is_ok(), "agent {me} step {step}: {checked:?}");
                let end = *mv.waypoints.last().expect("a move");
                assert!(
                    (end - at[me]).norm() <= 0.5 + 1e-9,
                    "agent {me} step {step}"
                );
                at[me] = end;
            }
        }
        at
    }

    /// Without giving way the agent in the gap keeps its slot and its mate never gets
    /// through; giving way, it steps out of the gap, the mate passes and reaches its slot,
    /// and the agent is back on its own.
    #[test]
    fn an_agent_in_a_gap_gives_way_to_a_mate_far_behind() {
        let [_, stuck] = run(20, false);
        assert!(
            stuck.x < 11.0,
            "without giving way the mate stays behind: {stuck}"
        );
        let [agent, mate] = run(20, true);
        assert!(
            (mate - Point::new(13.0, 10.0)).norm() < 0.05,
            "the mate passed: {mate}"
        );
        assert!(
            (agent - Point::new(11.0, 10.0)).norm() < 0.05,
            "back on its slot: {agent}"
        );
    }

    /// A frozen mate changes nothing: where the agent first steps aside for its mate
    /// alive, it makes the move it makes without mates when the mate is frozen.
    #[test]
    fn a_frozen_mate_changes_nothing() {
        let (controllers, _, _) = setup();
        let centre = Pose::new(11.0, 10.0, 0.0);
        let mut at = [Point::new(11.0, 10.0), Point::new(9.0, 10.0)];
        let plan = |at: &[Point; 2], me: usize, mates: &[MateView]| {
            let other = Body {
                position: at[1 - me],
                radius_m: 0.25,
            };
            controllers[me].plan(&TurnRequest {
                step: 1,
                centre,
                ahead: &[centre; 10],
                me: at[me],
                heading_rad: None,
                others: &[other],
                mates,
                velocities: None,
            })
        };
        let view = |at: &[Point; 2], alive| MateView {
            agent: 1,
            position: at[1],
            alive,
        };
        for step in 1..=20 {
            let giving_way = plan(&at, 0, &[view(&at, true)]);
            let alone = plan(&at, 0, &[]);
            if giving_way != alone {
                assert_eq!(plan(&at, 0, &[view(&at, false)]), alone);
                return;
            }
            // The agent stands; its mate comes closer.
            let mate = plan(&at, 1, &[]);
            at[1] = *mate.waypoints.last().expect("a move");
            assert!(step < 20, "the agent never gave way");
        }
    }
}
