//! The look-ahead along the moving obstacles' routes: when a planned move would end
//! where an obstacle's reach soon will be, the straight move from whose end the agent can
//! keep clear longest.

use crate::control::survival_grid::SurvivalGrid;
use crate::control::vocabulary::{Body, Move, MoveStatus};
use crate::geometry::{Disk, Point, Vector};
use crate::world::moving_obstacle::MovingObstacle;

use super::{PLANNING_MARGIN_M, TurnController};

/// How many steps ahead along the moving obstacles' routes an agent looks when it weighs
/// moves ([`TurnController::plan`]).
pub const LOOKAHEAD_TURNS: usize = 20;

/// An agent replaces its planned move by one that stays clear longer only when an
/// obstacle could reach the planned end within this many of its turns. Measured with
/// `shared/core/examples/strike_survey.rs` and `scenarios/moving-field.toml`: replacing every
/// move not clear for all [`LOOKAHEAD_TURNS`] made agents needlessly wary (the mean
/// deviation in `moving-field` rose from 0.34 m to 2.2 m); with the lattice sweep
/// ([`SURVIVAL_TURNS`]), 4 turns left fewer fields struck than 3 (300 random fields a
/// speed band) or 5 (1 000).
pub const LOOKAHEAD_TRIGGER_TURNS: usize = 4;

/// How many turns ahead an agent that looks ahead sweeps the lattice of points it could
/// move through ([`SurvivalGrid`]): can it keep out of every obstacle's reach that long,
/// moving as it likes?
pub const SURVIVAL_TURNS: usize = 10;

/// Lattice points per top-speed move along a side of the sweep's lattice
/// ([`SURVIVAL_TURNS`]): 3 weighed as well as 4 in the strike survey, at about half the
/// cost.
pub const SURVIVAL_CELLS_PER_MOVE: usize = 3;

// The sweep looks no farther than the turns the look-ahead lays out.
const _: () = assert!(SURVIVAL_TURNS <= LOOKAHEAD_TURNS + LOOKAHEAD_RUN_TURNS);

/// How many directions, evenly spread, an agent weighs a straight move in when looking
/// ahead (every 10 degrees).
pub const LOOKAHEAD_DIRECTIONS: usize = 36;

/// How many turns on along a straight move an agent weighs when looking ahead: a way out
/// of a gap that is closing may take several turns at the top speed.
pub const LOOKAHEAD_RUN_TURNS: usize = 8;

impl TurnController {
    /// The move `planned`, or one that keeps the agent clear of the `sensed` moving
    /// obstacles longer.
    ///
    /// An agent knows each obstacle's route, so it can tell for how many of its next
    /// [`LOOKAHEAD_TURNS`] turns a point would stay outside every obstacle's reach disk
    /// there (each grown by the agent's radius): for so many turns the agent could stand
    /// there and still begin every turn where the obstacles' next motion cannot reach it.
    /// When the planned move ends where that holds for fewer than
    /// [`LOOKAHEAD_TRIGGER_TURNS`] turns, the agent weighs straight moves in
    /// [`LOOKAHEAD_DIRECTIONS`] directions, at its top speed and at half of it, each clear
    /// of every body, the field's edges and the obstacles where they stand and ending
    /// outside every reach disk (as an escape must). The best one is the one from whose
    /// end the agent can keep out of every reach disk for the most turns (up to
    /// [`SURVIVAL_TURNS`]) moving as it likes, its mates standing where they are
    /// ([`SurvivalGrid`]: a gap the obstacles are closing may take several moves to
    /// leave); then the one whose end stays clear for the most turns standing there (up
    /// to the trigger); then the one with the longest horizon when the agent goes on the
    /// same way at its top speed for up to [`LOOKAHEAD_RUN_TURNS`] turns before it stands;
    /// then the smallest overlap where that horizon ends; then the one ending nearest the
    /// slot. It replaces the planned move when it is better by the same order. So an
    /// agent leaves an obstacle's path, or a gap obstacles are closing, while there is
    /// still room, rather than when the obstacle's reach is upon it and its mates are in
    /// the way. Without a top speed the planned move is kept.
    pub(super) fn look_ahead(
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
        // next LOOKAHEAD_TRIGGER_TURNS turns.
        let end = planned.end();
        let safe_for_now = (1..=LOOKAHEAD_TRIGGER_TURNS).all(|j| {
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
        let turns = LOOKAHEAD_TURNS + LOOKAHEAD_RUN_TURNS;
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
        // many turns (up to LOOKAHEAD_TURNS) it stays outside every reach disk, and the
        // gap at the first turn it does not (infinite when it always does).
        let clear_from = |p: &Point, from: usize| -> (usize, f64) {
            for j in 1..=LOOKAHEAD_TURNS {
                let gap_m = ahead
                    .iter()
                    .map(|(centres, big_r)| (p - centres[from + j]).norm() - big_r)
                    .fold(f64::INFINITY, f64::min);
                if gap_m < 0.0 {
                    return (j - 1, gap_m);
                }
            }
            (LOOKAHEAD_TURNS, f64::INFINITY)
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
        // there does (up to LOOKAHEAD_TRIGGER_TURNS, the least an agent wants); the
        // longest clear horizon of standing there or going on along `v` at the top speed
        // for up to LOOKAHEAD_RUN_TURNS turns (each ending outside that turn's reach
        // disks and in the field) and then standing; the gap where that horizon ends; and
        // the distance from `q` to the slot.
        type Score = (usize, usize, usize, f64, f64);
        let score = |q: &Point, v: Option<Vector>| -> Score {
            let (standing, mut gap_m) = clear_from(q, 0);
            let mut horizon = standing;
            // Going on along `v`, as long as each turn ends outside its reach disks and
            // in the field, and the horizon can still grow.
            for (n, v) in (1..=LOOKAHEAD_RUN_TURNS).flat_map(|n| v.map(|v| (n, v))) {
                let p = q + (n as f64 * budget_m) * v;
                let inside_reach = ahead
                    .iter()
                    .any(|(centres, big_r)| (p - centres[n]).norm() < *big_r);
                if horizon == LOOKAHEAD_TURNS
                    || inside_reach
                    || self.field.signed_inset_m(&p) < clear_m
                {
                    break;
                }
                let (c, g) = clear_from(&p, n);
                if (n + c).min(LOOKAHEAD_TURNS) > horizon {
                    (horizon, gap_m) = ((n + c).min(LOOKAHEAD_TURNS), g);
                }
            }
            (
                sweep.turns_clear(q).max(standing.min(SURVIVAL_TURNS)),
                standing.min(LOOKAHEAD_TRIGGER_TURNS),
                horizon,
                gap_m,
                (q - slot).norm(),
            )
        };
        let better = |a: Score, b: Score| {
            if (a.0, a.1, a.2) != (b.0, b.1, b.2) {
                (a.0, a.1, a.2) > (b.0, b.1, b.2)
            } else if a.2 < LOOKAHEAD_TURNS && a.3 != b.3 {
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
                end_heading_rad: None,
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
}
