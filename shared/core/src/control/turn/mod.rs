//! One agent's turn (the inner loop of the paper's Fig. 5): ideal slot, reachable best
//! point, shortest collision-free path to it, as a polyline the agent then follows.
//!
//! This is the one place the decision is made: the reference simulation and the agent
//! process both hand a [`TurnRequest`] to [`TurnController::plan`] (the paper's
//! [`BestPointController`] or a barrier controller), so their trajectories agree to the bit.
//!
//! One concept a file: here the dispatch over the controllers ([`TurnController`]); in
//! `request.rs` what a turn is planned from; in `best_point_controller.rs` the paper's
//! controller; in `escape.rs` a turn among moving
//! obstacles (the escape from an obstacle's reach and the plan round the reach disks);
//! in `look_ahead.rs` the look-ahead along the moving obstacles' routes.

use std::borrow::Cow;

use crate::control::cbf::{CbfController, ZcbfLogSumExpController};
use crate::control::kinematics::{CarLimits, UnicycleLimits, drive_unicycle};
use crate::control::orca::OrcaController;
use crate::control::tracking;
use crate::control::vocabulary::{
    AgentSpec, Body, CbfSettingsError, ControllerKind, ControllerSpec, Kinematics, Move, MoveStatus,
};
use crate::geometry::{
    Disk, DiskGrid, Field, InflatedPolygon, Point, Polygon, PolygonLayer, Pose, Vector,
    polyline_prefix,
};
use crate::world::moving_obstacle::MovingObstacle;
use crate::world::scenario::ScenarioMap;

mod best_point_controller;
mod car;
mod escape;
mod give_way;
mod look_ahead;
mod request;

pub use best_point_controller::{Aim, BestPointController};
pub use car::{GOAL_HEADINGS, SEARCH_EXPANSIONS};
pub use give_way::{GIVE_WAY_MARGIN_M, LaggingMate, MateView};
pub use look_ahead::{
    LOOKAHEAD_DIRECTIONS, LOOKAHEAD_RUN_TURNS, LOOKAHEAD_TRIGGER_TURNS, LOOKAHEAD_TURNS,
    SURVIVAL_CELLS_PER_MOVE, SURVIVAL_TURNS,
};
pub use request::TurnRequest;

/// Extra inflation of every disk when choosing the best point and planning the path, in
/// metres. It absorbs rounding and the chords of arcs: the followed polyline stays at
/// least half of it away from every true body.
pub const PLANNING_MARGIN_M: f64 = 1e-3;

/// The longest chord of an arc in a unicycle's polyline, as a share of its top speed: a
/// step whose time runs out inside a chord that cuts into a disk's margin ends at the
/// chord's start, so short chords keep such a step from losing more than this share.
const UNICYCLE_CHORD_SHARE: f64 = 0.25;

/// How the bodies moved over the last step (metres per step), what an agent knows when
/// every agent moves at once ([`crate::control::vocabulary::TurnMode::Simultaneous`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Velocities {
    /// This agent's.
    pub me: Vector,
    /// Each other body's, in the order of the `others` they come with.
    pub others: Vec<Vector>,
}

impl Velocities {
    /// Agent `agent`'s view of `all` (every agent's, by index): its own, and the others'
    /// in index order, as [`crate::run::World::others`] lists their bodies.
    pub fn of_agent(all: &[Vector], agent: usize) -> Self {
        Self {
            me: all.get(agent).copied().unwrap_or_default(),
            others: all
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != agent)
                .map(|(_, v)| *v)
                .collect(),
        }
    }
}

/// Any of the controllers, behind one [`TurnController::plan`], with the agent's sensing
/// radius and top speed applied: what the reference simulation and the agent processes
/// call.
#[derive(Clone, Debug)]
pub struct TurnController {
    controller: Controller,
    spec: AgentSpec,
    /// The moving obstacles of the scenario ([`Self::with_moving`]).
    moving: Vec<MovingObstacle>,
    /// With moving obstacles: the static ones (true radii), to check an escape against.
    statics: DiskGrid,
    /// The static polygons (as given, indexed), to check an escape against.
    polygons: PolygonLayer,
    /// For an agent with a heading: the static obstacles (true radii), to check where a
    /// move cut inside a segment stops.
    obstacles: DiskGrid,
    field: Field,
    /// Every agent of the formation, by index ([`Self::with_formation`]): the mates'
    /// slots, to tell which lag far behind.
    formation: Vec<AgentSpec>,
}

/// The controllers.
#[derive(Clone, Debug)]
enum Controller {
    /// The paper's method, exact ([`BestPointController`]).
    BestPoint(BestPointController),
    /// The control-barrier-function QP.
    Cbf(CbfController),
    /// The paper's failed LogSumExp barrier, for comparison.
    ZcbfLogSumExp(ZcbfLogSumExpController),
    /// ORCA, the reactive baseline.
    Orca(OrcaController),
}

impl TurnController {
    /// The controller `controller.kind` for agent `spec` in `field` among `obstacles` (true
    /// radii). A barrier controller senses no farther than the agent does.
    pub fn new(
        controller: &ControllerSpec,
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
    ) -> Result<Self, CbfSettingsError> {
        let mut cbf = controller.cbf;
        if let Some(sensing_m) = spec.sensing_radius_m {
            cbf.sensing_radius_m = cbf.sensing_radius_m.min(sensing_m);
        }
        let controller = match controller.kind {
            ControllerKind::BestPoint => {
                Controller::BestPoint(BestPointController::new(field, obstacles, spec))
            }
            ControllerKind::Cbf => {
                Controller::Cbf(CbfController::new(field, obstacles, spec, cbf)?)
            }
            ControllerKind::ZcbfLogsumexp => {
                Controller::ZcbfLogSumExp(ZcbfLogSumExpController::new(
                    field,
                    obstacles,
                    spec,
                    cbf,
                    controller.lse_sharpness_per_m,
                )?)
            }
            // Its maximum speed is the top speed; without one, the barrier controllers' step.
            ControllerKind::Orca => Controller::Orca(
                OrcaController::new(
                    field,
                    obstacles,
                    spec,
                    spec.max_step_m.unwrap_or(cbf.max_speed_m_per_s * cbf.dt_s),
                    spec.sensing_radius_m,
                )
                .with_settings(controller.orca),
            ),
        };
        Ok(Self {
            controller,
            spec: *spec,
            moving: Vec::new(),
            statics: DiskGrid::new(Vec::new()),
            polygons: PolygonLayer::default(),
            obstacles: DiskGrid::new(if spec.kinematics.has_heading() {
                obstacles.to_vec()
            } else {
                Vec::new()
            }),
            field,
            formation: Vec::new(),
        })
    }

    /// This controller knowing every agent of the formation (`agents`, by index): an agent
    /// that looks ahead gives way to a mate far behind its slot ([`Aim::lagging`]).
    pub fn with_formation(mut self, agents: &[AgentSpec]) -> Self {
        self.formation = agents.to_vec();
        self
    }

    /// This controller in a world with `moving` obstacles: [`Self::plan`] plans around
    /// them. `obstacles` are the static ones given to [`Self::new`] (true radii).
    pub fn with_moving(mut self, moving: &[MovingObstacle], obstacles: &[Disk]) -> Self {
        if !moving.is_empty() {
            self.moving = moving.to_vec();
            self.statics = DiskGrid::new(obstacles.to_vec());
        }
        self
    }

    /// This controller also planning round the static `polygons` (only the best-point
    /// controller plans round polygons; scenario validation refuses the others beside
    /// them).
    pub fn with_polygons(mut self, polygons: &[Polygon]) -> Self {
        if let Controller::BestPoint(c) = self.controller {
            self.controller = Controller::BestPoint(c.with_polygons(polygons));
        }
        // An escape from a moving obstacle keeps clear of them too.
        self.polygons = PolygonLayer::new(
            polygons
                .iter()
                .map(|p| InflatedPolygon::from_polygon(p.clone(), 0.0))
                .collect(),
        );
        self
    }

    /// This controller knowing that the polygons from `map.first_piece` on are `map`'s
    /// blocked cells (`None`: no map): see [`BestPointController::with_map`].
    pub fn with_map(mut self, map: Option<&ScenarioMap>) -> Self {
        if let (Controller::BestPoint(c), Some(map)) = (&self.controller, map) {
            self.controller = Controller::BestPoint(c.clone().with_map(map));
        }
        self
    }

    /// The agent this controller moves.
    pub fn spec(&self) -> &AgentSpec {
        &self.spec
    }

    /// Plan this agent's move for `turn`: the one entry point of every controller.
    ///
    /// Every other body stands still while the agent moves. With a sensing radius the
    /// controller sees only the bodies of `turn.others` (and the obstacles) whose disks
    /// come within it, so bodies beyond it change nothing. With a top speed the move is the
    /// first `max_step_m` of the controller's path, with status [`MoveStatus::UnderWay`]
    /// when it stops short of the best point.
    ///
    /// **Moving obstacles** stand where they are at `turn.step`
    /// ([`crate::world::moving_obstacle`]). The agent plans around each one it senses as around a
    /// disk grown by twice the obstacle's speed, or as much of that as leaves it outside:
    /// at least the obstacle's reach ([`MovingObstacle::reach_disk_at`], where it can be
    /// until the agent's next turn), so a move that ends outside it is still clear after
    /// the obstacle's next motion, and a step to spare where there is room. An agent that
    /// starts its turn inside such a disk (the obstacle came closer since its last turn)
    /// first escapes: a straight motion out of the disk, radially or up to 150 degrees
    /// off, that is clear of every body and within its top speed, or else the shortest
    /// path out round the bodies in its way (`escape.rs`); the rest of the turn is planned
    /// from there with what is left of the top speed. Without an escape, the disk is
    /// shrunk to leave the agent outside. Then it looks ahead (`look_ahead.rs`): when the
    /// move would end where a sensed obstacle's reach will be within
    /// [`LOOKAHEAD_TRIGGER_TURNS`] steps along its route, the straight move from whose end
    /// the agent can keep clear longest (up to [`SURVIVAL_TURNS`], moving on as it likes)
    /// is taken instead.
    ///
    /// **The centre's plan** (`turn.ahead`): a holonomic agent with a top speed and a
    /// look-ahead (`AgentSpec::horizon_steps` > 0) knows where its slot will be over the
    /// next steps ([`Aim`]): when that way crosses a static obstacle it takes the first
    /// move of the best track round it, and when it cannot follow its slot exactly it aims
    /// at the first point of its least-deviation track ([`crate::control::tracking::lead_point`]);
    /// see [`BestPointController::plan_move_aiming`]. Only the best-point controller looks
    /// ahead; the others, an agent with a heading (not yet: see `aim`), without a top speed
    /// or with a horizon of 0, and an agent that can follow its slot along a way clear of
    /// obstacles, plan exactly as without `ahead`, bit for bit. With
    /// [`Self::with_formation`], an agent that looks ahead gives way to a mate of
    /// `turn.mates` it senses far behind its slot ([`Aim::lagging`]).
    ///
    /// **A heading** (`turn.heading_rad`, for a unicycle or a car): a unicycle agent plans
    /// its path as a holonomic one would (a disk turning in place sweeps nothing new, so
    /// the path's safety holds for it), then follows it by turning in place and driving
    /// straight, as far as one step's time allows ([`drive_unicycle`]); it ends facing the
    /// centre's heading when the scenario asks for it (`align_heading`); with the barrier
    /// controller it drives and turns at once ([`CbfController::plan_unicycle_move`]). A
    /// car agent drives the shortest clear Dubins or Reeds-Shepp path to the holonomic
    /// best point, cut at the top speed, and stands when it finds none (`car.rs`). A move
    /// cut short is [`MoveStatus::UnderWay`]. The move carries the heading it ends at.
    ///
    /// **Velocities** (`turn.velocities`, every agent moving at once): the ORCA controller
    /// plans in its own model ([`OrcaController::plan_move_reciprocal`]); the other
    /// controllers ignore them.
    pub fn plan(&self, turn: &TurnRequest<'_>) -> Move {
        let TurnRequest {
            step,
            ref centre,
            ahead,
            ref me,
            heading_rad,
            others,
            mates,
            velocities,
        } = *turn;
        if let (Controller::Orca(p), Some(v)) = (&self.controller, velocities) {
            let (sensed, sensed_velocities): (Vec<Body>, Vec<Vector>) = others
                .iter()
                .zip(&v.others)
                .filter(|(b, _)| self.spec.senses(me, &b.position, b.radius_m))
                .map(|(b, v)| (*b, *v))
                .unzip();
            return p.plan_move_reciprocal(centre, me, &v.me, &sensed, &sensed_velocities);
        }
        let aim = self.aim(centre, ahead, me, mates);
        let aim = aim.as_ref();
        match heading_rad {
            Some(h) => self.plan_turn_with_heading_aiming(step, centre, aim, me, h, others),
            None => self.plan_turn_aiming(step, centre, aim, me, others),
        }
    }

    /// Where this agent is heading this turn (`None`: it does not look ahead): see
    /// [`Self::plan`].
    fn aim(&self, centre: &Pose, ahead: &[Pose], me: &Point, mates: &[MateView]) -> Option<Aim> {
        let (Controller::BestPoint(_), Some(max_step_m)) = (&self.controller, self.spec.max_step_m)
        else {
            return None;
        };
        // An agent with a heading spends part of a step turning, so the lead point (a
        // whole step of travel) misleads it: measured on paper-unicycle, paper-car and
        // narrow-reversing-car, the mean deviation rose by 4 to 23 %.
        if self.spec.kinematics.has_heading() {
            return None;
        }
        let horizon = self.spec.horizon_steps.min(ahead.len());
        if horizon == 0 {
            return None;
        }
        let slots: Vec<Point> = std::iter::once(centre)
            .chain(&ahead[..horizon])
            .map(|c| self.spec.slot.ideal_position(c))
            .collect();
        let lead = tracking::lead_point(me, &slots, max_step_m);
        let lagging = self.lagging_mates(centre, ahead, me, &slots, mates);
        Some(Aim {
            lead,
            slots,
            lagging,
        })
    }

    /// A turn of an agent without a heading (see [`Self::plan`]), with the best point
    /// taken for `aim` when given.
    fn plan_turn_aiming(
        &self,
        step: usize,
        centre: &Pose,
        aim: Option<&Aim>,
        me: &Point,
        others: &[Body],
    ) -> Move {
        if self.moving.is_empty() {
            return self.plan_move_within(centre, aim, me, others, self.spec.max_step_m);
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
        let mv = self.plan_turn_around(step, centre, aim, me, others, &sensed, &reach);
        self.look_ahead(step, me, others, &sensed, &reach, mv)
    }

    /// A turn of an agent facing `heading_rad` (see [`Self::plan`]: a holonomic agent
    /// ignores it), with the best point taken for `aim` when given.
    fn plan_turn_with_heading_aiming(
        &self,
        step: usize,
        centre: &Pose,
        aim: Option<&Aim>,
        me: &Point,
        heading_rad: f64,
        others: &[Body],
    ) -> Move {
        if let Kinematics::Car {
            turning_radius_m,
            reverse,
        } = self.spec.kinematics
        {
            let start = Pose::new(me.x, me.y, heading_rad);
            return self.plan_car_turn(centre, aim, &start, others, turning_radius_m, reverse);
        }
        let Kinematics::Unicycle {
            max_turn_rad,
            reverse,
        } = self.spec.kinematics
        else {
            return self.plan_turn_aiming(step, centre, aim, me, others);
        };
        // Validation gives a unicycle a top speed, and no moving obstacles beside it.
        let Some(max_step_m) = self.spec.max_step_m else {
            return self.plan_turn_aiming(step, centre, aim, me, others);
        };
        let limits = UnicycleLimits {
            max_step_m,
            max_turn_rad,
            reverse,
        };
        // The barrier controller drives a unicycle the Robotarium's way: speed and turn
        // rate at once, from the barrier on a point ahead of it.
        if let Controller::Cbf(p) = &self.controller {
            let others = &*self.sensed_bodies(me, others);
            let align = self.spec.align_heading.then_some(centre.heading_rad);
            return p.plan_unicycle_move(centre, me, heading_rad, others, &limits, align);
        }
        // The path is cut at the top speed (on an arc, at a free point), further than
        // the agent can drive this step, and drawn with chords of at most a quarter of it:
        // where the step's time runs out inside a chord that cuts into a disk's margin,
        // the agent stops at the chord's start, so each step loses at most one short chord.
        let mut mv = match &self.controller {
            Controller::BestPoint(p) => p.plan_move_aiming(
                centre,
                aim,
                me,
                &self.sensed_bodies(me, others),
                Some(max_step_m),
                UNICYCLE_CHORD_SHARE * max_step_m,
            ),
            _ => self.plan_move_within(centre, aim, me, others, None),
        };
        let align = self.spec.align_heading.then_some(centre.heading_rad);
        let driven = drive_unicycle(heading_rad, &mv.waypoints, align, &limits);
        let mut waypoints = driven.waypoints;
        // A stop inside a segment may lie within the planning margin of a body (on the
        // chord of an arc round it), where the next turn could not plan from: then the
        // agent stops at the segment's start instead, already facing along it.
        let k = waypoints.len();
        if k >= 2 && waypoints[k - 1] != mv.waypoints[k - 1] {
            let stop = waypoints[k - 1];
            let reach_m = self.spec.radius_m + PLANNING_MARGIN_M;
            let clear =
                |centre: &Point, radius_m: f64| (stop - centre).norm() >= radius_m + reach_m;
            let free = others.iter().all(|b| clear(&b.position, b.radius_m))
                && self
                    .obstacles
                    .all_near(&stop, reach_m + self.obstacles.max_radius_m(), |d| {
                        clear(&d.centre, d.radius_m)
                    });
            if !free {
                waypoints.pop();
            }
        }
        mv.waypoints = waypoints;
        mv.end_heading_rad = Some(driven.end_heading_rad);
        if !driven.complete {
            mv.status = MoveStatus::UnderWay;
        }
        mv
    }

    /// A car's turn ([`car`]): the best point as for a holonomic agent, then the
    /// shortest clear drivable path to it from `start` (where the car stands and faces),
    /// cut at the top speed; standing when none is clear.
    fn plan_car_turn(
        &self,
        centre: &Pose,
        aim: Option<&Aim>,
        start: &Pose,
        others: &[Body],
        turning_radius_m: f64,
        reverse: bool,
    ) -> Move {
        let (me, heading_rad) = (&start.position(), start.heading_rad);
        let others = &*self.sensed_bodies(me, others);
        let mut mv = self.plan_move_within(centre, aim, me, others, None);
        let stand = |mut mv: Move| {
            mv.best = *me;
            mv.waypoints = vec![*me];
            mv.end_heading_rad = Some(heading_rad);
            if mv.status != MoveStatus::NoFreePoint {
                mv.status = MoveStatus::Stayed;
            }
            mv
        };
        // Validation gives a car a top speed.
        let (Some(max_step_m), Some(&goal)) = (self.spec.max_step_m, mv.waypoints.last()) else {
            return stand(mv);
        };
        if mv.waypoints.len() < 2 {
            mv.end_heading_rad = Some(heading_rad);
            return mv;
        }
        let goal_headings: Vec<f64> = if self.spec.align_heading {
            vec![centre.heading_rad]
        } else {
            std::iter::once(centre.heading_rad)
                .chain(
                    (0..car::GOAL_HEADINGS)
                        .map(|k| std::f64::consts::TAU * k as f64 / car::GOAL_HEADINGS as f64),
                )
                .chain([heading_rad])
                .collect()
        };
        let limits = CarLimits {
            max_step_m,
            turning_radius_m,
            reverse,
        };
        let world = car::CarWorld {
            field: &self.field,
            obstacles: &self.obstacles,
            others,
            reach_m: self.spec.radius_m + PLANNING_MARGIN_M,
            margin_m: PLANNING_MARGIN_M,
        };
        let Some(drive) = car::plan_car_drive(start, &goal, &goal_headings, 1, &limits, &world)
        else {
            return stand(mv);
        };
        if !drive.complete {
            mv.status = MoveStatus::UnderWay;
        }
        mv.waypoints = drive.waypoints;
        mv.end_heading_rad = Some(drive.end_heading_rad);
        if let Some(end) = mv.waypoints.last()
            && mv.status != MoveStatus::UnderWay
        {
            // The path ends at the best point up to the rounding of its word (about
            // 1e-9 m): the best point is where it ends (moving the end instead would bend
            // its last, perhaps short, chord).
            mv.best = *end;
        }
        mv
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

    /// The controller's move among `others` (no moving obstacle, no heading) cut at
    /// `max_step_m` (absent: not cut), the best point taken for `aim` when given (the
    /// best-point controller only).
    fn plan_move_within(
        &self,
        centre: &Pose,
        aim: Option<&Aim>,
        me: &Point,
        others: &[Body],
        max_step_m: Option<f64>,
    ) -> Move {
        let others = &*self.sensed_bodies(me, others);
        let mut mv = match &self.controller {
            Controller::BestPoint(p) => {
                p.plan_move_aiming(centre, aim, me, others, max_step_m, f64::INFINITY)
            }
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
