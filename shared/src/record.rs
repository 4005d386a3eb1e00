//! The record of a run: what every agent did at every step, the faults, and the figures
//! the paper reports (deviation, Fig. 9) plus the safety figures (clearance).
//!
//! [`Recorder`] holds the world state during a run and is shared by the reference
//! simulation and the coordinator, so both keep their books the same way.

use serde::Serialize;

use crate::course::{Course, Replan, Wait};
use crate::geometry::{DiskGrid, Point, Pose, distance_polyline_polyline, polyline_length_m};
use crate::safety::{self, SAFETY_TOLERANCE_M, Violation};
use crate::scenario::Scenario;
use crate::vocabulary::{Body, MAX_WAYPOINTS, Move, MoveStatus};

/// One agent at the end of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct AgentStep {
    /// Where the agent stands.
    pub position: Point,
    /// Its ideal slot at this step.
    pub slot: Point,
    /// The best point it chose (its position when it did not move); with a top speed it
    /// may stand short of it ([`MoveStatus::UnderWay`]).
    pub best: Point,
    /// `||position - slot||`, in metres.
    pub deviation_m: f64,
    /// Distance to the nearest other body (obstacle or agent) minus both radii, in metres.
    pub clearance_m: f64,
    /// What it did this step.
    pub status: MoveStatus,
    /// Whether it still belongs to the formation (its process is alive).
    pub alive: bool,
    /// The polyline it followed this step (its position alone when it did not move).
    pub waypoints: Vec<Point>,
}

/// Every agent at the end of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// Step number; step 0 is the formation at the start pose.
    pub step: usize,
    /// The formation centre.
    pub centre: Pose,
    /// One entry per agent, in agent order.
    pub agents: Vec<AgentStep>,
    /// How many groups of turns the step took (one per live agent in sequential mode).
    pub groups: usize,
    /// Where each moving obstacle stands during the step's turns, in scenario order.
    pub moving: Vec<Point>,
    /// `(moving obstacle, agent, distance in metres)` for each live agent that a moving
    /// obstacle's motion at the start of the step came within their radii sum of: empty
    /// in a safe run.
    pub struck: Vec<(usize, usize, f64)>,
}

impl Step {
    /// The longest move of the step, in metres.
    pub fn max_move_m(&self) -> f64 {
        self.agents
            .iter()
            .map(|a| polyline_length_m(&a.waypoints))
            .fold(0.0, f64::max)
    }

    /// Smallest clearance between any two bodies at the end of the step, in metres.
    pub fn min_clearance_m(&self) -> f64 {
        self.agents
            .iter()
            .map(|a| a.clearance_m)
            .fold(f64::INFINITY, f64::min)
    }

    /// Mean deviation of the live agents (the paper's red curve in Fig. 9); 0 when none
    /// is alive.
    pub fn mean_deviation_m(&self) -> f64 {
        let live: Vec<f64> = self
            .agents
            .iter()
            .filter(|a| a.alive)
            .map(|a| a.deviation_m)
            .collect();
        if live.is_empty() {
            0.0
        } else {
            live.iter().sum::<f64>() / live.len() as f64
        }
    }
}

/// What went wrong with an agent, and when.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fault {
    /// The agent.
    pub agent: usize,
    /// The step it happened in.
    pub step: usize,
    /// What happened, as a short name (`rejected`, `missed`, `dead`, `respawned`, ...).
    pub kind: String,
    /// Details for people.
    pub detail: String,
    /// For a detected death: milliseconds from the moment the coordinator started waiting
    /// on the agent (its turn, or the step's liveness check) to the detection.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub detection_ms: Option<f64>,
}

/// A whole run.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The scenario's name.
    pub scenario: String,
    /// The formation centre's poses, one per step.
    pub centre_path: Vec<Pose>,
    /// Every step recorded, starting with step 0.
    pub steps: Vec<Step>,
    /// Every fault, in order.
    pub faults: Vec<Fault>,
    /// Whether the run went through the whole centre path.
    pub completed: bool,
    /// What the centre's course did in a changing world: replans, waits, obstacles found.
    pub course: CourseRecord,
}

/// What the centre's course did during a run ([`Course`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CourseRecord {
    /// Every replanning, found or not.
    pub replans: Vec<Replan>,
    /// Every step the centre held its pose.
    pub waits: Vec<Wait>,
    /// For each `[[obstacles.unknown]]` obstacle, the step it became known.
    pub found_at: Vec<Option<usize>>,
    /// Whether the run ended because no way through was found for too long.
    pub gave_up: bool,
}

impl CourseRecord {
    /// The record of `course` so far.
    pub fn of(course: &Course) -> Self {
        Self {
            replans: course.replans().to_vec(),
            waits: course.waits().to_vec(),
            found_at: course.found_at().to_vec(),
            gave_up: course.gave_up(),
        }
    }
}

/// The figures of a run (the `summary.json` keys that do not depend on timing).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Number of agents.
    pub agents: usize,
    /// Number of steps recorded after step 0.
    pub steps: usize,
    /// Whether the run went through the whole centre path.
    pub completed: bool,
    /// Number of (step, agent) records in which the agent overlaps another body (an
    /// obstacle or an agent) at the end of the step, plus the number of times a moving
    /// obstacle's motion came within an agent's reach: 0 in a safe run.
    pub collisions: usize,
    /// Smallest clearance between two bodies over the run, in metres.
    pub min_clearance_m: f64,
    /// Mean of the per-step mean deviation of the live agents, in metres.
    pub mean_deviation_m: f64,
    /// Largest deviation of a live agent over the run, in metres.
    pub max_deviation_m: f64,
    /// Mean deviation at the last step, in metres.
    pub final_mean_deviation_m: f64,
    /// The longest single move of an agent in one step over the run, in metres.
    pub max_move_m: f64,
    /// Mean number of turn groups per step (steps 1 to the last): the number of live
    /// agents in sequential mode, fewer with parallel turns.
    pub mean_groups_per_step: f64,
    /// Every fault.
    pub faults: Vec<Fault>,
    /// Every replanning of the centre's path (a changing world), found or not.
    pub replans: Vec<ReplanNote>,
    /// Every step the centre held its pose, and why.
    pub waits: Vec<WaitNote>,
    /// For each `[[obstacles.unknown]]` obstacle, the step it became known (`null`: never).
    pub unknown_found_at_step: Vec<Option<usize>>,
    /// Whether the run ended because the centre found no way through for too long.
    pub gave_up: bool,
}

/// One replanning, as `summary.json` lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReplanNote {
    /// The step at whose start it was planned.
    pub step: usize,
    /// `found-obstacle` or `moving-obstacle`.
    pub reason: &'static str,
    /// Wall time of the planning, in milliseconds.
    pub planning_ms: f64,
    /// Whether a path was found and taken (false: the centre waited).
    pub found: bool,
}

/// One step the centre held, as `summary.json` lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WaitNote {
    /// The step.
    pub step: usize,
    /// `lag` (an agent too far behind) or `blocked` (no way through yet).
    pub reason: &'static str,
}

impl Run {
    /// The centre path actually followed, one pose per step (waits repeat a pose).
    pub fn followed_path(&self) -> Vec<Pose> {
        self.steps.iter().map(|s| s.centre).collect()
    }

    /// The run's figures.
    pub fn summary(&self) -> Summary {
        let moving = &self.steps[self.steps.len().min(1)..];
        let mean_deviation_m = if moving.is_empty() {
            0.0
        } else {
            moving.iter().map(Step::mean_deviation_m).sum::<f64>() / moving.len() as f64
        };
        let collisions = self
            .steps
            .iter()
            .map(|s| {
                s.agents
                    .iter()
                    .filter(|a| a.clearance_m < -SAFETY_TOLERANCE_M)
                    .count()
                    + s.struck.len()
            })
            .sum();
        Summary {
            scenario: self.scenario.clone(),
            agents: self.steps.first().map_or(0, |s| s.agents.len()),
            steps: self.steps.len().saturating_sub(1),
            completed: self.completed,
            collisions,
            min_clearance_m: self
                .steps
                .iter()
                .map(Step::min_clearance_m)
                .fold(f64::INFINITY, f64::min),
            mean_deviation_m,
            max_deviation_m: self
                .steps
                .iter()
                .flat_map(|s| s.agents.iter().filter(|a| a.alive).map(|a| a.deviation_m))
                .fold(0.0, f64::max),
            final_mean_deviation_m: self.steps.last().map_or(0.0, Step::mean_deviation_m),
            max_move_m: self.steps.iter().map(Step::max_move_m).fold(0.0, f64::max),
            mean_groups_per_step: if moving.is_empty() {
                0.0
            } else {
                moving.iter().map(|s| s.groups as f64).sum::<f64>() / moving.len() as f64
            },
            faults: self.faults.clone(),
            replans: self
                .course
                .replans
                .iter()
                .map(|r| ReplanNote {
                    step: r.step,
                    reason: r.reason.name(),
                    planning_ms: r.planning_ms,
                    found: r.found,
                })
                .collect(),
            waits: self
                .course
                .waits
                .iter()
                .map(|w| WaitNote {
                    step: w.step,
                    reason: w.reason.name(),
                })
                .collect(),
            unknown_found_at_step: self.course.found_at.clone(),
            gave_up: self.course.gave_up,
        }
    }
}

/// The world during a run: where every agent stands, who is alive, and the record so far.
#[derive(Debug)]
pub struct Recorder<'a> {
    scenario: &'a Scenario,
    /// Every static obstacle, known to the centre or not, with its true radius, for the
    /// safety check and clearances.
    obstacles: DiskGrid,
    /// The moving obstacles where they stand now, true radii.
    moving_now: DiskGrid,
    /// Where each moving obstacle stands now.
    moving: Vec<Point>,
    /// The agents a moving obstacle's motion struck at the start of this step.
    struck: Vec<(usize, usize, f64)>,
    bodies: Vec<Body>,
    alive: Vec<bool>,
    /// This step's moves, one per agent, until the step ends.
    pending: Vec<Option<Move>>,
    /// Groups of turns of this step ([`Self::note_groups`]).
    groups: usize,
    run: Run,
}

impl<'a> Recorder<'a> {
    /// Start a run of `scenario` with the centre at `start`: every agent at its ideal
    /// slot, every moving obstacle at its first waypoint, recorded as step 0.
    pub fn new(scenario: &'a Scenario, start: Pose) -> Self {
        let bodies: Vec<Body> = scenario
            .agents
            .iter()
            .map(|a| Body {
                position: a.slot.ideal_position(&start),
                radius_m: a.radius_m,
            })
            .collect();
        let n = bodies.len();
        let moving: Vec<Point> = scenario.moving.iter().map(|m| m.position_at(0)).collect();
        let mut recorder = Self {
            scenario,
            obstacles: DiskGrid::new(scenario.static_obstacles()),
            moving_now: Self::moving_at(scenario, 0),
            moving,
            struck: Vec::new(),
            bodies,
            alive: vec![true; n],
            pending: vec![None; n],
            groups: 0,
            run: Run {
                scenario: scenario.name.clone(),
                centre_path: vec![start],
                steps: Vec::new(),
                faults: Vec::new(),
                completed: false,
                course: CourseRecord::default(),
            },
        };
        for (i, b) in recorder.bodies.clone().iter().enumerate() {
            recorder.pending[i] = Some(Move {
                slot: b.position,
                best: b.position,
                status: MoveStatus::AtSlot,
                waypoints: vec![b.position],
            });
        }
        recorder.end_step(0);
        recorder
    }

    /// The scenario being run.
    pub fn scenario(&self) -> &Scenario {
        self.scenario
    }

    /// Every moving obstacle where it stands at `step`.
    fn moving_at(scenario: &Scenario, step: usize) -> DiskGrid {
        DiskGrid::new(scenario.moving.iter().map(|m| m.disk_at(step)).collect())
    }

    /// Open step `step` (from 1) with the centre at `centre`: every moving obstacle
    /// drives to where it stands at `step` while the agents stand still, and any live
    /// agent its motion comes within reach of is recorded as struck (in the step, and as
    /// a fault `struck`; see [`crate::moving_obstacle`]). Call before any turn or fault
    /// of the step.
    pub fn begin_step(&mut self, step: usize, centre: Pose) {
        self.run.centre_path.push(centre);
        if self.scenario.moving.is_empty() {
            return;
        }
        for (m, obstacle) in self.scenario.moving.iter().enumerate() {
            let sweep = obstacle.sweep(step);
            for (a, body) in self.bodies.iter().enumerate() {
                if !self.alive[a] {
                    continue;
                }
                let reach_m = obstacle.radius_m + body.radius_m;
                let distance_m = distance_polyline_polyline(&sweep, &[body.position]);
                if distance_m < reach_m - SAFETY_TOLERANCE_M {
                    self.struck.push((m, a, distance_m));
                    self.run.faults.push(Fault {
                        agent: a,
                        step,
                        kind: "struck".to_string(),
                        detail: format!(
                            "moving obstacle {m}'s motion came {distance_m} m from the agent, within their radii sum {reach_m} m"
                        ),
                        detection_ms: None,
                    });
                }
            }
            self.moving[m] = obstacle.position_at(step);
        }
        self.moving_now = Self::moving_at(self.scenario, step);
    }

    /// `(moving obstacle, agent, distance in metres)` for each strike of this step's
    /// obstacle motion ([`Self::begin_step`]), each also recorded as a fault `struck`.
    pub fn struck_now(&self) -> &[(usize, usize, f64)] {
        &self.struck
    }

    /// Where each moving obstacle stands now, in scenario order.
    pub fn moving_positions(&self) -> &[Point] {
        &self.moving
    }

    /// Every agent's body, in agent order.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// Whether each agent is alive, in agent order.
    pub fn alive(&self) -> &[bool] {
        &self.alive
    }

    /// Every body but `agent`'s: the other agents, dead or alive, which stand still.
    pub fn others(&self, agent: usize) -> Vec<Body> {
        self.bodies
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != agent)
            .map(|(_, b)| *b)
            .collect()
    }

    /// The steps recorded so far.
    pub fn steps(&self) -> &[Step] {
        &self.run.steps
    }

    /// Record that this step's turns are taken in `groups` groups.
    pub fn note_groups(&mut self, groups: usize) {
        self.groups = groups;
    }

    /// Check `mv` against the safety invariant (plain geometry) and, if it holds, move
    /// `agent` to where the move ends. A violating move is rejected: the agent stays
    /// where it was, and the rejection is recorded as a fault of `step`. One turn alone:
    /// a group of one.
    pub fn submit(&mut self, step: usize, agent: usize, mv: Move) -> Result<(), Violation> {
        let mut verdicts = self.submit_group(step, vec![(agent, mv)]);
        verdicts.pop().unwrap_or(Ok(()))
    }

    /// Check the moves of one group of turns (agents planned against the same snapshot
    /// and moving at once) and take those that hold; one verdict per move, in order.
    ///
    /// Each move is checked against every other body where it stands (the snapshot), its
    /// length against the agent's top speed, and its end against its best point (it may
    /// stop short only [`MoveStatus::UnderWay`]); then every pair of the moves that passed
    /// is checked against each other's whole move: two that come within their radii sum
    /// are both rejected.
    pub fn submit_group(
        &mut self,
        step: usize,
        moves: Vec<(usize, Move)>,
    ) -> Vec<Result<(), Violation>> {
        let mut verdicts: Vec<Result<(), Violation>> = moves
            .iter()
            .map(|(agent, mv)| self.check_alone(*agent, mv))
            .collect();
        // Every point of a move lies within its length of its start: far-apart pairs need
        // no polyline distance.
        let lengths_m: Vec<f64> = moves
            .iter()
            .map(|(_, mv)| polyline_length_m(&mv.waypoints))
            .collect();
        for i in 0..moves.len() {
            for j in 0..i {
                if verdicts[i].is_err() || verdicts[j].is_err() {
                    continue;
                }
                let ((a, ma), (b, mb)) = (&moves[i], &moves[j]);
                let reach_m = self.bodies[*a].radius_m + self.bodies[*b].radius_m;
                let start_gap_m = (self.bodies[*a].position - self.bodies[*b].position).norm();
                if start_gap_m > lengths_m[i] + lengths_m[j] + reach_m {
                    continue;
                }
                let distance_m = distance_polyline_polyline(&ma.waypoints, &mb.waypoints);
                if distance_m < reach_m - SAFETY_TOLERANCE_M {
                    verdicts[i] = Err(Violation::MeetsGroupMate {
                        agent: *b,
                        distance_m,
                        reach_m,
                    });
                    verdicts[j] = Err(Violation::MeetsGroupMate {
                        agent: *a,
                        distance_m,
                        reach_m,
                    });
                }
            }
        }
        for ((agent, mv), verdict) in moves.into_iter().zip(&verdicts) {
            match verdict {
                Ok(()) => {
                    self.bodies[agent].position = mv.end();
                    self.pending[agent] = Some(mv);
                }
                Err(v) => {
                    self.reject(step, agent, mv.slot, MoveStatus::Rejected, v.to_string());
                }
            }
        }
        verdicts
    }

    /// Check one move against the bodies where they stand, the field, the agent's top
    /// speed and its best point.
    fn check_alone(&self, agent: usize, mv: &Move) -> Result<(), Violation> {
        let body = self.bodies[agent];
        safety::check_move_of(
            &self.scenario.field,
            &self.obstacles,
            &self.bodies,
            agent,
            &body.position,
            &mv.waypoints,
            MAX_WAYPOINTS,
        )?;
        safety::check_move_against_moving(
            self.moving_now.disks(),
            body.radius_m,
            &body.position,
            &mv.waypoints,
        )?;
        if let Some(max_m) = self.scenario.agents[agent].max_step_m {
            let length_m = polyline_length_m(&mv.waypoints);
            if length_m > max_m + SAFETY_TOLERANCE_M {
                return Err(Violation::TooLong { length_m, max_m });
            }
        }
        // The last waypoint is where the agent ends up; it must be the best point, unless
        // the agent is under way to it.
        if mv.status != MoveStatus::UnderWay && mv.end() != mv.best {
            return Err(Violation::WrongEnd);
        }
        Ok(())
    }

    /// Record that `agent` did not move this step because its move was refused
    /// ([`MoveStatus::Rejected`]) or never came ([`MoveStatus::Missed`]): it stays where
    /// it was, and a fault named after the status is recorded.
    pub fn reject(
        &mut self,
        step: usize,
        agent: usize,
        slot: Point,
        status: MoveStatus,
        detail: String,
    ) {
        self.reject_as(step, agent, slot, status, status.name(), detail);
    }

    /// [`Self::reject`] recording a fault of `kind` (e.g. `malformed` for an answer that
    /// failed the checks before any geometry was looked at).
    pub fn reject_as(
        &mut self,
        step: usize,
        agent: usize,
        slot: Point,
        status: MoveStatus,
        kind: &str,
        detail: String,
    ) {
        let here = self.bodies[agent].position;
        self.pending[agent] = Some(Move {
            slot,
            best: here,
            status,
            waypoints: vec![here],
        });
        self.note_fault(step, agent, kind, detail, None);
    }

    /// Record a fault that does not change the agent's move (a kill, a respawn, a
    /// detected death).
    pub fn note_fault(
        &mut self,
        step: usize,
        agent: usize,
        kind: &str,
        detail: String,
        detection_ms: Option<f64>,
    ) {
        self.run.faults.push(Fault {
            agent,
            step,
            kind: kind.to_string(),
            detail,
            detection_ms,
        });
    }

    /// Take `agent` out of the formation because its process died: it stays as a static
    /// obstacle where it stands, and the death is recorded with how long it took to
    /// notice.
    pub fn freeze_dead(&mut self, step: usize, agent: usize, detail: String, detection_ms: f64) {
        self.freeze(step, agent, "dead", detail, Some(detection_ms));
    }

    /// Take `agent` out of the formation: it stays as a static obstacle where it stands,
    /// and a fault of `kind` is recorded (`dead`, `failed-to-start`, ...).
    pub fn freeze(
        &mut self,
        step: usize,
        agent: usize,
        kind: &str,
        detail: String,
        detection_ms: Option<f64>,
    ) {
        let here = self.bodies[agent].position;
        let centre = self
            .run
            .centre_path
            .get(step)
            .copied()
            .unwrap_or(self.scenario.path.start);
        self.pending[agent] = Some(Move {
            slot: self.scenario.agents[agent].slot.ideal_position(&centre),
            best: here,
            status: MoveStatus::Dead,
            waypoints: vec![here],
        });
        self.alive[agent] = false;
        self.note_fault(step, agent, kind, detail, detection_ms);
    }

    /// Put `agent` back into the formation (a replacement process took its place).
    pub fn mark_alive(&mut self, agent: usize) {
        self.alive[agent] = true;
    }

    /// Close step `step`: record every agent's row with its deviation and clearance.
    pub fn end_step(&mut self, step: usize) {
        let centre = self
            .run
            .centre_path
            .get(step)
            .copied()
            .unwrap_or(self.scenario.path.start);
        let reach_m = self
            .obstacles
            .max_radius_m()
            .max(self.moving_now.max_radius_m())
            + self.bodies.iter().map(|b| b.radius_m).fold(0.0, f64::max);
        let mut agents = Vec::with_capacity(self.bodies.len());
        for i in 0..self.bodies.len() {
            let body = self.bodies[i];
            let slot = self.scenario.agents[i].slot.ideal_position(&centre);
            let mv = self.pending[i].take().unwrap_or(Move {
                slot,
                best: body.position,
                status: if self.alive[i] {
                    MoveStatus::Stayed
                } else {
                    MoveStatus::Dead
                },
                waypoints: vec![body.position],
            });
            // Obstacles farther than the largest radii sum cannot be the nearest overlap;
            // look a little farther so clearance is reported for near misses too.
            let (to_static, to_other) =
                safety::clearances_of_m(&self.bodies, i, &self.obstacles, reach_m + 10.0);
            let to_obstacle = if self.scenario.moving.is_empty() {
                to_static
            } else {
                let (to_moving, _) =
                    safety::clearances_m(&body, &self.moving_now, &[], reach_m + 10.0);
                to_static.min(to_moving)
            };
            agents.push(AgentStep {
                position: body.position,
                slot,
                best: mv.best,
                deviation_m: (body.position - slot).norm(),
                clearance_m: to_obstacle.min(to_other),
                status: mv.status,
                alive: self.alive[i],
                waypoints: mv.waypoints,
            });
        }
        self.run.steps.push(Step {
            step,
            centre,
            agents,
            groups: std::mem::take(&mut self.groups),
            moving: self.moving.clone(),
            struck: std::mem::take(&mut self.struck),
        });
    }

    /// End the run; `completed` says whether it went through the whole path.
    pub fn finish(mut self, completed: bool) -> Run {
        self.run.completed = completed;
        self.run
    }

    /// Keep what the centre's course did in the record.
    pub fn note_course(&mut self, course: &Course) {
        self.run.course = CourseRecord::of(course);
    }

    /// The run so far, marked not completed (for a run stopped early).
    pub fn snapshot(&self) -> Run {
        let mut run = self.run.clone();
        run.completed = false;
        run
    }
}
