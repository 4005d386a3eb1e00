//! One agent's turn (the inner loop of the paper's Fig. 5): ideal slot, reachable best
//! point, shortest collision-free path to it, as a polyline the agent then follows.
//!
//! This is the one place the decision is made: the reference simulation and the agent
//! process both call [`TurnPlanner::plan_move`] (the paper's [`BestPointPlanner`] or a
//! barrier planner), so their trajectories agree to the bit.

use crate::best_point::{self, BestPointError};
use crate::cbf::{CbfPlanner, ZcbfLogSumExpPlanner};
use crate::disk_path::{self, DiskPath};
use crate::formation::Slot;
use crate::geometry::{Disk, DiskGrid, Field, FreeSpace, Point, Pose, Vector};
use crate::vocabulary::{
    AgentSpec, Body, CbfSettingsError, MAX_WAYPOINTS, Move, MoveStatus, PlannerKind, PlannerSpec,
};

/// Extra inflation of every disk when choosing the best point and planning the path, in
/// metres. It absorbs rounding and the chords of arcs: the followed polyline stays at
/// least half of it away from every true body.
pub const PLANNING_MARGIN_M: f64 = 1e-3;

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
        }
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
    /// point nearest to the slot and the shortest path there.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
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
        let layers = [&self.obstacles, &agents];
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
        let mut waypoints: Vec<Point> = path
            .polyline(0.5 * PLANNING_MARGIN_M)
            .iter()
            .map(to_world)
            .collect();
        if waypoints.len() > MAX_WAYPOINTS {
            return stay(MoveStatus::PathTooLong);
        }
        // The polyline starts at the agent and ends at the best point, exactly.
        if let Some(first) = waypoints.first_mut() {
            *first = *me;
        }
        if let Some(last) = waypoints.last_mut() {
            *last = best;
        }
        let status = if (slot - best).norm() <= 1e-9 {
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

/// Any of the controllers, behind one `plan_move`: what the reference simulation and the
/// agent processes call.
#[derive(Clone, Debug)]
pub enum TurnPlanner {
    /// The paper's method, exact ([`BestPointPlanner`]).
    BestPoint(BestPointPlanner),
    /// The control-barrier-function QP.
    Cbf(CbfPlanner),
    /// The paper's failed LogSumExp barrier, for comparison.
    ZcbfLogSumExp(ZcbfLogSumExpPlanner),
}

impl TurnPlanner {
    /// The planner `planner.kind` for agent `spec` in `field` among `obstacles` (true
    /// radii).
    pub fn new(
        planner: &PlannerSpec,
        field: Field,
        obstacles: &[Disk],
        spec: &AgentSpec,
    ) -> Result<Self, CbfSettingsError> {
        Ok(match planner.kind {
            PlannerKind::BestPoint => {
                Self::BestPoint(BestPointPlanner::new(field, obstacles, spec))
            }
            PlannerKind::Cbf => Self::Cbf(CbfPlanner::new(field, obstacles, spec, planner.cbf)?),
            PlannerKind::ZcbfLogsumexp => Self::ZcbfLogSumExp(ZcbfLogSumExpPlanner::new(
                field,
                obstacles,
                spec,
                planner.cbf,
                planner.lse_sharpness_per_m,
            )?),
        })
    }

    /// Plan this agent's move while every `other` body stands still.
    pub fn plan_move(&self, centre: &Pose, me: &Point, others: &[Body]) -> Move {
        match self {
            Self::BestPoint(p) => p.plan_move(centre, me, others),
            Self::Cbf(p) => p.plan_move(centre, me, others),
            Self::ZcbfLogSumExp(p) => p.plan_move(centre, me, others),
        }
    }
}
