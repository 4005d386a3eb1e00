//! The project's own messages in `run.mcap` (JSON, one per message): a step, a fault, a
//! replanning, a wait, an obstacle found, a turn, each lossless, so that the record read
//! back from the log is the record the run kept, to the bit (`serde_json` writes every
//! `f64` in its shortest exact form and reads it back exactly).

use serde::{Deserialize, Serialize};
use shared::control::vocabulary::MoveStatus;
use shared::geometry::{Point, Pose};
use shared::run::record::{AgentStep, Fault, FaultKind, Step};
use shared::world::course::{Replan, ReplanReason, Wait, WaitReason};

/// A position, `[x_m, y_m]`.
pub type XyM = [f64; 2];

/// A pose, `[x_m, y_m, heading_rad]`.
pub type PoseM = [f64; 3];

fn xy(p: &Point) -> XyM {
    [p.x, p.y]
}

fn point(p: XyM) -> Point {
    Point::new(p[0], p[1])
}

fn pose_of(p: &Pose) -> PoseM {
    [p.x_m, p.y_m, p.heading_rad]
}

fn pose(p: PoseM) -> Pose {
    Pose::new(p[0], p[1], p[2])
}

/// The value of `all` called `name` (by `name_of`), or an error naming `what`.
fn by_name<T: Copy, const N: usize>(
    all: [T; N],
    name_of: impl Fn(T) -> &'static str,
    name: &str,
    what: &'static str,
) -> Result<T, RecordError> {
    all.into_iter()
        .find(|v| name_of(*v) == name)
        .ok_or_else(|| RecordError::UnknownName {
            what,
            name: name.to_string(),
        })
}

/// `/formation/step`: every agent at the end of one step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepMessage {
    /// The step.
    pub step: usize,
    /// The formation centre.
    pub centre: PoseM,
    /// Each agent, in agent order.
    pub agents: Vec<AgentMessage>,
    /// Groups of turns the step took.
    pub groups: usize,
    /// Each moving obstacle's position during the step's turns.
    pub moving: Vec<XyM>,
    /// `(moving obstacle, agent, distance in metres)` for each agent a moving obstacle
    /// came within reach of.
    pub struck: Vec<(usize, usize, f64)>,
}

/// One agent in a [`StepMessage`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AgentMessage {
    /// Where it stands.
    pub position: XyM,
    /// Its ideal slot.
    pub slot: XyM,
    /// Its best point.
    pub best: XyM,
    /// Distance to the slot, metres.
    pub deviation_m: f64,
    /// Clearance to the nearest other body, metres; `null` when there is none (infinite).
    pub clearance_m: Option<f64>,
    /// What it did (`at_slot`, `deviated`, ...).
    pub status: String,
    /// Whether it still belongs to the formation.
    pub alive: bool,
    /// The polyline it followed this step.
    pub waypoints: Vec<XyM>,
    /// Where it faces, radians, for an agent with a heading (absent for a holonomic one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heading_rad: Option<f64>,
}

/// Why a message of the log cannot be turned back into the record.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// A name no value of its kind has.
    #[error("unknown {what} `{name}`")]
    UnknownName {
        /// What kind of name (`move status`, ...).
        what: &'static str,
        /// The name.
        name: String,
    },
    /// A clearance that is neither a number nor null, or a null one that is not infinite.
    #[error("clearance of agent {agent}: {value}")]
    Clearance {
        /// The agent.
        agent: usize,
        /// What was there.
        value: String,
    },
}

impl StepMessage {
    /// The message of `step`.
    pub fn of(step: &Step) -> Self {
        Self {
            step: step.step,
            centre: pose_of(&step.centre),
            agents: step
                .agents
                .iter()
                .map(|a| AgentMessage {
                    position: xy(&a.position),
                    slot: xy(&a.slot),
                    best: xy(&a.best),
                    deviation_m: a.deviation_m,
                    clearance_m: a.clearance_m.is_finite().then_some(a.clearance_m),
                    status: a.status.name().to_string(),
                    alive: a.alive,
                    waypoints: a.waypoints.iter().map(xy).collect(),
                    heading_rad: a.heading_rad,
                })
                .collect(),
            groups: step.groups,
            moving: step.moving.iter().map(xy).collect(),
            struck: step.struck.clone(),
        }
    }

    /// The step this message records.
    pub fn to_step(&self) -> Result<Step, RecordError> {
        let agents = self
            .agents
            .iter()
            .map(|a| {
                let status = by_name(MoveStatus::ALL, |s| s.name(), &a.status, "move status")?;
                Ok(AgentStep {
                    position: point(a.position),
                    slot: point(a.slot),
                    best: point(a.best),
                    deviation_m: a.deviation_m,
                    clearance_m: a.clearance_m.unwrap_or(f64::INFINITY),
                    status,
                    alive: a.alive,
                    waypoints: a.waypoints.iter().copied().map(point).collect(),
                    heading_rad: a.heading_rad,
                })
            })
            .collect::<Result<Vec<_>, RecordError>>()?;
        Ok(Step {
            step: self.step,
            centre: pose(self.centre),
            agents,
            groups: self.groups,
            moving: self.moving.iter().copied().map(point).collect(),
            struck: self.struck.clone(),
        })
    }
}

/// `/formation/fault`: a fault, as the run recorded it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FaultMessage {
    /// The agent.
    pub agent: usize,
    /// The step.
    pub step: usize,
    /// What happened.
    pub kind: FaultKind,
    /// Details for people.
    pub detail: String,
    /// Time to detect it, milliseconds.
    pub detection_ms: Option<f64>,
}

impl FaultMessage {
    /// The message of `fault`.
    pub fn of(fault: &Fault) -> Self {
        Self {
            agent: fault.agent,
            step: fault.step,
            kind: fault.kind,
            detail: fault.detail.clone(),
            detection_ms: fault.detection_ms,
        }
    }

    /// The fault.
    pub fn to_fault(&self) -> Fault {
        Fault {
            agent: self.agent,
            step: self.step,
            kind: self.kind,
            detail: self.detail.clone(),
            detection_ms: self.detection_ms,
        }
    }
}

/// `/formation/replan`: a replanning of the centre's path, found or not.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReplanMessage {
    /// The step it was made at.
    pub step: usize,
    /// Why (`found-obstacle`, `moving-obstacle`).
    pub reason: String,
    /// Planning time, milliseconds.
    pub planning_ms: f64,
    /// Whether a path was found.
    pub found: bool,
    /// The new path (empty when none was found).
    pub path: Vec<PoseM>,
}

impl ReplanMessage {
    /// The message of `replan`.
    pub fn of(replan: &Replan) -> Self {
        Self {
            step: replan.step,
            reason: replan.reason.name().to_string(),
            planning_ms: replan.planning_ms,
            found: replan.found,
            path: replan.path.iter().map(pose_of).collect(),
        }
    }

    /// The replanning.
    pub fn to_replan(&self) -> Result<Replan, RecordError> {
        let reason = by_name(
            [ReplanReason::FoundObstacle, ReplanReason::MovingObstacle],
            ReplanReason::name,
            &self.reason,
            "replan reason",
        )?;
        Ok(Replan {
            step: self.step,
            reason,
            planning_ms: self.planning_ms,
            found: self.found,
            path: self.path.iter().copied().map(pose).collect(),
        })
    }
}

/// `/formation/wait`: a step the centre held its pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WaitMessage {
    /// The step.
    pub step: usize,
    /// Why (`lag`, `blocked`).
    pub reason: String,
}

impl WaitMessage {
    /// The message of `wait`.
    pub fn of(wait: &Wait) -> Self {
        Self {
            step: wait.step,
            reason: wait.reason.name().to_string(),
        }
    }

    /// The wait.
    pub fn to_wait(&self) -> Result<Wait, RecordError> {
        let reason = by_name(
            [WaitReason::Lag, WaitReason::Blocked],
            WaitReason::name,
            &self.reason,
            "wait reason",
        )?;
        Ok(Wait {
            step: self.step,
            reason,
        })
    }
}

/// `/formation/found`: an unknown obstacle became known.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FoundMessage {
    /// The obstacle (its index among `[[obstacles.unknown]]`).
    pub obstacle: usize,
    /// The step.
    pub step: usize,
}

/// One answered turn's timing (the log writes them a step at a time: `/formation/turns`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TurnMessage {
    /// The step.
    pub step: usize,
    /// The agent.
    pub agent: usize,
    /// From ringing the turn to holding the move, microseconds.
    pub latency_us: f64,
    /// The agent's own compute time, as it reported it, microseconds.
    pub compute_us: f64,
}

/// One answered turn in a [`TurnsMessage`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TurnTiming {
    /// The agent.
    pub agent: usize,
    /// From ringing the turn to holding the move, microseconds.
    pub latency_us: f64,
    /// The agent's own compute time, as it reported it, microseconds.
    pub compute_us: f64,
}

/// `/formation/turns`: every turn answered during a step, one message a step (one MCAP
/// record for hundreds of turns).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TurnsMessage {
    /// The step.
    pub step: usize,
    /// Its answered turns, in the order they were answered.
    pub turns: Vec<TurnTiming>,
}

impl TurnsMessage {
    /// The messages of `turns`: one per step they belong to, in order.
    pub fn of(turns: &[TurnMessage]) -> Vec<Self> {
        let mut messages: Vec<Self> = Vec::new();
        for t in turns {
            let timing = TurnTiming {
                agent: t.agent,
                latency_us: t.latency_us,
                compute_us: t.compute_us,
            };
            match messages.last_mut() {
                Some(m) if m.step == t.step => m.turns.push(timing),
                _ => messages.push(Self {
                    step: t.step,
                    turns: vec![timing],
                }),
            }
        }
        messages
    }

    /// Its turns, each with its step.
    pub fn to_turns(&self) -> impl Iterator<Item = TurnMessage> + '_ {
        self.turns.iter().map(|t| TurnMessage {
            step: self.step,
            agent: t.agent,
            latency_us: t.latency_us,
            compute_us: t.compute_us,
        })
    }
}

/// `/formation/plan`: the centre path planned before the run (plan 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanMessage {
    /// The poses, one per step.
    pub path: Vec<PoseM>,
}

impl PlanMessage {
    /// The message of `path`.
    pub fn of(path: &[Pose]) -> Self {
        Self {
            path: path.iter().map(pose_of).collect(),
        }
    }

    /// The path.
    pub fn to_path(&self) -> Vec<Pose> {
        self.path.iter().copied().map(pose).collect()
    }
}

/// `/formation/end`: the run ended (written last, before the summary section).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EndMessage {
    /// Whether the run went through the whole centre path.
    pub completed: bool,
    /// Whether the course gave up (no way through for too long).
    pub gave_up: bool,
}

/// The version of the log's format this program writes and resumes: a log of another
/// version is read for `render` as far as it can be, never resumed. 2: a scenario's
/// `[cbf] deadlock_escape` (a log of version 1 ran without it, which its scenario, read
/// now, would switch on).
pub const LOG_FORMAT_VERSION: u32 = 2;

/// `/formation/scenario`: the scenario as run, the format's version, and the run's
/// options that change what happens (so that `run --resume` goes on as the run would).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScenarioMessage {
    /// The scenario's resolved TOML.
    pub toml: String,
    /// The scenario file as it was given (absent: an older program's log).
    #[serde(default)]
    pub source: Option<String>,
    /// [`LOG_FORMAT_VERSION`] of the program that wrote the log (absent: an older one).
    #[serde(default)]
    pub format_version: Option<u32>,
    /// The run's options (absent: an older program's log).
    #[serde(default)]
    pub options: Option<LoggedOptions>,
}

/// The options of a run that change its record, as logged.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LoggedOptions {
    /// The turn deadline, milliseconds.
    pub turn_deadline_ms: u64,
    /// The slow bound, milliseconds, if one was set.
    pub slow_turn_ms: Option<u64>,
    /// Whether dead agents are replaced.
    pub respawn: bool,
    /// `(agent, step)`: SIGKILL right after the grant of that turn.
    pub kills: Vec<(usize, usize)>,
    /// `(agent, step)`: killed before its group's turns at that step.
    pub deaths: Vec<(usize, usize)>,
    /// `AGENT=MODE`: test-mode misbehaviour.
    pub misbehave: Vec<String>,
}
