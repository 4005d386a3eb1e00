//! ORCA mode: the reactive baseline, optimal reciprocal collision avoidance (RVO2), on
//! the `dodgy_2d` crate (a Rust port of RVO2).
//!
//! Each turn the agent is a single integrator taking one step, one step counting as one
//! unit of time (so speeds are metres per step):
//!
//! 1. **Preferred velocity**: straight to the ideal slot, of length
//!    `min(distance, max_step_m)`.
//! 2. **ORCA**: every sensed body (each static obstacle and each other agent whose disk
//!    comes within the sensing radius of the agent's centre) is a neighbour standing
//!    still (velocity zero; the other agents do not move during the turn). Obstacles
//!    are disks, so they are given to ORCA as static agents of the obstacle's radius,
//!    which is exact and costs one ORCA half-plane each, rather than as `dodgy_2d`
//!    polygons, which could only approximate a disk with many edges. The agent takes
//!    the whole responsibility for every neighbour (responsibility 1.0: they do not
//!    move). The time horizon is [`ORCA_TIME_HORIZON_STEPS`] steps; ORCA sees the agent
//!    grown by [`ORCA_RADIUS_MARGIN_M`].
//!
//!    The controller keeps no state between turns, so the agent's current velocity, from
//!    which ORCA builds its half-planes, is taken to be the preferred one. With a
//!    current velocity of zero instead, the half-plane of a body straight ahead would
//!    only slow the agent down along its line, never turn it: it would stop in front of
//!    the body; from the preferred velocity, ORCA projects onto the edge of the velocity
//!    obstacle and the agent slides around. (Exactly head-on, the problem is symmetric
//!    and ORCA still only slows the agent down: like every reactive method, it can stop
//!    in front of a body.)
//!
//!    `dodgy_2d` computes in `f32`, in a frame centred on the agent (relative positions
//!    keep their precision); when ORCA leaves the preferred velocity unchanged the exact
//!    `f64` one is used. Bodies with a non-finite position or radius are not given to
//!    ORCA (`dodgy_2d` may panic on them).
//! 3. **Field**: the end point is clamped into the field inset by the agent's radius
//!    (a box, so the whole segment stays inside), which makes the agent slide along an
//!    edge towards a slot outside the field.
//! 4. **Safety**: ORCA in `f32` is not exactly safe, so the straight segment
//!    `me -> me + v` is checked against every body (every obstacle near enough to be
//!    reached and every other agent, sensed or not, true radii): a segment that keeps
//!    [`ORCA_CLEARANCE_MARGIN_M`] from every body is taken whole; otherwise it is cut,
//!    in closed form, at its first point at twice the margin from a body (nothing is
//!    left of it when it starts there). An agent already overlapping a body stays put.
//!
//! Everything but the `dodgy_2d` call is computed in `f64`, and the result depends only
//! on the inputs (bodies are taken in the order given), bit for bit.
//!
//! Bodies whose disks lie farther than `sensing_radius_m + radius` from the agent's
//! centre change nothing, to the bit, as long as
//! `max_step_m + ORCA_CLEARANCE_MARGIN_M <= sensing_radius_m`: ORCA does not see them and
//! one step cannot come within the margin of them.

use std::borrow::Cow;
use std::ops::ControlFlow;

use dodgy_2d::{Agent, AvoidanceOptions, Vec2};

use crate::control::cbf::AT_SLOT_TOLERANCE_M;
use crate::control::formation::Slot;
use crate::control::vocabulary::{AgentSpec, Body, Move, MoveStatus, OrcaSettings};
use crate::geometry::{Disk, DiskGrid, Field, Point, Pose, Vector};

/// ORCA's time horizon, in steps: velocities that would bring the agent into contact with
/// a neighbour within this many steps are avoided.
pub const ORCA_TIME_HORIZON_STEPS: f32 = 3.0;

/// The clearance, in metres, that the safety cut keeps between the agent and every body
/// (beyond their radii); it absorbs ORCA's `f32` rounding and the cut's own rounding.
pub const ORCA_CLEARANCE_MARGIN_M: f64 = 1e-6;

/// How much ORCA grows the agent's radius, in metres, so that its velocities keep clear
/// of the bodies by more than the safety cut's margin: a step along the edge of ORCA's
/// velocity obstacle is tangent to the grown disk, and the agent slides around a body
/// instead of being cut at [`ORCA_CLEARANCE_MARGIN_M`] and stopping there.
pub const ORCA_RADIUS_MARGIN_M: f64 = 1e-3;

/// Relative slack on the speed limit given to `dodgy_2d`, so that a preferred velocity
/// of exactly `max_step_m` is not rescaled by its `f32` rounding (the result is capped
/// again in `f64`).
const SPEED_SLACK: f64 = 1e-6;

/// A body standing still at `position` (relative to the agent) as ORCA sees it: the
/// agent takes the whole responsibility for it (share 1 / (1 + 0)).
fn standing_still(position: Vec2, radius: f32) -> Cow<'static, Agent> {
    Cow::Owned(Agent {
        position,
        velocity: Vec2::ZERO,
        radius,
        avoidance_responsibility: 0.0,
    })
}

/// The ORCA controller of one agent: ORCA's velocity towards the slot, kept in the field and
/// cut before the first contact (see the module documentation). Same turn interface as
/// [`crate::control::cbf::CbfController`].
#[derive(Clone, Debug)]
pub struct OrcaController {
    field: Field,
    slot: Slot,
    radius_m: f64,
    /// Static obstacles, true radii.
    obstacles: DiskGrid,
    max_step_m: f64,
    sensing_radius_m: Option<f64>,
    /// RVO2's settings in ORCA's own model.
    settings: OrcaSettings,
}

impl OrcaController {
    /// The controller of agent `spec` in `field` among `obstacles` (true radii), moving at
    /// most `max_step_m` per turn and seeing the bodies whose disks come within
    /// `sensing_radius_m` of its centre (`None`: every body). A `max_step_m` that is not
    /// a positive finite number makes the agent stay put. Far bodies are ignored only if
    /// the sensing radius exceeds `max_step_m` (by [`ORCA_CLEARANCE_MARGIN_M`]); a
    /// shorter one stays safe (the safety cut sees every body) but lets unseen bodies
    /// stop the agent.
    pub fn new(
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
        max_step_m: f64,
        sensing_radius_m: Option<f64>,
    ) -> Self {
        Self {
            field,
            slot: spec.slot,
            radius_m: spec.radius_m,
            obstacles: DiskGrid::new(obstacles.to_vec()),
            max_step_m: if max_step_m.is_finite() && max_step_m > 0.0 {
                max_step_m
            } else {
                0.0
            },
            sensing_radius_m,
            settings: OrcaSettings::default(),
        }
    }

    /// The same controller with RVO2's `settings` for its own model
    /// ([`Self::plan_move_reciprocal`]).
    pub fn with_settings(mut self, settings: OrcaSettings) -> Self {
        self.settings = settings;
        self
    }

    /// This agent's radius, in metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The longest move of one turn, in metres (0 when the given one was not a positive
    /// finite number).
    pub fn max_step_m(&self) -> f64 {
        self.max_step_m
    }

    /// The sensing radius, in metres (`None`: every body is sensed).
    pub fn sensing_radius_m(&self) -> Option<f64> {
        self.sensing_radius_m
    }

    /// The ideal slot when the centre is at `centre`.
    pub fn slot_position(&self, centre: &Pose) -> Point {
        self.slot.ideal_position(centre)
    }

    /// Plan this agent's move while every `other` body stands still: one straight step
    /// at ORCA's velocity, kept in the field and cut before any contact. Stays put
    /// ([`MoveStatus::Stayed`], or [`MoveStatus::AtSlot`] at the slot) when it cannot
    /// move, and when it already overlaps a body.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        self.step_at(centre, me, others, others, |preferred| {
            self.orca_velocity(me, others, preferred)
        })
    }

    /// One straight step at the velocity `orca` gives for the preferred one (straight to
    /// the slot, at most `max_step_m`; zero when it is not finite), kept in the field and
    /// cut before any contact with `standing` (those of `others` that do not move) or an
    /// obstacle; staying put when it cannot move or already overlaps a body of `others`.
    fn step_at(
        &self,
        centre: &Pose,
        me: &Point,
        others: &[Body],
        standing: &[Body],
        orca: impl FnOnce(&Vector) -> Vector,
    ) -> Move {
        let slot = self.slot_position(centre);
        let stay = || {
            let status = if (slot - me).norm() <= AT_SLOT_TOLERANCE_M {
                MoveStatus::AtSlot
            } else {
                MoveStatus::Stayed
            };
            Move {
                end_heading_rad: None,
                slot,
                best: *me,
                status,
                waypoints: vec![*me],
            }
        };
        // Overlapping a body already (an unsafe state): stay, before ORCA sees it.
        if self.clear_fraction(me, &Vector::zeros(), others).is_none() {
            return stay();
        }
        let to_slot = slot - me;
        let distance_m = to_slot.norm();
        let preferred = if !(distance_m.is_finite() && me.x.is_finite() && me.y.is_finite()) {
            Vector::zeros()
        } else if distance_m <= self.max_step_m {
            to_slot
        } else {
            to_slot * (self.max_step_m / distance_m)
        };
        let v = self.keep_in_field(me, orca(&preferred));
        let t = self.clear_fraction(me, &v, standing).unwrap_or(0.0);
        if v == Vector::zeros() || t <= 0.0 {
            return stay();
        }
        let end = if t >= 1.0 {
            // Unchanged preferred velocity that reaches the slot: end on it exactly.
            if v == to_slot { slot } else { me + v }
        } else {
            me + t * v
        };
        if end == *me {
            // A step too short to change the position.
            return stay();
        }
        let status = if (slot - end).norm() <= AT_SLOT_TOLERANCE_M {
            MoveStatus::AtSlot
        } else {
            MoveStatus::Deviated
        };
        Move {
            end_heading_rad: None,
            slot,
            best: end,
            status,
            waypoints: vec![*me, end],
        }
    }

    /// This agent's move in ORCA's own model (every agent moves at once,
    /// [`crate::control::vocabulary::TurnMode::Simultaneous`]): it moved by `velocity` over the
    /// last step, and each of `others` by the matching entry of `others_velocity`.
    /// Reciprocal avoidance, RVO2's way: each other agent (the `max_neighbours` nearest
    /// it senses) takes half of the responsibility, each obstacle none, with the time
    /// horizon of its settings ([`OrcaSettings`], `[orca]` in a scenario). The
    /// velocity is then kept in the field and cut before any contact with an obstacle or
    /// a body that stood still over the last step, as in [`Self::plan_move`]. A mate
    /// that moved is expected to move on, out of the way ORCA leaves: the two moves are
    /// the safety monitor's to check against each other in time (if they meet, or if
    /// the mate stands after all and this move runs into it, this one is refused).
    pub fn plan_move_reciprocal(
        &self,
        centre: &Pose,
        me: &Point,
        velocity: &Vector,
        others: &[Body],
        others_velocity: &[Vector],
    ) -> Move {
        let standing: Vec<Body> = others
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                others_velocity
                    .get(*i)
                    .is_none_or(|v| *v == Vector::zeros())
            })
            .map(|(_, b)| *b)
            .collect();
        self.step_at(centre, me, others, &standing, |preferred| {
            self.reciprocal_velocity(me, velocity, others, others_velocity, preferred)
        })
    }

    /// ORCA's velocity in its own model (see [`Self::plan_move_reciprocal`]), at most
    /// `max_step_m` long; zero if ORCA returns a non-finite velocity.
    fn reciprocal_velocity(
        &self,
        me: &Point,
        velocity: &Vector,
        others: &[Body],
        others_velocity: &[Vector],
        preferred: &Vector,
    ) -> Vector {
        if self.max_step_m == 0.0 || *preferred == Vector::zeros() {
            return Vector::zeros();
        }
        let to_f32 = |v: &Vector| Vec2::new(v.x as f32, v.y as f32);
        let usable = |v: Vec2, radius: f32| v.is_finite() && radius.is_finite() && radius >= 0.0;
        let seen = |centre: &Point, radius_m: f64| match self.sensing_radius_m {
            Some(sensing_m) => (me - centre).norm() - radius_m <= sensing_m,
            None => true,
        };
        // The sensed obstacles (in the order given) within RVO2's obstacle range (how far
        // the agent gets within the time horizon), as static agents taking no share.
        let horizon = self.settings.time_horizon_steps;
        let range_m = horizon * self.max_step_m + self.radius_m;
        let mut neighbours: Vec<Cow<'_, Agent>> = self
            .sensed(me, &[])
            .iter()
            .filter(|(centre, radius_m)| (centre - me).norm() - radius_m <= range_m)
            .map(|(centre, radius_m)| (to_f32(&(centre - me)), *radius_m as f32))
            .filter(|&(position, radius)| usable(position, radius))
            .map(|(position, radius)| standing_still(position, radius))
            .collect();
        // The nearest sensed agents, ties by index, each sharing the avoidance.
        let mut near: Vec<(f64, usize)> = others
            .iter()
            .enumerate()
            .filter(|(_, b)| seen(&b.position, b.radius_m))
            .map(|(i, b)| ((b.position - me).norm(), i))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(_, i) in near.iter().take(self.settings.max_neighbours) {
            let (b, v) = (
                &others[i],
                others_velocity.get(i).copied().unwrap_or_default(),
            );
            let (position, radius, v) = (to_f32(&(b.position - me)), b.radius_m as f32, to_f32(&v));
            if usable(position, radius) && v.is_finite() {
                neighbours.push(Cow::Owned(Agent {
                    position,
                    velocity: v,
                    radius,
                    avoidance_responsibility: 1.0,
                }));
            }
        }
        let own = to_f32(velocity);
        let radius = (self.radius_m + ORCA_RADIUS_MARGIN_M) as f32;
        let max_speed = (self.max_step_m * (1.0 + SPEED_SLACK)) as f32;
        let preferred_f32 = to_f32(preferred);
        if !usable(own, radius) || !usable(preferred_f32, radius) || !max_speed.is_finite() {
            return Vector::zeros();
        }
        let agent = Agent {
            position: Vec2::ZERO,
            velocity: own,
            radius,
            avoidance_responsibility: 1.0,
        };
        let options = AvoidanceOptions {
            obstacle_margin: 0.0,
            time_horizon: horizon as f32,
            obstacle_time_horizon: horizon as f32,
        };
        let v = agent.compute_avoiding_velocity(
            &neighbours,
            &[],
            preferred_f32,
            max_speed,
            1.0,
            &options,
        );
        self.capped_answer(v, preferred_f32, preferred)
    }

    /// The bodies ORCA sees from `me`, as `(centre, radius_m)`: the sensed obstacles in
    /// the order given to [`OrcaController::new`], then the sensed `others` in order.
    fn sensed(&self, me: &Point, others: &[Body]) -> Vec<(Point, f64)> {
        let seen = |centre: &Point, radius_m: f64| match self.sensing_radius_m {
            Some(sensing_m) => (me - centre).norm() - radius_m <= sensing_m,
            None => true,
        };
        let mut obstacles: Vec<(usize, Point, f64)> = match self.sensing_radius_m {
            Some(sensing_m) => {
                let mut found = Vec::new();
                // A superset of the sensed obstacles (rounding of the box test aside).
                let reach_m = sensing_m * (1.0 + 1e-9) + 1e-9;
                let _ = self.obstacles.visit_near(me, reach_m, |i, d| {
                    if seen(&d.centre, d.radius_m) {
                        found.push((i, d.centre, d.radius_m));
                    }
                    ControlFlow::<()>::Continue(())
                });
                found
            }
            None => self
                .obstacles
                .disks()
                .iter()
                .enumerate()
                .map(|(i, d)| (i, d.centre, d.radius_m))
                .collect(),
        };
        // The grid's visiting order depends on its layout: restore the given order.
        obstacles.sort_by_key(|&(i, _, _)| i);
        obstacles
            .into_iter()
            .map(|(_, c, r)| (c, r))
            .chain(
                others
                    .iter()
                    .filter(|b| seen(&b.position, b.radius_m))
                    .map(|b| (b.position, b.radius_m)),
            )
            .collect()
    }

    /// ORCA's velocity (metres per step) for the agent at `me` preferring `preferred`
    /// (at most `max_step_m` long), at most `max_step_m` long; zero if ORCA returns a
    /// non-finite velocity.
    fn orca_velocity(&self, me: &Point, others: &[Body], preferred: &Vector) -> Vector {
        if self.max_step_m == 0.0 || *preferred == Vector::zeros() {
            return Vector::zeros();
        }
        let to_f32 = |v: &Vector| Vec2::new(v.x as f32, v.y as f32);
        let usable = |v: Vec2, radius: f32| v.is_finite() && radius.is_finite() && radius >= 0.0;
        let preferred_f32 = to_f32(preferred);
        let max_speed = (self.max_step_m * (1.0 + SPEED_SLACK)) as f32;
        let radius = (self.radius_m + ORCA_RADIUS_MARGIN_M) as f32;
        // A frame centred on the agent: the relative positions keep their precision.
        // `dodgy_2d` may panic on values that are not finite: such bodies are left to the
        // safety cut.
        let neighbours: Vec<Cow<'_, Agent>> = self
            .sensed(me, others)
            .iter()
            .map(|(centre, radius_m)| (to_f32(&(centre - me)), *radius_m as f32))
            .filter(|&(position, radius)| usable(position, radius))
            .map(|(position, radius)| standing_still(position, radius))
            .collect();
        if neighbours.is_empty() || !usable(preferred_f32, radius) || !max_speed.is_finite() {
            return *preferred;
        }
        let agent = Agent {
            position: Vec2::ZERO,
            // Stateless: the preferred velocity stands for the current one (see the
            // module documentation).
            velocity: preferred_f32,
            radius,
            avoidance_responsibility: 1.0,
        };
        let options = AvoidanceOptions {
            obstacle_margin: 0.0,
            time_horizon: ORCA_TIME_HORIZON_STEPS,
            obstacle_time_horizon: ORCA_TIME_HORIZON_STEPS,
        };
        let v = agent.compute_avoiding_velocity(
            &neighbours,
            &[],
            preferred_f32,
            max_speed,
            1.0,
            &options,
        );
        self.capped_answer(v, preferred_f32, preferred)
    }

    /// ORCA's answer `v` for the preferred velocity `preferred` (given to it as
    /// `preferred_f32`) in metres per step: the exact `preferred` when ORCA left it
    /// unchanged, else `v` capped at `max_step_m` (zero when not finite).
    fn capped_answer(&self, v: Vec2, preferred_f32: Vec2, preferred: &Vector) -> Vector {
        if v == preferred_f32 {
            return *preferred;
        }
        let v = Vector::new(f64::from(v.x), f64::from(v.y));
        let speed = v.norm();
        if !speed.is_finite() {
            Vector::zeros()
        } else if speed > self.max_step_m {
            v * (self.max_step_m / speed)
        } else {
            v
        }
    }

    /// `v` changed so that `me + v` lies in the field inset by the agent's radius (the
    /// end point clamped into that box), at most `max_step_m` long; `v` itself when
    /// `me + v` is already inside.
    fn keep_in_field(&self, me: &Point, v: Vector) -> Vector {
        let (low, high_x, high_y) = (
            self.radius_m,
            self.field.width_m - self.radius_m,
            self.field.height_m - self.radius_m,
        );
        let end = me + v;
        if end.x >= low && end.x <= high_x && end.y >= low && end.y <= high_y {
            return v;
        }
        // max then min: no panic on an empty box (a field narrower than the agent).
        let clamped = Point::new(end.x.max(low).min(high_x), end.y.max(low).min(high_y));
        let w = clamped - me;
        let length_m = w.norm();
        if !length_m.is_finite() {
            Vector::zeros()
        } else if length_m > self.max_step_m {
            // Only when `me` itself is outside the box.
            w * (self.max_step_m / length_m)
        } else {
            w
        }
    }

    /// How much of the segment `me -> me + v` the agent may travel, `t` in `[0, 1]`:
    /// all of it when it keeps the agent at least [`ORCA_CLEARANCE_MARGIN_M`] from every
    /// body (every obstacle it can reach and every one of `others`, true radii);
    /// otherwise up to the first point at twice that margin from a body, or nothing when
    /// the agent already stands within twice the margin of a body it approaches. `None`
    /// when the agent already overlaps a body.
    ///
    /// Stopping at twice the margin lets the next turn's move graze the body (slide
    /// along it), whose segment may dip by rounding but stays above one margin.
    fn clear_fraction(&self, me: &Point, v: &Vector, others: &[Body]) -> Option<f64> {
        let mut bodies: Vec<(Point, f64)> =
            others.iter().map(|b| (b.position, b.radius_m)).collect();
        // Every obstacle the segment can come within the margin of (a superset).
        let reach_m =
            (v.norm() + self.radius_m + 2.0 * ORCA_CLEARANCE_MARGIN_M) * (1.0 + 1e-9) + 1e-9;
        let _ = self.obstacles.visit_near(me, reach_m, |_, d| {
            bodies.push((d.centre, d.radius_m));
            ControlFlow::<()>::Continue(())
        });
        let a = v.norm_squared();
        let mut t = 1.0f64;
        for (centre, radius_m) in bodies {
            let away = me - centre;
            let distance_m = away.norm();
            let contact_m = radius_m + self.radius_m;
            if distance_m < contact_m || distance_m == 0.0 {
                return None;
            }
            let b = away.dot(v);
            if a == 0.0 || b >= 0.0 {
                // Not moving, or moving away (or along the tangent): the distance along
                // the segment never shrinks.
                continue;
            }
            // The nearest point of the segment to the body.
            let nearest = away + (-b / a).min(1.0) * v;
            if nearest.norm() >= contact_m + ORCA_CLEARANCE_MARGIN_M {
                continue;
            }
            let stop_m = contact_m + 2.0 * ORCA_CLEARANCE_MARGIN_M;
            if distance_m <= stop_m {
                return Some(0.0);
            }
            // First s with |away + s v| = stop: c + 2 b s + a s^2 = 0, c > 0, b < 0;
            // (d - R)(d + R) keeps its precision near the boundary, unlike d^2 - R^2, and
            // c / (-b + sqrt(b^2 - a c)) is the smaller root without cancellation.
            let c = (distance_m - stop_m) * (distance_m + stop_m);
            let discriminant = (b * b - a * c).max(0.0);
            t = t.min(c / (-b + discriminant.sqrt()));
        }
        Some(t.clamp(0.0, 1.0))
    }
}
