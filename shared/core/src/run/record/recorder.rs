//! The referee and the record of a run: which moves the safety invariant lets through
//! into the world ([`World`]), and the record of what happened so far.

use super::{AgentStep, CourseRecord, Fault, FaultKind, Run, Step};
use crate::control::safety::{self, SAFETY_TOLERANCE_M, Violation};
use crate::control::vocabulary::{Move, MoveStatus, TurnMode};
use crate::geometry::{
    DiskGrid, Point, Pose, distance_at_the_same_time_m, distance_polyline_polyline,
};
use crate::run::turn_world::World;
use crate::world::course::Course;
use crate::world::groups::{GroupMove, group_meetings, simultaneous_meetings};
use crate::world::scenario::Scenario;

mod check;

/// The referee of a run and its record: it owns the [`World`] every turn reads, moves an
/// agent only by a move that keeps the safety invariant, and records every step and fault.
#[derive(Debug)]
pub struct Recorder<'a> {
    scenario: &'a Scenario,
    /// The world every turn reads.
    world: World<'a>,
    /// Every static obstacle, known to the centre or not, with its true radius, for the
    /// safety check and clearances.
    obstacles: DiskGrid,
    /// The moving obstacles where they stand now, true radii.
    moving_now: DiskGrid,
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
        let world = World::new(scenario, start);
        let n = scenario.agents.len();
        let mut recorder = Self {
            scenario,
            obstacles: DiskGrid::new(scenario.static_obstacles()),
            moving_now: Self::moving_at(scenario, 0),
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
            world,
        };
        for (i, b) in recorder.world.bodies().iter().enumerate() {
            recorder.pending[i] = Some(Move {
                end_heading_rad: None,
                slot: b.position,
                best: b.position,
                status: MoveStatus::AtSlot,
                waypoints: vec![b.position],
            });
        }
        recorder.end_step(0);
        recorder
    }

    /// Go on with a run of `scenario` whose record so far is `run` (a killed run's, read
    /// back from its log): every agent where the last step left it, alive or not as it
    /// was, every moving obstacle where it stood; the next step is the one after the
    /// last. `None` when `run` has no step, or its last step does not fit the scenario
    /// (another number of agents or moving obstacles).
    pub fn resume(scenario: &'a Scenario, run: Run) -> Option<Self> {
        let last = run.steps.last()?;
        if last.agents.len() != scenario.agents.len() || last.moving.len() != scenario.moving.len()
        {
            return None;
        }
        let from = run.steps.len().saturating_sub(2);
        let world = World::resumed(
            scenario,
            last.bodies(scenario),
            last.agents.iter().map(|a| a.heading_rad).collect(),
            last.agents.iter().map(|a| a.alive).collect(),
            last.moving.clone(),
            run.steps[from..]
                .iter()
                .map(|s| s.agents.iter().map(|a| a.position).collect())
                .collect(),
        );
        let last = last.step;
        Some(Self {
            scenario,
            obstacles: DiskGrid::new(scenario.static_obstacles()),
            moving_now: Self::moving_at(scenario, last),
            pending: vec![None; scenario.agents.len()],
            groups: 0,
            run: Run {
                centre_path: run.steps.iter().map(|s| s.centre).collect(),
                completed: false,
                ..run
            },
            world,
        })
    }

    /// The world every turn reads.
    pub fn world(&self) -> &World<'a> {
        &self.world
    }

    /// The scenario being run.
    pub fn scenario(&self) -> &'a Scenario {
        self.scenario
    }

    /// Every moving obstacle where it stands at `step`.
    fn moving_at(scenario: &Scenario, step: usize) -> DiskGrid {
        DiskGrid::new(scenario.moving.iter().map(|m| m.disk_at(step)).collect())
    }

    /// Open step `step` (from 1) with the centre at `centre`: every moving obstacle
    /// drives to where it stands at `step` while the agents stand still, and any live
    /// agent its motion comes within reach of is recorded as struck (in the step, and as
    /// a fault `struck`; see [`crate::world::moving_obstacle`]). Call before any turn or fault
    /// of the step.
    pub fn begin_step(&mut self, step: usize, centre: Pose) {
        self.run.centre_path.push(centre);
        if self.scenario.moving.is_empty() {
            return;
        }
        let mut struck = Vec::new();
        for (m, obstacle) in self.scenario.moving.iter().enumerate() {
            let sweep = obstacle.sweep(step);
            for (a, body) in self.world.bodies().iter().enumerate() {
                if !self.world.alive()[a] {
                    continue;
                }
                let reach_m = obstacle.radius_m + body.radius_m;
                let distance_m = distance_polyline_polyline(&sweep, &[body.position]);
                if distance_m < reach_m - SAFETY_TOLERANCE_M {
                    struck.push((m, a, distance_m));
                    self.run.faults.push(Fault {
                        agent: a,
                        step,
                        kind: FaultKind::Struck,
                        detail: format!(
                            "moving obstacle {m}'s motion came {distance_m} m from the agent, within their radii sum {reach_m} m"
                        ),
                        detection_ms: None,
                    });
                }
            }
        }
        for (m, a, distance_m) in struck {
            self.world.note_strike(m, a, distance_m);
        }
        for (m, obstacle) in self.scenario.moving.iter().enumerate() {
            self.world.place_moving(m, obstacle.position_at(step));
        }
        self.moving_now = Self::moving_at(self.scenario, step);
    }

    /// The steps recorded so far.
    pub fn steps(&self) -> &[Step] {
        &self.run.steps
    }

    /// The faults recorded so far, in order.
    pub fn faults(&self) -> &[Fault] {
        &self.run.faults
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
    ///
    /// In [`TurnMode::Simultaneous`], where every agent moves at once at a constant speed
    /// along its move, a move is checked alone against the bodies that are not in the
    /// group (they stand), and against the group's moves in time: of two that come within
    /// their radii sum at the same time, the one whose agent, standing, lets the other
    /// pass is rejected (both if neither does), and so is a move that comes within reach
    /// of a mate whose move was rejected (it stands), until none does
    /// ([`simultaneous_meetings`]).
    pub fn submit_group(
        &mut self,
        step: usize,
        moves: Vec<(usize, Move)>,
    ) -> Vec<Result<(), Violation>> {
        // At once at constant speeds (ORCA's own model), the group's moves are checked
        // against each other in time, and each alone against the bodies that stand; a
        // parallel group's timing is not known: against the others where they stand,
        // then against each other anywhere.
        let simultaneous = self.scenario.turns == TurnMode::Simultaneous;
        let mut passing = Vec::new();
        if simultaneous {
            passing = vec![false; self.world.bodies().len()];
            for (agent, _) in &moves {
                passing[*agent] = true;
            }
        }
        // Each move against the bodies near it, found with a grid over them, when there
        // are enough moves to pay for building it (the verdicts are the same).
        let grid = (moves.len() > 1).then(|| safety::bodies_grid(self.world.bodies()));
        let others = safety::Others {
            bodies: self.world.bodies(),
            passing: &passing,
            grid: grid.as_ref(),
        };
        let mut verdicts: Vec<Result<(), Violation>> = moves
            .iter()
            .map(|(agent, mv)| self.check_alone(*agent, mv, &others))
            .collect();
        // A move refused on its own leaves its agent where it stands.
        let starts: Vec<[Point; 1]> = moves
            .iter()
            .map(|(agent, _)| [self.world.bodies()[*agent].position])
            .collect();
        let group: Vec<GroupMove<'_>> = moves
            .iter()
            .zip(&verdicts)
            .zip(&starts)
            .map(|(((agent, mv), verdict), start)| GroupMove {
                radius_m: self.world.bodies()[*agent].radius_m,
                waypoints: if simultaneous && verdict.is_err() {
                    start
                } else {
                    &mv.waypoints
                },
                refused: verdict.is_err(),
            })
            .collect();
        let meetings = if simultaneous {
            simultaneous_meetings(&group, distance_at_the_same_time_m)
        } else {
            group_meetings(&group, distance_polyline_polyline)
        };
        for (verdict, meeting) in verdicts.iter_mut().zip(meetings) {
            if let Some(m) = meeting {
                *verdict = Err(Violation::MeetsGroupMate {
                    agent: moves[m.mate].0,
                    distance_m: m.distance_m,
                    reach_m: m.reach_m,
                });
            }
        }
        for ((agent, mv), verdict) in moves.into_iter().zip(&verdicts) {
            match verdict {
                Ok(()) => {
                    self.world.take_move(agent, &mv);
                    self.pending[agent] = Some(mv);
                }
                Err(v) => {
                    self.refuse(step, agent, mv.slot, FaultKind::Rejected, v.to_string());
                }
            }
        }
        verdicts
    }

    /// Record that `agent` did not move this step: its answer was refused (`kind`
    /// [`FaultKind::Rejected`] by the safety checks, [`FaultKind::Malformed`] before any
    /// geometry was looked at; status [`MoveStatus::Rejected`]) or never came
    /// ([`FaultKind::Missed`]; status [`MoveStatus::Missed`]). It stays where it was, and
    /// the fault is recorded.
    pub fn refuse(
        &mut self,
        step: usize,
        agent: usize,
        slot: Point,
        kind: FaultKind,
        detail: String,
    ) {
        let status = if kind == FaultKind::Missed {
            MoveStatus::Missed
        } else {
            MoveStatus::Rejected
        };
        let here = self.world.bodies()[agent].position;
        self.pending[agent] = Some(Move {
            end_heading_rad: None,
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
        kind: FaultKind,
        detail: String,
        detection_ms: Option<f64>,
    ) {
        self.run.faults.push(Fault {
            agent,
            step,
            kind,
            detail,
            detection_ms,
        });
    }

    /// Take `agent` out of the formation because its process died: it stays as a static
    /// obstacle where it stands, and the death is recorded with how long it took to
    /// notice.
    pub fn freeze_dead(&mut self, step: usize, agent: usize, detail: String, detection_ms: f64) {
        self.freeze(Fault {
            agent,
            step,
            kind: FaultKind::Dead,
            detail,
            detection_ms: Some(detection_ms),
        });
    }

    /// Take the fault's agent out of the formation: it stays as a static obstacle where it
    /// stands, and the fault is recorded ([`FaultKind::Dead`],
    /// [`FaultKind::FailedToStart`], ...).
    pub fn freeze(&mut self, fault: Fault) {
        let (step, agent) = (fault.step, fault.agent);
        let here = self.world.bodies()[agent].position;
        let centre = self
            .run
            .centre_path
            .get(step)
            .copied()
            .unwrap_or(self.scenario.path.start);
        self.pending[agent] = Some(Move {
            end_heading_rad: None,
            slot: self.scenario.agents[agent].slot.ideal_position(&centre),
            best: here,
            status: MoveStatus::Dead,
            waypoints: vec![here],
        });
        self.world.set_alive(agent, false);
        self.run.faults.push(fault);
    }

    /// Put `agent` back into the formation (a replacement process took its place).
    pub fn mark_alive(&mut self, agent: usize) {
        self.world.set_alive(agent, true);
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
            + self
                .world
                .bodies()
                .iter()
                .map(|b| b.radius_m)
                .fold(0.0, f64::max);
        let mut agents = Vec::with_capacity(self.world.bodies().len());
        let grid = safety::bodies_grid(self.world.bodies());
        for i in 0..self.world.bodies().len() {
            let body = self.world.bodies()[i];
            let slot = self.scenario.agents[i].slot.ideal_position(&centre);
            let mv = self.pending[i].take().unwrap_or(Move {
                end_heading_rad: None,
                slot,
                best: body.position,
                status: if self.world.alive()[i] {
                    MoveStatus::Stayed
                } else {
                    MoveStatus::Dead
                },
                waypoints: vec![body.position],
            });
            // Obstacles farther than the largest radii sum cannot be the nearest overlap;
            // look a little farther so clearance is reported for near misses too.
            let (to_static, _) = safety::clearances_m(&body, &self.obstacles, &[], reach_m + 10.0);
            let to_other = safety::clearance_to_others_m(self.world.bodies(), i, &grid);
            let to_static = to_static.min(safety::clearance_to_polygons_m(
                &body,
                &self.scenario.polygons,
            ));
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
                alive: self.world.alive()[i],
                waypoints: mv.waypoints,
                heading_rad: self.world.headings()[i],
            });
        }
        self.run.steps.push(Step {
            step,
            centre,
            agents,
            groups: std::mem::take(&mut self.groups),
            moving: self.world.moving_positions().to_vec(),
            struck: self.world.end_step(),
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
