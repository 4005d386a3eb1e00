//! The reference simulation: the paper's solution flow (Fig. 5) in one process.
//!
//! The formation centre follows the Hybrid A* path; at every step each agent in turn
//! plans its move while the others stand still ([`TurnController::plan`]), and the
//! move is checked against the safety invariant before it is taken. With parallel turns
//! the agents of one group ([`crate::world::groups::turn_groups_ordered`]) plan against the same
//! snapshot and their moves are taken together. The step itself is
//! [`crate::run::step_loop::run_steps`], which the multi-process run goes through too, its
//! moves coming from agent processes instead of the controllers here: the run
//! reproduces this trajectory to the bit.

use std::convert::Infallible;

use crate::control::turn::{TurnController, TurnRequest, Velocities};
use crate::control::vocabulary::CbfSettingsError;
use crate::geometry::Pose;
use crate::paths::hybrid_astar::{self, HybridAStarSettings, PlanError};
use crate::run::record::{Fault, FaultKind, Recorder, Run};
use crate::run::step_loop::{GroupMoves, GroupTurn, MoveSource, WorldChecksOnly, run_steps};
use crate::world::course::Course;
use crate::world::scenario::Scenario;

/// Plan the formation centre's path with Hybrid A* and resample it every `step_m`.
pub fn plan_centre_path(scenario: &Scenario) -> Result<Vec<Pose>, PlanError> {
    let p = &scenario.path;
    let settings =
        HybridAStarSettings::new(p.turning_radius_m, p.centre_clearance_m, p.allow_reverse);
    let (dense, _) = hybrid_astar::plan_among_polygons(
        &scenario.field,
        &scenario.obstacles,
        &scenario.polygons,
        &p.start,
        &p.goal,
        &settings,
    )?;
    Ok(hybrid_astar::resample(&dense, p.step_m))
}

/// One controller per agent, in agent order, of the scenario's kind. The scenario's
/// settings were validated for every agent, so this cannot fail on a loaded scenario.
pub fn agent_controllers(scenario: &Scenario) -> Result<Vec<TurnController>, CbfSettingsError> {
    // Agents plan around every real obstacle they sense, known to the centre or not.
    let obstacles = scenario.static_obstacles();
    scenario
        .agents
        .iter()
        .map(|a| {
            TurnController::new(&scenario.controller, scenario.field, &obstacles, a).map(|p| {
                p.with_moving(&scenario.moving, &obstacles)
                    .with_polygons(&scenario.polygons)
                    .with_map(scenario.map.as_ref())
                    .with_formation(&scenario.agents)
            })
        })
        .collect()
}

/// Why the reference simulation could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimulateError {
    /// The formation centre has no path.
    #[error("centre path: {0}")]
    Path(#[from] PlanError),
    /// The barrier-function settings do not suit an agent.
    #[error("controller settings: {0}")]
    Controller(#[from] CbfSettingsError),
}

/// Plan the centre path and run the whole scenario.
///
/// ```
/// use shared::world::scenario::Scenario;
/// use shared::run::simulate::simulate;
/// // The paper's example (section III): six agents through the obstacle field.
/// let run = simulate(&Scenario::paper()).unwrap();
/// let summary = run.summary();
/// assert_eq!(summary.agents, 6);
/// assert!(summary.completed);
/// assert_eq!(summary.collisions, 0);
/// assert!(summary.max_deviation_m > 0.0, "the obstacles disturb the formation");
/// assert!(summary.final_mean_deviation_m < 0.05, "and it recovers");
/// ```
pub fn simulate(scenario: &Scenario) -> Result<Run, SimulateError> {
    let path = plan_centre_path(scenario)?;
    simulate_along(scenario, &path)
}

/// Run the scenario starting along a given centre path (one pose per step); in a
/// changing world the centre's [`Course`] may leave it.
pub fn simulate_along(scenario: &Scenario, centre_path: &[Pose]) -> Result<Run, SimulateError> {
    simulate_along_with_deaths(scenario, centre_path, &[])
}

/// [`simulate_along`] where, for every `(agent, step)` of `deaths`, the agent dies at that
/// step just before its group's turns (after the groups of the step are formed, with it
/// still alive): it takes no turn, is frozen as an obstacle where it stands and leaves the
/// formation ([`Recorder::freeze`]), recorded as the faults `killed` then `dead` of that
/// step; its group mates still take their turns, planned against the same snapshot. A
/// death of an agent already dead, or at a step without a turn, changes nothing.
///
/// This is what the coordinator does with `FaultInjection::deaths` (the agent's process is
/// killed before its group's turns are granted, so the death is always detected during
/// its turn): the multi-process run equals this one to the bit, faults aside from their
/// detail and detection time.
///
/// ```
/// use shared::world::scenario::Scenario;
/// use shared::run::simulate::{plan_centre_path, simulate_along_with_deaths};
/// let scenario = Scenario::paper();
/// let path = plan_centre_path(&scenario).unwrap();
/// let run = simulate_along_with_deaths(&scenario, &path, &[(2, 40)]).unwrap();
/// let kinds: Vec<(usize, usize, &str)> =
///     run.faults.iter().map(|f| (f.agent, f.step, f.kind.name())).collect();
/// assert_eq!(kinds, [(2, 40, "killed"), (2, 40, "dead")]);
/// assert!(run.steps[40..].iter().all(|s| !s.agents[2].alive));
/// assert!(run.steps[..40].iter().all(|s| s.agents[2].alive));
/// assert_eq!(run.summary().collisions, 0);
/// ```
pub fn simulate_along_with_deaths(
    scenario: &Scenario,
    centre_path: &[Pose],
    deaths: &[(usize, usize)],
) -> Result<Run, SimulateError> {
    let mut planners = InProcess {
        controllers: agent_controllers(scenario)?,
        deaths,
    };
    let mut course = Course::new(scenario, centre_path);
    let mut recorder = Recorder::new(scenario, course.pose());
    let Ok(_) = run_steps(
        &mut course,
        &mut recorder,
        0,
        &mut planners,
        &mut WorldChecksOnly,
    );
    Ok(recorder.finish(!course.gave_up()))
}

/// The moves of the reference simulation: every agent's controller in this process, and
/// the deaths injected (`(agent, step)`).
struct InProcess<'d> {
    /// One controller per agent, in agent order.
    controllers: Vec<TurnController>,
    /// The agents that die, and when: just before their group's turns.
    deaths: &'d [(usize, usize)],
}

impl MoveSource for InProcess<'_> {
    type Error = Infallible;

    fn take_group(
        &mut self,
        turn: &GroupTurn<'_>,
        recorder: &mut Recorder<'_>,
    ) -> Result<GroupMoves, Infallible> {
        let step = turn.step;
        for &agent in turn.agents() {
            if self.deaths.contains(&(agent, step)) {
                recorder.note_fault(
                    step,
                    agent,
                    FaultKind::Killed,
                    "fault injection: killed before its group's turns".to_string(),
                    None,
                );
                recorder.freeze(Fault {
                    agent,
                    step,
                    kind: FaultKind::Dead,
                    detail: "the agent process died during its turn".to_string(),
                    detection_ms: None,
                });
            }
        }
        // Every agent of the group plans against the same snapshot.
        let moves = turn
            .agents()
            .iter()
            .filter(|&&agent| recorder.world().alive()[agent])
            .map(|&agent| {
                let others = recorder.world().others(agent);
                let mates = self.controllers[agent].mate_views(agent, recorder.world().views());
                let velocities = turn.velocities.map(|all| Velocities::of_agent(all, agent));
                let mv = self.controllers[agent].plan(&TurnRequest {
                    step,
                    centre: *turn.centre,
                    ahead: turn.ahead,
                    me: recorder.world().bodies()[agent].position,
                    heading_rad: recorder.world().headings()[agent],
                    others: &others,
                    mates: &mates,
                    velocities: velocities.as_ref(),
                });
                (agent, mv)
            })
            .collect();
        Ok(GroupMoves::Taken(moves))
    }
}
