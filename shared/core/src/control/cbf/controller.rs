//! The safe control-barrier-function controller.

use crate::control::formation::Slot;
use crate::control::vocabulary::{
    AgentSpec, Body, CBF_MARGIN_M, CBF_STALL_SHARE, CbfSettings, CbfSettingsError, Move,
};
use crate::geometry::{Disk, DiskGrid, Field, Point, Pose, Vector};

use super::*;

/// The CBF-QP controller of one agent: one barrier constraint per sensed neighbour and per
/// field edge, an exact QP, straight pieces over `dt` (see the module documentation for
/// the safety argument and the deadlock escape). Same turn interface as
/// [`crate::control::turn::BestPointController`].
#[derive(Clone, Debug)]
pub struct CbfController {
    pub(super) field: Field,
    pub(super) slot: Slot,
    pub(super) radius_m: f64,
    /// Static obstacles, true radii.
    pub(super) obstacles: DiskGrid,
    pub(super) settings: CbfSettings,
}

impl CbfController {
    /// The controller of agent `spec` in `field` among `obstacles` (true radii), after
    /// checking `settings` for this agent ([`CbfSettings::validate_for_agent`]).
    pub fn new(
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
        settings: CbfSettings,
    ) -> Result<Self, CbfSettingsError> {
        settings.validate_for_agent(spec.radius_m)?;
        Ok(Self {
            field,
            slot: spec.slot,
            radius_m: spec.radius_m,
            obstacles: DiskGrid::new(obstacles.to_vec()),
            settings,
        })
    }

    /// This agent's radius, in metres.
    pub fn radius_m(&self) -> f64 {
        self.radius_m
    }

    /// The settings in use.
    pub fn settings(&self) -> &CbfSettings {
        &self.settings
    }

    /// The ideal slot when the centre is at `centre`.
    pub fn slot_position(&self, centre: &Pose) -> Point {
        self.slot.ideal_position(centre)
    }

    /// The safety constraints on the velocity of the agent at `me` (rows `a . u <= b`):
    /// the four field edges, then every sensed obstacle, then every sensed agent of
    /// `others` (half responsibility).
    pub fn constraints(&self, me: &Point, others: &[Body]) -> Vec<HalfPlane> {
        self.constraints_for_disk(me, self.radius_m, others)
    }

    /// [`Self::constraints`] for a disk of `radius_m` at `me` (the projected point of a
    /// unicycle agent stands for a disk larger than the agent: `projection.rs`).
    pub(super) fn constraints_for_disk(
        &self,
        me: &Point,
        radius_m: f64,
        others: &[Body],
    ) -> Vec<HalfPlane> {
        let bodies = sensed(&self.obstacles, others, me, self.settings.sensing_radius_m);
        self.rows_at(me, radius_m, &bodies, self.settings.gamma_per_s)
    }

    /// The barrier rows of a disk of `radius_m` at `me` with class-K gain `gamma`: the
    /// four field edges, then one per body of `bodies` (centre, radius).
    fn rows_at(
        &self,
        me: &Point,
        radius_m: f64,
        bodies: &[(Point, f64)],
        gamma: f64,
    ) -> Vec<HalfPlane> {
        let inset_m = radius_m + CBF_MARGIN_M;
        let mut rows = vec![
            HalfPlane::new(Vector::new(-1.0, 0.0), gamma * (me.x - inset_m)),
            HalfPlane::new(
                Vector::new(1.0, 0.0),
                gamma * (self.field.width_m - inset_m - me.x),
            ),
            HalfPlane::new(Vector::new(0.0, -1.0), gamma * (me.y - inset_m)),
            HalfPlane::new(
                Vector::new(0.0, 1.0),
                gamma * (self.field.height_m - inset_m - me.y),
            ),
        ];
        // The whole responsibility for every body, mates included: they stand still
        // during this turn (or, in a parallel group, cannot reach this agent within the
        // step).
        for &(centre, body_radius_m) in bodies {
            let away = me - centre;
            let reach_m = radius_m + body_radius_m + CBF_MARGIN_M;
            let distance_m = away.norm();
            // (d - R)(d + R) keeps its precision near the boundary, unlike d^2 - R^2.
            let h = (distance_m - reach_m) * (distance_m + reach_m);
            rows.push(HalfPlane::new(-2.0 * away, gamma * h));
        }
        rows
    }

    /// The plain filter's velocity at `me` towards `slot`: the QP's solution, capped at the
    /// maximum speed (a turn of one piece moves by it unless the piece stalls and the
    /// deadlock escape finds a faster way round).
    pub fn velocity(&self, slot: &Point, me: &Point, others: &[Body]) -> Result<Vector, QpError> {
        let u_nom = self.settings.nominal(slot, me);
        let u = solve_qp_2d(&u_nom, &self.constraints(me, others))?;
        Ok(self.settings.capped(u))
    }

    /// Plan this agent's move while every `other` body stands still: `substeps` straight
    /// pieces of `dt / substeps`, each at the CBF-QP velocity from where the last one
    /// ended (gains per piece, see [`CbfSettings::substeps`]), against the bodies sensed
    /// where the turn began (a body farther off cannot be reached within the turn). The
    /// turn ends early where a QP is infeasible (only from an unsafe or non-finite state)
    /// or gives no motion; with no motion at all the agent stays put
    /// ([`MoveStatus::Stayed`]).
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        let slot = self.slot_position(centre);
        let pieces = f64::from(self.settings.substeps);
        let piece = CbfSettings {
            gamma_per_s: self.settings.gamma_per_s * pieces,
            gain_per_s: self.settings.gain_per_s * pieces,
            dt_s: self.settings.dt_s / pieces,
            ..self.settings
        };
        let bodies = sensed(&self.obstacles, others, me, self.settings.sensing_radius_m);

        let mut waypoints = vec![*me];
        let mut at = *me;
        for _ in 0..self.settings.substeps {
            let u_nom = piece.nominal(&slot, &at);
            let rows = self.rows_at(&at, self.radius_m, &bodies, piece.gamma_per_s);
            let u = match solve_qp_2d(&u_nom, &rows) {
                Ok(u) => piece.capped(u),
                Err(_) => break,
            };
            let u = if piece.deadlock_escape {
                escape_stall(&piece, &u_nom, u, &rows)
            } else {
                u
            };
            if u == Vector::zeros() {
                break;
            }
            at += piece.dt_s * u;
            waypoints.push(at);
        }
        Move {
            end_heading_rad: None,
            slot,
            best: at,
            status: step_status(&slot, me, &at),
            waypoints,
        }
    }
}

/// The velocity `u` filtered from `u_nom` under `rows`, or, when it is stalled (under
/// [`CBF_STALL_SHARE`] of the nominal speed), the filtered quarter turn clockwise of the
/// nominal if that is faster ([`CbfSettings::deadlock_escape`]): the same constraints, so
/// as safe.
fn escape_stall(settings: &CbfSettings, u_nom: &Vector, u: Vector, rows: &[HalfPlane]) -> Vector {
    if u.norm() >= CBF_STALL_SHARE * u_nom.norm() {
        return u;
    }
    let clockwise = Vector::new(u_nom.y, -u_nom.x);
    match solve_qp_2d(&clockwise, rows).map(|v| settings.capped(v)) {
        Ok(v) if v.norm() > u.norm() => v,
        _ => u,
    }
}
