//! The formation centre's course in a changing world: the path planned before the run,
//! followed step by step, replanned online when the way ahead is blocked (relaxing the
//! paper's Assumption 7), and held while the way is shut or an agent lags behind.
//!
//! At the start of every step `k` (before the moving obstacles move and the agents take
//! their turns), [`Course::advance`]:
//!
//! 1. marks as known every obstacle of `[[obstacles.unknown]]` that a live agent senses
//!    from where it stands (every one of them at step 1 when agents sense without limit);
//! 2. holds the centre where it is while a live agent is farther than `[path] max_lag_m`
//!    from its slot, for at most [`MAX_LAG_WAIT_STEPS`] steps in a row;
//! 3. checks the rest of the path: it is blocked when a known obstacle comes within the
//!    centre clearance of it, or when a moving obstacle will, within
//!    [`LOOKAHEAD_STEPS`] steps, come within that clearance of where the centre will then
//!    be. A blocked path is replanned with Hybrid A* from the current pose to the goal,
//!    around the known obstacles and around every place a conflicting moving obstacle
//!    takes in the look-ahead. When there is no such path, or the new one is blocked in
//!    the same way, the centre waits and tries again: the next step when moving
//!    obstacles are in the way, else after a pause that doubles from one step up to
//!    [`MAX_REPLAN_PAUSE_STEPS`]; for at most [`MAX_BLOCKED_WAIT_STEPS`] steps
//!    in a row before the run gives up (as it does after [`MAX_COURSE_STEPS_FACTOR`]
//!    times the first plan's steps plus [`MAX_BLOCKED_WAIT_STEPS`] in all);
//! 4. otherwise moves the centre one pose along the path.
//!
//! A scenario where nothing changes ([`Scenario::changes`]) follows the first plan pose
//! by pose, as the paper does. Every decision depends on geometry alone, so the reference
//! simulation and the multi-process run take the same course, bit for bit; only the
//! planning times differ.

use std::time::Instant;

use crate::control::vocabulary::Body;
use crate::geometry::{Disk, Pose};
use crate::paths::hybrid_astar::{
    self, HybridAStarSettings, PlanError, Replanner, first_blocked_pose,
};
use crate::world::scenario::Scenario;

/// How many steps ahead the centre looks for moving obstacles crossing its path.
pub const LOOKAHEAD_STEPS: usize = 20;
/// Longest hold, in steps in a row, while an agent lags behind (`[path] max_lag_m`).
pub const MAX_LAG_WAIT_STEPS: usize = 50;
/// Longest wait, in steps in a row, for a way through before the run gives up.
pub const MAX_BLOCKED_WAIT_STEPS: usize = 400;
/// Longest pause, in steps, between two tries to replan while the way stays blocked: the
/// pause doubles after every try that finds no way, from 1 step up to this.
pub const MAX_REPLAN_PAUSE_STEPS: usize = 16;
/// A run gives up after this many times the first plan's steps, plus
/// [`MAX_BLOCKED_WAIT_STEPS`] (waits and detours have their bound).
pub const MAX_COURSE_STEPS_FACTOR: usize = 10;

/// Why the centre's path was planned again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReplanReason {
    /// An obstacle found on the way blocks the rest of the path.
    FoundObstacle,
    /// A moving obstacle will cross the path within the look-ahead.
    MovingObstacle,
}

impl ReplanReason {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            ReplanReason::FoundObstacle => "found-obstacle",
            ReplanReason::MovingObstacle => "moving-obstacle",
        }
    }
}

/// Why the centre held its pose for a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WaitReason {
    /// A live agent was farther than `max_lag_m` from its slot.
    Lag,
    /// The path was blocked and no way through was found.
    Blocked,
}

impl WaitReason {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            WaitReason::Lag => "lag",
            WaitReason::Blocked => "blocked",
        }
    }
}

/// One replanning of the centre's path.
#[derive(Clone, Debug, PartialEq)]
pub struct Replan {
    /// The step at whose start it was planned.
    pub step: usize,
    /// Why.
    pub reason: ReplanReason,
    /// Wall time of the planning, in milliseconds (the only figure that is not the same
    /// from run to run).
    pub planning_ms: f64,
    /// Whether a path was found and taken (false: the centre waited).
    pub found: bool,
    /// The new path, one pose per step from the current pose (empty when none was found).
    pub path: Vec<Pose>,
}

/// One step the centre held its pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wait {
    /// The step.
    pub step: usize,
    /// Why.
    pub reason: WaitReason,
}

/// The centre's course through a run (see the module documentation).
#[derive(Debug)]
pub struct Course<'a> {
    scenario: &'a Scenario,
    settings: HybridAStarSettings,
    /// Built at the first replanning around found obstacles; keeps the heuristic between
    /// replannings (the known obstacles only grow, which it updates in place).
    replanner: Option<Replanner>,
    /// The same for replannings around moving obstacles (whose places change every time).
    replanner_moving: Option<Replanner>,
    /// No replanning before this step (the pause after tries that found no way).
    retry_at: usize,
    /// Tries in a row that found no way.
    failed_tries: u32,
    /// The run gives up at this step.
    step_limit: usize,
    /// The path being followed, one pose per step.
    plan: Vec<Pose>,
    /// Index in `plan` of the current pose.
    at: usize,
    /// The obstacles the centre's planner knows: the scenario's, then those found.
    known: Vec<Disk>,
    /// For each `[[obstacles.unknown]]` obstacle, the step it became known.
    found_at: Vec<Option<usize>>,
    /// Steps in a row the centre has held for a lagging agent.
    lag_waits: usize,
    /// Steps in a row the centre has waited for a way through.
    blocked_waits: usize,
    /// Whether an obstacle found earlier still blocks the path (no way was found yet).
    blocked_by_found: bool,
    replans: Vec<Replan>,
    waits: Vec<Wait>,
    gave_up: bool,
}

impl<'a> Course<'a> {
    /// The course of `scenario` starting along `first_plan` (one pose per step, the start
    /// pose first: [`crate::run::simulate::plan_centre_path`]).
    pub fn new(scenario: &'a Scenario, first_plan: &[Pose]) -> Self {
        let p = &scenario.path;
        Self {
            scenario,
            settings: HybridAStarSettings::new(
                p.turning_radius_m,
                p.centre_clearance_m,
                p.allow_reverse,
            ),
            replanner: None,
            replanner_moving: None,
            retry_at: 0,
            failed_tries: 0,
            step_limit: first_plan
                .len()
                .saturating_mul(MAX_COURSE_STEPS_FACTOR)
                .saturating_add(MAX_BLOCKED_WAIT_STEPS),
            plan: if first_plan.is_empty() {
                vec![p.start]
            } else {
                first_plan.to_vec()
            },
            at: 0,
            known: scenario.obstacles.clone(),
            found_at: vec![None; scenario.unknown.len()],
            lag_waits: 0,
            blocked_waits: 0,
            blocked_by_found: false,
            replans: Vec::new(),
            waits: Vec::new(),
            gave_up: false,
        }
    }

    /// Where the centre stands now.
    pub fn pose(&self) -> Pose {
        self.plan[self.at]
    }

    /// The next poses along the current plan, at most `n`: where the centre goes next if
    /// it does not hold or replan (fewer near the goal). An agent looks ahead along them
    /// ([`crate::control::turn::TurnController::plan`]).
    pub fn ahead(&self, n: usize) -> &[Pose] {
        let from = (self.at + 1).min(self.plan.len());
        &self.plan[from..(from + n).min(self.plan.len())]
    }

    /// The centre pose of `step` (from 1), given every agent's body and liveness at the
    /// end of step `step - 1`; `None` when the run is over: the goal was reached, or the
    /// centre waited too long for a way through ([`Self::gave_up`]).
    pub fn advance(&mut self, step: usize, bodies: &[Body], alive: &[bool]) -> Option<Pose> {
        if self.at + 1 >= self.plan.len() {
            return None;
        }
        if !self.scenario.changes() {
            self.at += 1;
            return Some(self.pose());
        }
        if step > self.step_limit {
            self.gave_up = true;
            return None;
        }
        let found = self.sense_unknown(step, bodies, alive);
        if self.lags(bodies, alive) && self.lag_waits < MAX_LAG_WAIT_STEPS {
            self.lag_waits += 1;
            self.waits.push(Wait {
                step,
                reason: WaitReason::Lag,
            });
            return Some(self.pose());
        }
        self.lag_waits = 0;
        let blocked_by_found =
            (found || self.blocked_by_found) && self.blocked_by_known(&self.plan[self.at + 1..]);
        self.blocked_by_found = blocked_by_found;
        let crossing = self.crossing_movers(step, &self.plan[self.at..]);
        if blocked_by_found || !crossing.is_empty() {
            let reason = if blocked_by_found {
                ReplanReason::FoundObstacle
            } else {
                ReplanReason::MovingObstacle
            };
            let taken = step >= self.retry_at && self.replan(step, reason, &crossing);
            if taken {
                self.failed_tries = 0;
                self.retry_at = 0;
            } else {
                if step >= self.retry_at && reason == ReplanReason::FoundObstacle {
                    // A try that found no way round still obstacles: pause before the
                    // next, longer each time (moving ones are tried again every step, as
                    // they change the way every step).
                    let pause = (1usize << self.failed_tries.min(4)).min(MAX_REPLAN_PAUSE_STEPS);
                    self.failed_tries += 1;
                    self.retry_at = step + pause;
                }
                self.blocked_waits += 1;
                if self.blocked_waits > MAX_BLOCKED_WAIT_STEPS {
                    self.gave_up = true;
                    return None;
                }
                self.waits.push(Wait {
                    step,
                    reason: WaitReason::Blocked,
                });
                return Some(self.pose());
            }
        }
        self.blocked_waits = 0;
        self.at += 1;
        Some(self.pose())
    }

    /// Whether the centre stands at the end of its path (the goal).
    pub fn arrived(&self) -> bool {
        self.at + 1 >= self.plan.len() && !self.gave_up
    }

    /// Whether the run ended because no way through was found for too long.
    pub fn gave_up(&self) -> bool {
        self.gave_up
    }

    /// Every replanning so far, found or not.
    pub fn replans(&self) -> &[Replan] {
        &self.replans
    }

    /// Every step the centre held its pose.
    pub fn waits(&self) -> &[Wait] {
        &self.waits
    }

    /// For each `[[obstacles.unknown]]` obstacle, the step it became known.
    pub fn found_at(&self) -> &[Option<usize>] {
        &self.found_at
    }

    /// Mark the unknown obstacles a live agent senses; true if any was new.
    fn sense_unknown(&mut self, step: usize, bodies: &[Body], alive: &[bool]) -> bool {
        let mut found = false;
        for (j, o) in self.scenario.unknown.iter().enumerate() {
            if self.found_at[j].is_some() {
                continue;
            }
            let seen = self
                .scenario
                .agents
                .iter()
                .zip(bodies)
                .zip(alive)
                .any(|((spec, b), &live)| live && spec.senses(&b.position, &o.centre, o.radius_m));
            if seen {
                self.found_at[j] = Some(step);
                self.known.push(*o);
                found = true;
            }
        }
        found
    }

    /// Whether a live agent is farther than `max_lag_m` from its slot at the current pose.
    fn lags(&self, bodies: &[Body], alive: &[bool]) -> bool {
        let Some(lag_m) = self.scenario.path.max_lag_m else {
            return false;
        };
        let centre = self.pose();
        self.scenario
            .agents
            .iter()
            .zip(bodies)
            .zip(alive)
            .any(|((spec, b), &live)| {
                live && (b.position - spec.slot.ideal_position(&centre)).norm() > lag_m
            })
    }

    /// Whether a known obstacle comes within the centre clearance of a pose of `path`.
    fn blocked_by_known(&self, path: &[Pose]) -> bool {
        let clearance_m = self.scenario.path.centre_clearance_m;
        first_blocked_pose(&self.scenario.field, path, &self.known, clearance_m).is_some()
    }

    /// The moving obstacles that, within the look-ahead, come within the centre clearance
    /// of where the centre would be if it went on along `path` (whose first pose is where
    /// it stands at the start of `step`) one pose a step from `step` on.
    fn crossing_movers(&self, step: usize, path: &[Pose]) -> Vec<usize> {
        let clearance_m = self.scenario.path.centre_clearance_m;
        let last = path.len().saturating_sub(1);
        self.scenario
            .moving
            .iter()
            .enumerate()
            .filter(|(_, m)| {
                (0..=LOOKAHEAD_STEPS).any(|k| {
                    let pose = path[(k + 1).min(last)];
                    m.disk_at(step + k).signed_distance_m(&pose.position()) < clearance_m
                })
            })
            .map(|(i, _)| i)
            .collect()
    }

    /// Plan from the current pose to the goal around the known obstacles and every place
    /// the `crossing` moving obstacles take in the look-ahead; take the path if it is
    /// clear. Recorded either way; true if taken.
    fn replan(&mut self, step: usize, reason: ReplanReason, crossing: &[usize]) -> bool {
        let started = Instant::now();
        let here = self.pose();
        let clearance_m = self.scenario.path.centre_clearance_m;
        let mut obstacles = self.known.clone();
        for &i in crossing {
            let m = &self.scenario.moving[i];
            obstacles.extend((0..=LOOKAHEAD_STEPS).map(|k| m.disk_at(step + k)));
        }
        // An obstacle found within the clearance of where the centre stands is shrunk to
        // leave it room to move away (the agents keep their own distance).
        for o in &mut obstacles {
            let room_m = o.signed_distance_m(&here.position());
            if room_m < clearance_m {
                o.radius_m = (o.radius_m - (clearance_m - room_m) - 1e-6).max(0.0);
            }
        }
        let slot = if crossing.is_empty() {
            &mut self.replanner
        } else {
            &mut self.replanner_moving
        };
        let replanner = match slot.take() {
            Some(r) => Ok(r),
            None => Replanner::new(
                self.scenario.field,
                self.scenario.path.goal,
                self.settings.clone(),
            )
            .map(|r| r.with_polygons(&self.scenario.polygons)),
        };
        let planned: Result<Vec<Pose>, PlanError> = replanner.and_then(|mut r| {
            let dense = r.plan_from(&here, &obstacles);
            *slot = Some(r);
            dense.map(|dense| hybrid_astar::resample(&dense, self.scenario.path.step_m))
        });
        let path = planned
            .ok()
            .filter(|path| path.len() >= 2 && self.crossing_movers(step, path).is_empty());
        let planning_ms = started.elapsed().as_secs_f64() * 1e3;
        let found = path.is_some();
        self.replans.push(Replan {
            step,
            reason,
            planning_ms,
            found,
            path: path.clone().unwrap_or_default(),
        });
        if let Some(path) = path {
            self.plan = path;
            self.at = 0;
            self.blocked_by_found = false;
        }
        found
    }
}
