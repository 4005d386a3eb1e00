//! One agent's turn (the inner loop of the paper's Fig. 5): ideal slot, reachable best
//! point, shortest collision-free path to it, as a polyline the agent then follows.
//!
//! This is the one place the decision is made: the reference simulation and the agent
//! process both call [`TurnPlanner::plan_move`] (the paper's [`BestPointPlanner`] or a
//! barrier planner), so their trajectories agree to the bit.

use std::borrow::Cow;

use crate::best_point::{self, BestPointError};
use crate::cbf::{CbfPlanner, ZcbfLogSumExpPlanner};
use crate::disk_path::{self, DiskPath};
use crate::formation::Slot;
use crate::geometry::{
    Disk, DiskGrid, Field, FreeSpace, Point, Pose, Vector, distance_point_segment,
    polyline_length_m, polyline_prefix,
};
use crate::moving_obstacle::MovingObstacle;
use crate::orca::OrcaPlanner;
use crate::survival_grid::SurvivalGrid;
use crate::vocabulary::{
    AgentSpec, Body, CbfSettingsError, MAX_WAYPOINTS, Move, MoveStatus, PlannerKind, PlannerSpec,
};

/// Extra inflation of every disk when choosing the best point and planning the path, in
/// metres. It absorbs rounding and the chords of arcs: the followed polyline stays at
/// least half of it away from every true body.
pub const PLANNING_MARGIN_M: f64 = 1e-3;

/// How many steps ahead along the moving obstacles' routes an agent looks when it weighs
/// moves ([`TurnPlanner::plan_turn`]).
pub const LOOKAHEAD_STEPS: usize = 20;

/// An agent replaces its planned move by one that stays clear longer only when an
/// obstacle could reach the planned end within this many of its turns. Measured with
/// `shared/examples/strike_survey.rs` and `scenarios/moving-field.toml`: replacing every
/// move not clear for all [`LOOKAHEAD_STEPS`] made agents needlessly wary (the mean
/// deviation in `moving-field` rose from 0.34 m to 2.2 m); with the lattice sweep
/// ([`SURVIVAL_TURNS`]), 4 turns left fewer fields struck than 3 (300 random fields a
/// speed band) or 5 (1 000).
pub const LOOKAHEAD_TRIGGER_STEPS: usize = 4;

/// How many turns ahead an agent that looks ahead sweeps the lattice of points it could
/// move through ([`SurvivalGrid`]): can it keep out of every obstacle's reach that long,
/// moving as it likes?
pub const SURVIVAL_TURNS: usize = 10;

/// Lattice points per top-speed move along a side of the sweep's lattice
/// ([`SURVIVAL_TURNS`]): 3 weighed as well as 4 in the strike survey, at about half the
/// cost.
pub const SURVIVAL_CELLS_PER_MOVE: usize = 3;

// The sweep looks no farther than the turns the look-ahead lays out.
const _: () = assert!(SURVIVAL_TURNS <= LOOKAHEAD_STEPS + LOOKAHEAD_RUN_STEPS);

/// How many directions, evenly spread, an agent weighs a straight move in when looking
/// ahead (every 10 degrees).
pub const LOOKAHEAD_DIRECTIONS: usize = 36;

/// How many turns on along a straight move an agent weighs when looking ahead: a way out
/// of a gap that is closing may take several turns at the top speed.
pub const LOOKAHEAD_RUN_STEPS: usize = 8;

/// The paper's planner for one agent (exact best point, then the shortest path to it):
/// everything the agent needs to take its turns; built once, reused every step.
///
/// The agent is planned as a point: every other body is inflated by the agent's radius
/// plus [`PLANNING_MARGIN_M`], and the field is shrunk by the same amount on every side.
/// The planners take a field anchored at the origin, so planning happens in a frame
/// shifted by that inset; results are mapped back (exactly for the slot and the agent's
/// own position).
#[derive(Clone, Debug)]
pub struct BestPointPlanner {
    /// The field the agent's centre may use, in the planning frame.
    field: Field,
    /// Planning frame origin in world coordinates (the inset on both axes).
    offset: Vector,
    slot: Slot,
    radius_m: f64,
    /// Static obstacles inflated by this agent's radius and the planning margin, in the
    /// planning frame.
    obstacles: DiskGrid,
    /// With limited sensing: the obstacles with their true radii in world coordinates
    /// (same order as `obstacles`), to pick the ones the agent senses each turn.
    sensed_from: Option<DiskGrid>,
    spec: AgentSpec,
}

impl BestPointPlanner {
    /// The planner of agent `spec` in `field` among `obstacles` (true radii).
    pub fn new(field: Field, obstacles: &[Disk], spec: &AgentSpec) -> Self {
        let grow_m = spec.radius_m + PLANNING_MARGIN_M;
        let offset = Vector::new(grow_m, grow_m);
        Self {
            field: Field::new(
                (field.width_m - 2.0 * grow_m).max(0.0),
                (field.height_m - 2.0 * grow_m).max(0.0),
            ),
            offset,
            slot: spec.slot,
            radius_m: spec.radius_m,
            obstacles: DiskGrid::new(
                obstacles
                    .iter()
                    .map(|o| Disk {
                        centre: o.centre - offset,
                        radius_m: o.radius_m + grow_m,
                    })
                    .collect(),
            ),
            sensed_from: spec
                .sensing_radius_m
                .map(|_| DiskGrid::new(obstacles.to_vec())),
            spec: *spec,
        }
    }

    /// The inflated obstacles (planning frame) the agent senses from `me`, in obstacle
    /// order; `None` when it senses everything.
    fn sensed_obstacles(&self, me: &Point) -> Option<DiskGrid> {
        let (grid, sensing_m) = (self.sensed_from.as_ref()?, self.spec.sensing_radius_m?);
        let mut seen = Vec::new();
        let _ = grid.visit_near(me, sensing_m + grid.max_radius_m(), |i, d| {
            if self.spec.senses(me, &d.centre, d.radius_m) {
                seen.push(i);
            }
            std::ops::ControlFlow::<()>::Continue(())
        });
        seen.sort_unstable();
        let inflated = self.obstacles.disks();
        Some(DiskGrid::new(seen.iter().map(|&i| inflated[i]).collect()))
    }

    /// This agent's radius, in metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The ideal slot when the centre is at `centre`.
    pub fn slot_position(&self, centre: &Pose) -> Point {
        self.slot.ideal_position(centre)
    }

    /// Plan this agent's move while every `other` body stands still: the reachable free
    /// point nearest to the slot and the shortest path there. With limited sensing, only
    /// the obstacles it senses are planned around (`others` are taken as given: see
    /// [`TurnPlanner::plan_move`], which picks the sensed ones); the top speed is
    /// [`TurnPlanner`]'s business too.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        self.plan_move_within(centre, me, others, self.spec.max_step_m)
    }

    /// [`Self::plan_move`] with the path cut at `max_step_m` (absent: not cut) instead of
    /// the agent's top speed: what is left of a turn that began with another motion.
    pub fn plan_move_within(
        &self,
        centre: &Pose,
        me: &Point,
        others: &[Body],
        max_step_m: Option<f64>,
    ) -> Move {
        let slot = self.slot_position(centre);
        let grow_m = self.radius_m + PLANNING_MARGIN_M;
        let agents = DiskGrid::new(
            others
                .iter()
                .map(|b| Disk {
                    centre: b.position - self.offset,
                    radius_m: b.radius_m + grow_m,
                })
                .collect(),
        );
        let sensed = self.sensed_obstacles(me);
        let layers = [sensed.as_ref().unwrap_or(&self.obstacles), &agents];
        let space = FreeSpace::new(self.field, &layers);
        let (slot_p, me_p) = (slot - self.offset, me - self.offset);
        // Back to world coordinates, keeping the slot and the start bit-exact.
        let to_world = |p: &Point| -> Point {
            if *p == slot_p {
                slot
            } else if *p == me_p {
                *me
            } else {
                p + self.offset
            }
        };
        let stay = |status| Move {
            slot,
            best: *me,
            status,
            waypoints: vec![*me],
        };

        let mut found: Option<(Point, DiskPath)> = None;
        let best = best_point::nearest_reachable_free_point(&space, &slot_p, &me_p, {
            // One context for every candidate of the turn (same space, same start): it
            // answers as `disk_path::shortest_path` does, but proves most candidates in
            // another free component unreachable without a search.
            let mut paths = disk_path::PathsFrom::new(&space, &me_p);
            let found = &mut found;
            move |p| match paths.shortest_path(p) {
                Ok(path) => {
                    *found = Some((*p, path));
                    true
                }
                Err(_) => false,
            }
        });
        let best_p = match best {
            Ok(p) => p,
            Err(BestPointError::NoFreePoint) => return stay(MoveStatus::NoFreePoint),
        };
        let best = to_world(&best_p);
        if best_p == me_p {
            let status = if (slot - best).norm() <= 1e-9 {
                MoveStatus::AtSlot
            } else {
                MoveStatus::Stayed
            };
            return stay(status);
        }
        // The closure accepted `best` last, so `found` holds its path.
        let path = match found {
            Some((p, path)) if p == best_p => path,
            _ => return stay(MoveStatus::Stayed),
        };
        // With a top speed the agent follows the path that far: cut on the path itself
        // (on an arc's circle, not on a chord), so it stops at a free point.
        let under_way = max_step_m.and_then(|s| path.prefix(s));
        let followed = under_way.as_ref().unwrap_or(&path);
        let mut waypoints: Vec<Point> = followed
            .polyline(0.5 * PLANNING_MARGIN_M)
            .iter()
            .map(to_world)
            .collect();
        if waypoints.len() > MAX_WAYPOINTS {
            return stay(MoveStatus::PathTooLong);
        }
        // The polyline starts at the agent and ends at the best point (or the cut),
        // exactly.
        if let Some(first) = waypoints.first_mut() {
            *first = *me;
        }
        if under_way.is_none()
            && let Some(last) = waypoints.last_mut()
        {
            *last = best;
        }
        let status = if under_way.is_some() {
            MoveStatus::UnderWay
        } else if (slot - best).norm() <= 1e-9 {
            MoveStatus::AtSlot
        } else {
            MoveStatus::Deviated
        };
        Move {
            slot,
            best,
            status,
            waypoints,
        }
    }
}

/// Any of the controllers, behind one `plan_move`, with the agent's sensing radius and
/// top speed applied: what the reference simulation and the agent processes call.
#[derive(Clone, Debug)]
pub struct TurnPlanner {
    controller: Controller,
    spec: AgentSpec,
    /// The moving obstacles of the scenario ([`Self::with_moving`]).
    moving: Vec<MovingObstacle>,
    /// With moving obstacles: the static ones (true radii), to check an escape against.
    statics: DiskGrid,
    field: Field,
}

/// The controllers.
#[derive(Clone, Debug)]
enum Controller {
    /// The paper's method, exact ([`BestPointPlanner`]).
    BestPoint(BestPointPlanner),
    /// The control-barrier-function QP.
    Cbf(CbfPlanner),
    /// The paper's failed LogSumExp barrier, for comparison.
    ZcbfLogSumExp(ZcbfLogSumExpPlanner),
    /// ORCA, the reactive baseline.
    Orca(OrcaPlanner),
}

impl TurnPlanner {
    /// The planner `planner.kind` for agent `spec` in `field` among `obstacles` (true
    /// radii). A barrier planner senses no farther than the agent does.
    pub fn new(
        planner: &PlannerSpec,
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
    ) -> Result<Self, CbfSettingsError> {
        let mut cbf = planner.cbf;
        if let Some(sensing_m) = spec.sensing_radius_m {
            cbf.sensing_radius_m = cbf.sensing_radius_m.min(sensing_m);
        }
        let controller = match planner.kind {
            PlannerKind::BestPoint => {
                Controller::BestPoint(BestPointPlanner::new(field, obstacles, spec))
            }
            PlannerKind::Cbf => Controller::Cbf(CbfPlanner::new(field, obstacles, spec, cbf)?),
            PlannerKind::ZcbfLogsumexp => Controller::ZcbfLogSumExp(ZcbfLogSumExpPlanner::new(
                field,
                obstacles,
                spec,
                cbf,
                planner.lse_sharpness_per_m,
            )?),
            // Its maximum speed is the top speed; without one, the barrier planners' step.
            PlannerKind::Orca => Controller::Orca(OrcaPlanner::new(
                field,
                obstacles,
                spec,
                spec.max_step_m.unwrap_or(cbf.max_speed_m_per_s * cbf.dt_s),
                spec.sensing_radius_m,
            )),
        };
        Ok(Self {
            controller,
            spec: *spec,
            moving: Vec::new(),
            statics: DiskGrid::new(Vec::new()),
            field,
        })
    }

    /// This planner in a world with `moving` obstacles: [`Self::plan_turn`] plans around
    /// them. `obstacles` are the static ones given to [`Self::new`] (true radii).
    pub fn with_moving(mut self, moving: &[MovingObstacle], obstacles: &[Disk]) -> Self {
        if !moving.is_empty() {
            self.moving = moving.to_vec();
            self.statics = DiskGrid::new(obstacles.to_vec());
        }
        self
    }

    /// The agent this planner moves.
    pub fn spec(&self) -> &AgentSpec {
        &self.spec
    }

    /// Plan this agent's move while every `other` body stands still.
    ///
    /// With a sensing radius the controller sees only the bodies of `others` (and the
    /// obstacles) whose disks come within it, so bodies beyond it change nothing; `others`
    /// may be all bodies or any superset of the sensed ones. With a top speed the move is
    /// the first `max_step_m` of the controller's path, with status
    /// [`MoveStatus::UnderWay`] when it stops short of the best point.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        self.plan_move_within(centre, me, others, self.spec.max_step_m)
    }

    /// Plan this agent's turn at `step` while every `other` body stands still and every
    /// moving obstacle stands where it is at `step` ([`crate::moving_obstacle`]).
    ///
    /// The agent plans around each moving obstacle it senses as around a disk grown by
    /// twice the obstacle's speed, or as much of that as leaves it outside: at least the
    /// obstacle's reach ([`MovingObstacle::reach_disk_at`], where it can be until the
    /// agent's next turn), so a move that ends outside it is still clear after the
    /// obstacle's next motion, and a step to spare where there is room. An agent that starts its turn inside such a disk (the
    /// obstacle came closer since its last turn) first escapes: a straight motion out of
    /// the disk, radially or up to 150 degrees off, that is clear of every body and
    /// within its top speed, or else the shortest path out round the bodies in its way
    /// ([`Self::escape_path`]); the rest of the turn is planned from there with what is left
    /// of the top speed. Without an escape, the disk is shrunk to leave the agent outside.
    /// Without moving obstacles this is [`Self::plan_move`].
    ///
    /// Then it looks ahead ([`Self::look_ahead`]): when the move would end where a sensed
    /// obstacle's reach will be within [`LOOKAHEAD_TRIGGER_STEPS`] steps along its route,
    /// the straight move from whose end the agent can keep clear longest (up to
    /// [`SURVIVAL_TURNS`], moving on as it likes) is taken instead.
    pub fn plan_turn(&self, step: usize, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        if self.moving.is_empty() {
            return self.plan_move(centre, me, others);
        }
        // What the agent senses from where it stands, once: the coordinator sends an
        // agent process only that, and an escape must not see more.
        let others = &*self.sensed_bodies(me, others);
        let sensed: Vec<&MovingObstacle> = self
            .moving
            .iter()
            .filter(|m| {
                let c = m.position_at(step);
                self.spec.senses(me, &c, m.radius_m)
            })
            .collect();
        // Where each can be until this agent's next turn.
        let reach: Vec<Disk> = sensed.iter().map(|m| m.reach_disk_at(step)).collect();
        let mv = self.plan_turn_around(step, centre, me, others, &sensed, &reach);
        self.look_ahead(step, me, others, &sensed, &reach, mv)
    }

    /// [`Self::plan_turn`] before looking ahead: the escape, if any, and the plan round
    /// the reach disks `reach` (with a step to spare) of the `sensed` moving obstacles;
    /// `others` are the sensed bodies.
    fn plan_turn_around(
        &self,
        step: usize,
        centre: &Pose,
        me: &Point,
        others: &[Body],
        sensed: &[&MovingObstacle],
        reach: &[Disk],
    ) -> Move {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let spares_m: Vec<f64> = sensed.iter().map(|m| m.speed_m_per_step).collect();
        let inside = reach
            .iter()
            .any(|d| (me - d.centre).norm() < d.radius_m + keep_m);
        let escape: Option<Vec<Point>> = if inside {
            // Every moving obstacle where it stands, sensed or not (an escape is checked
            // against the true bodies).
            let now: Vec<Disk> = self.moving.iter().map(|m| m.disk_at(step)).collect();
            self.escape_point(me, others, &now, reach, &spares_m)
                .map(|q| vec![*me, q])
                .or_else(|| self.escape_path(me, others, &now, reach, &spares_m))
                .or_else(|| {
                    self.flee_point(me, others, &now, reach)
                        .map(|q| vec![*me, q])
                })
        } else {
            None
        };
        let start = escape
            .as_ref()
            .and_then(|e| e.last().copied())
            .unwrap_or(*me);
        // Planned around with a second step to spare where there is room, so that an
        // obstacle coming closer seldom catches the agent inside its reach.
        let mut bodies = others.to_vec();
        for (m, d) in sensed.iter().zip(reach) {
            let d = d.inflated(m.speed_m_per_step);
            let room_m = (start - d.centre).norm() - keep_m;
            let radius_m = d.radius_m.min(room_m);
            if radius_m > 0.0 {
                bodies.push(Body {
                    position: d.centre,
                    radius_m,
                });
            }
        }
        let Some(escape) = escape else {
            return self.plan_move_within(centre, me, &bodies, self.spec.max_step_m);
        };
        let used_m = polyline_length_m(&escape);
        let left_m = self.spec.max_step_m.map(|s| (s - used_m).max(0.0));
        let mut mv = self.plan_move_within(centre, &start, &bodies, left_m);
        // The escape, then the rest (which begins where the escape ends).
        let mut waypoints = escape;
        waypoints.extend(mv.waypoints.iter().skip(1));
        mv.waypoints = waypoints;
        if mv.waypoints.len() > MAX_WAYPOINTS {
            mv.waypoints.truncate(MAX_WAYPOINTS);
            mv.best = mv.end();
            mv.status = MoveStatus::UnderWay;
        }
        mv
    }

    /// The move `planned`, or one that keeps the agent clear of the `sensed` moving
    /// obstacles longer.
    ///
    /// An agent knows each obstacle's route, so it can tell for how many of its next
    /// [`LOOKAHEAD_STEPS`] turns a point would stay outside every obstacle's reach disk
    /// there (each grown by the agent's radius): for so many turns the agent could stand
    /// there and still begin every turn where the obstacles' next motion cannot reach it.
    /// When the planned move ends where that holds for fewer than
    /// [`LOOKAHEAD_TRIGGER_STEPS`] turns, the agent weighs straight moves in
    /// [`LOOKAHEAD_DIRECTIONS`] directions, at its top speed and at half of it, each clear
    /// of every body, the field's edges and the obstacles where they stand and ending
    /// outside every reach disk (as an escape must). The best one is the one from whose
    /// end the agent can keep out of every reach disk for the most turns (up to
    /// [`SURVIVAL_TURNS`]) moving as it likes, its mates standing where they are
    /// ([`SurvivalGrid`]: a gap the obstacles are closing may take several moves to
    /// leave); then the one whose end stays clear for the most turns standing there (up
    /// to the trigger); then the one with the longest horizon when the agent goes on the
    /// same way at its top speed for up to [`LOOKAHEAD_RUN_STEPS`] turns before it stands;
    /// then the smallest overlap where that horizon ends; then the one ending nearest the
    /// slot. It replaces the planned move when it is better by the same order. So an
    /// agent leaves an obstacle's path, or a gap obstacles are closing, while there is
    /// still room, rather than when the obstacle's reach is upon it and its mates are in
    /// the way. Without a top speed the planned move is kept.
    fn look_ahead(
        &self,
        step: usize,
        me: &Point,
        others: &[Body],
        sensed: &[&MovingObstacle],
        reach: &[Disk],
        planned: Move,
    ) -> Move {
        let Some(budget_m) = self.spec.max_step_m else {
            return planned;
        };
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let clear_m = self.spec.radius_m + PLANNING_MARGIN_M;
        let slot = planned.slot;
        // Nothing to weigh when the planned end stays outside every reach disk for the
        // next LOOKAHEAD_TRIGGER_STEPS turns.
        let end = planned.end();
        let safe_for_now = (1..=LOOKAHEAD_TRIGGER_STEPS).all(|j| {
            sensed.iter().all(|m| {
                let reach = m.reach_disk_at(step + j);
                (end - reach.centre).norm() - reach.radius_m - keep_m >= 0.0
            })
        });
        if safe_for_now {
            return planned;
        }
        // The reach disk at each turn looked at, grown by the agent's radius (centres by
        // turn, 0 this one; radius), of every sensed obstacle that can come near enough
        // to matter: within the agent's top speed for every turn looked at.
        let turns = LOOKAHEAD_STEPS + LOOKAHEAD_RUN_STEPS;
        let far_m = (turns + 1) as f64 * budget_m;
        let ahead: Vec<(Vec<Point>, f64)> = sensed
            .iter()
            .filter(|m| {
                let reach_m = m.radius_m + (turns + 1) as f64 * m.speed_m_per_step + keep_m;
                (me - m.position_at(step)).norm() < reach_m + far_m
            })
            .map(|m| {
                let centres = (0..=turns).map(|j| m.position_at(step + j)).collect();
                (centres, m.radius_m + m.speed_m_per_step + keep_m)
            })
            .collect();
        // Standing at `p` from the end of turn `from` (counted from this one) on: for how
        // many turns (up to LOOKAHEAD_STEPS) it stays outside every reach disk, and the
        // gap at the first turn it does not (infinite when it always does).
        let clear_from = |p: &Point, from: usize| -> (usize, f64) {
            for j in 1..=LOOKAHEAD_STEPS {
                let gap_m = ahead
                    .iter()
                    .map(|(centres, big_r)| (p - centres[from + j]).norm() - big_r)
                    .fold(f64::INFINITY, f64::min);
                if gap_m < 0.0 {
                    return (j - 1, gap_m);
                }
            }
            (LOOKAHEAD_STEPS, f64::INFINITY)
        };
        // Where the agent could end each of its next SURVIVAL_TURNS turns: in the field,
        // clear of the static obstacles and of its mates where they stand (they move
        // too, but may not make room), and outside that turn's reach disks.
        let stays_free = |p: &Point| {
            self.field.signed_inset_m(p) >= clear_m
                && others
                    .iter()
                    .all(|b| (p - b.position).norm() >= b.radius_m + clear_m)
                && self
                    .statics
                    .all_near(p, clear_m + self.statics.max_radius_m(), |d| {
                        d.signed_distance_m(p) >= clear_m
                    })
        };
        let reach_at = |n: usize| -> Vec<Disk> {
            ahead
                .iter()
                .map(|(centres, big_r)| Disk {
                    centre: centres[n],
                    radius_m: *big_r,
                })
                .collect()
        };
        let cell_m = budget_m / SURVIVAL_CELLS_PER_MOVE as f64;
        let sweep = SurvivalGrid::new(me, budget_m, cell_m, SURVIVAL_TURNS, stays_free, reach_at);
        // A point `q` reached by a straight move along `v`: for how many turns the agent
        // can keep out of every reach disk from there, moving as it likes (up to
        // SURVIVAL_TURNS; at least as long as standing there); for how many standing
        // there does (up to LOOKAHEAD_TRIGGER_STEPS, the least an agent wants); the
        // longest clear horizon of standing there or going on along `v` at the top speed
        // for up to LOOKAHEAD_RUN_STEPS turns (each ending outside that turn's reach
        // disks and in the field) and then standing; the gap where that horizon ends; and
        // the distance from `q` to the slot.
        type Score = (usize, usize, usize, f64, f64);
        let score = |q: &Point, v: Option<Vector>| -> Score {
            let (standing, mut gap_m) = clear_from(q, 0);
            let mut horizon = standing;
            // Going on along `v`, as long as each turn ends outside its reach disks and
            // in the field, and the horizon can still grow.
            for (n, v) in (1..=LOOKAHEAD_RUN_STEPS).flat_map(|n| v.map(|v| (n, v))) {
                let p = q + (n as f64 * budget_m) * v;
                let inside_reach = ahead
                    .iter()
                    .any(|(centres, big_r)| (p - centres[n]).norm() < *big_r);
                if horizon == LOOKAHEAD_STEPS
                    || inside_reach
                    || self.field.signed_inset_m(&p) < clear_m
                {
                    break;
                }
                let (c, g) = clear_from(&p, n);
                if (n + c).min(LOOKAHEAD_STEPS) > horizon {
                    (horizon, gap_m) = ((n + c).min(LOOKAHEAD_STEPS), g);
                }
            }
            (
                sweep.turns_clear(q).max(standing.min(SURVIVAL_TURNS)),
                standing.min(LOOKAHEAD_TRIGGER_STEPS),
                horizon,
                gap_m,
                (q - slot).norm(),
            )
        };
        let better = |a: Score, b: Score| {
            if (a.0, a.1, a.2) != (b.0, b.1, b.2) {
                (a.0, a.1, a.2) > (b.0, b.1, b.2)
            } else if a.2 < LOOKAHEAD_STEPS && a.3 != b.3 {
                a.3 > b.3
            } else {
                a.4 < b.4
            }
        };
        let kept = score(&end, None);
        let now: Vec<Disk> = self.moving.iter().map(|m| m.disk_at(step)).collect();
        let mut best: Option<(Score, Point)> = None;
        for k in 0..LOOKAHEAD_DIRECTIONS {
            let rad = std::f64::consts::TAU * k as f64 / LOOKAHEAD_DIRECTIONS as f64;
            let v = Vector::new(rad.cos(), rad.sin());
            for t in [budget_m, 0.5 * budget_m] {
                if let Some(q) = self.escape_to(me, v, t, others, reach, &now, true) {
                    let s = score(&q, Some(v));
                    if best.is_none_or(|(b, _)| better(s, b)) {
                        best = Some((s, q));
                    }
                }
            }
        }
        match best {
            Some((s, q)) if better(s, kept) => Move {
                slot,
                best: q,
                status: if (q - slot).norm() <= 1e-9 {
                    MoveStatus::AtSlot
                } else {
                    MoveStatus::Deviated
                },
                waypoints: vec![*me, q],
            },
            _ => planned,
        }
    }

    /// When no straight motion gets out ([`Self::escape_point`]): the shortest path among
    /// every body, the static obstacles and the moving ones where they stand, within the
    /// top speed, to a point just outside every disk of `reach` (grown by the agent's
    /// radius), tried every 10 degrees round the disk it is deepest in, nearest the
    /// straight way out first, a step to spare beyond it before just outside it. A
    /// polyline from `me` to that point.
    fn escape_path(
        &self,
        me: &Point,
        others: &[Body],
        now: &[Disk],
        reach: &[Disk],
        spares_m: &[f64],
    ) -> Option<Vec<Point>> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let budget_m = self.spec.max_step_m.unwrap_or(f64::INFINITY);
        let (i, away_rad) = deepest_of(me, reach, keep_m)?;
        let (deepest, spare_m) = (reach[i], spares_m.get(i).copied().unwrap_or(0.0));
        let big_r = deepest.radius_m + keep_m + PLANNING_MARGIN_M;
        // Planning frame as in BestPointPlanner: the agent a point, every body grown by
        // its radius and the margin, the field inset by as much.
        let grow_m = self.spec.radius_m + PLANNING_MARGIN_M;
        let offset = Vector::new(grow_m, grow_m);
        let field = Field::new(
            (self.field.width_m - 2.0 * grow_m).max(0.0),
            (self.field.height_m - 2.0 * grow_m).max(0.0),
        );
        let near_m = budget_m.min(2.0 * big_r) + grow_m;
        let mut statics = Vec::new();
        let _ = self
            .statics
            .visit_near(me, near_m + self.statics.max_radius_m(), |_, d| {
                statics.push(Disk {
                    centre: d.centre - offset,
                    radius_m: d.radius_m + grow_m,
                });
                std::ops::ControlFlow::<()>::Continue(())
            });
        let bodies: Vec<Disk> = others
            .iter()
            .map(|b| Disk {
                centre: b.position - offset,
                radius_m: b.radius_m + grow_m,
            })
            .chain(now.iter().map(|d| Disk {
                centre: d.centre - offset,
                radius_m: d.radius_m + grow_m,
            }))
            .collect();
        let (statics, bodies) = (DiskGrid::new(statics), DiskGrid::new(bodies));
        let layers = [&statics, &bodies];
        let space = FreeSpace::new(field, &layers);
        let me_p = me - offset;
        // A step to spare beyond the disk first, then just outside it.
        for (off_deg, out_r) in offsets_deg(180)
            .map(|off| (off, big_r + spare_m))
            .chain(offsets_deg(180).map(|off| (off, big_r)))
        {
            let rad = away_rad + off_deg.to_radians();
            let q = deepest.centre + out_r * Vector::new(rad.cos(), rad.sin());
            if (q - me).norm() > budget_m
                || reach
                    .iter()
                    .any(|d| (q - d.centre).norm() < d.radius_m + keep_m)
            {
                continue;
            }
            let q_p = q - offset;
            if !space.is_free(&q_p, 0.0) {
                continue;
            }
            let Ok(path) = disk_path::shortest_path(&space, &me_p, &q_p) else {
                continue;
            };
            if path.length_m() > budget_m {
                continue;
            }
            let mut points: Vec<Point> = path
                .polyline(0.5 * PLANNING_MARGIN_M)
                .iter()
                .map(|p| p + offset)
                .collect();
            if points.len() < 2 || points.len() > MAX_WAYPOINTS / 2 {
                continue;
            }
            // Exactly from the agent to the escape point.
            points[0] = *me;
            if let Some(last) = points.last_mut() {
                *last = q;
            }
            return Some(points);
        }
        None
    }

    /// A point just outside every disk of `reach` (grown by the agent's radius), reached
    /// from `me` by a straight motion clear of every body, the static obstacles, the
    /// moving ones where they stand and the field's edges, within the top speed.
    fn escape_point(
        &self,
        me: &Point,
        others: &[Body],
        now: &[Disk],
        reach: &[Disk],
        spares_m: &[f64],
    ) -> Option<Point> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        // The disk it is deepest in, and that obstacle's speed: how far beyond the disk
        // the agent goes if it can, to keep a step to spare.
        let (i, away_rad) = deepest_of(me, reach, keep_m)?;
        let (deepest, spare_m) = (reach[i], spares_m.get(i).copied().unwrap_or(0.0));
        let away = me - deepest.centre;
        let budget_m = self.spec.max_step_m.unwrap_or(f64::INFINITY);
        for off_deg in offsets_deg(150) {
            let rad = away_rad + off_deg.to_radians();
            let v = Vector::new(rad.cos(), rad.sin());
            // |me + t v - c| = R, the larger root (leaving the disk).
            let leave = |big_r: f64| {
                let b = v.dot(&away);
                let disc = b * b - (away.norm_squared() - big_r * big_r);
                (disc >= 0.0).then(|| -b + disc.sqrt())
            };
            let Some(t_out) = leave(deepest.radius_m + keep_m + PLANNING_MARGIN_M) else {
                continue;
            };
            if !(t_out > 0.0 && t_out <= budget_m) {
                continue;
            }
            // As far as a step to spare, or the top speed, allows; else just out.
            let t_far = leave(deepest.radius_m + spare_m + keep_m + PLANNING_MARGIN_M)
                .map_or(t_out, |t| t.min(budget_m));
            for t in [t_far, t_out] {
                if let Some(q) = self.escape_to(me, v, t, others, reach, now, true) {
                    return Some(q);
                }
            }
        }
        None
    }

    /// When there is no way out of the obstacle's reach within the top speed (it came
    /// too close, or struck the agent): a straight motion as far from it as the top speed
    /// allows, radially or up to 90 degrees off, clear of everything.
    fn flee_point(
        &self,
        me: &Point,
        others: &[Body],
        now: &[Disk],
        reach: &[Disk],
    ) -> Option<Point> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let budget_m = self.spec.max_step_m?;
        let (i, away_rad) = deepest_of(me, reach, keep_m)?;
        let deepest = reach[i];
        for off_deg in offsets_deg(90) {
            let rad = away_rad + off_deg.to_radians();
            let v = Vector::new(rad.cos(), rad.sin());
            if let Some(q) = self.escape_to(me, v, budget_m, others, reach, now, false)
                && (q - deepest.centre).norm() > (me - deepest.centre).norm()
            {
                return Some(q);
            }
        }
        None
    }

    /// `me + t v` if the straight motion there is clear of every body, the static
    /// obstacles, the moving ones where they stand (`now`) and the field's edges, and,
    /// with `leave_reach`, it ends outside every disk of `reach` (grown by the agent's
    /// radius).
    #[allow(clippy::too_many_arguments)]
    fn escape_to(
        &self,
        me: &Point,
        v: Vector,
        t: f64,
        others: &[Body],
        reach: &[Disk],
        now: &[Disk],
        leave_reach: bool,
    ) -> Option<Point> {
        let keep_m = self.spec.radius_m + 2.0 * PLANNING_MARGIN_M;
        let clear_m = self.spec.radius_m + PLANNING_MARGIN_M;
        {
            let q = me + t * v;
            let outside_reach = !leave_reach
                || reach
                    .iter()
                    .all(|d| (q - d.centre).norm() >= d.radius_m + keep_m);
            let in_field = self.field.signed_inset_m(&q) >= clear_m;
            // The motion keeps half the planning margin from every body (the agent may
            // start its turn touching one, at the margin); its end the whole margin, so
            // the rest of the turn is planned from a free point.
            let segment_clear = |d: &Disk| {
                d.signed_distance_to_segment_m(me, &q)
                    >= self.spec.radius_m + 0.5 * PLANNING_MARGIN_M
                    && d.signed_distance_m(&q) >= clear_m
            };
            let clear_of_bodies = others.iter().all(|b| {
                segment_clear(&Disk {
                    centre: b.position,
                    radius_m: b.radius_m,
                })
            });
            // An agent a moving obstacle struck (it overlaps it) may leave it, never
            // coming closer to its centre.
            let clear_of_moving = now.iter().all(|d| {
                let start_m = (me - d.centre).norm();
                if start_m < d.radius_m + self.spec.radius_m {
                    distance_point_segment(&d.centre, me, &q) >= start_m
                        && d.signed_distance_m(&q) >= clear_m
                } else {
                    segment_clear(d)
                }
            });
            let clear_of_statics =
                self.statics
                    .all_near(me, t + clear_m + self.statics.max_radius_m(), segment_clear);
            (outside_reach && in_field && clear_of_bodies && clear_of_moving && clear_of_statics)
                .then_some(q)
        }
    }

    /// The bodies of `others` this agent senses from `me` (all of them without a sensing
    /// radius).
    fn sensed_bodies<'b>(&self, me: &Point, others: &'b [Body]) -> Cow<'b, [Body]> {
        if self.spec.sensing_radius_m.is_none() {
            return Cow::Borrowed(others);
        }
        Cow::Owned(
            others
                .iter()
                .filter(|b| self.spec.senses(me, &b.position, b.radius_m))
                .copied()
                .collect(),
        )
    }

    /// [`Self::plan_move`] with the move cut at `max_step_m` (absent: not cut).
    fn plan_move_within(
        &self,
        centre: &Pose,
        me: &Point,
        others: &[Body],
        max_step_m: Option<f64>,
    ) -> Move {
        let others = &*self.sensed_bodies(me, others);
        let mut mv = match &self.controller {
            Controller::BestPoint(p) => p.plan_move_within(centre, me, others, max_step_m),
            Controller::Cbf(p) => p.plan_move(centre, me, others),
            Controller::ZcbfLogSumExp(p) => p.plan_move(centre, me, others),
            Controller::Orca(p) => p.plan_move(centre, me, others),
        };
        if let Some(max_step_m) = max_step_m
            && let Some(prefix) = polyline_prefix(&mv.waypoints, max_step_m)
        {
            mv.waypoints = prefix;
            mv.status = MoveStatus::UnderWay;
        }
        mv
    }
}

/// The disk of `reach` that `me` is deepest in (each grown by `keep_m`), by index, and the
/// direction straight away from its centre, in radians.
fn deepest_of(me: &Point, reach: &[Disk], keep_m: f64) -> Option<(usize, f64)> {
    let depth = |d: &Disk| d.radius_m + keep_m - (me - d.centre).norm();
    let (i, d) = reach
        .iter()
        .enumerate()
        .max_by(|(_, a), (_, b)| depth(a).total_cmp(&depth(b)))?;
    let away = me - d.centre;
    let away_rad = if away.norm() > 0.0 {
        away.y.atan2(away.x)
    } else {
        0.0
    };
    Some((i, away_rad))
}

/// Turns off the straight way out, in degrees, nearest first: 0, 10, -10, 20, -20, ...,
/// `max_deg`, `-max_deg` (`max_deg` a multiple of 10).
fn offsets_deg(max_deg: i32) -> impl Iterator<Item = f64> {
    (0..=max_deg / 5).map(|k: i32| f64::from(10 * ((k + 1) / 2) * if k % 2 == 0 { 1 } else { -1 }))
}
