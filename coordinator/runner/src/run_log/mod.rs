//! `run.mcap`: the run's log, written as the run goes, and the record every other output
//! is made from (`docs/outputs.md#runmcap`).
//!
//! An [MCAP](https://mcap.dev) file: one chunk per step (uncompressed, with its CRC),
//! written by a thread of its own while the next step goes on ([`LogThread`]), which
//! tells each step done once it is in the file; synced to the disk about once a second
//! (or every N steps) and at the end; the summary section at the end. A run killed at
//! any moment leaves every step reported done: a reader drops the last chunk if it is
//! incomplete, and never reads part of one ([`read_run_log`]).
//!
//! Every message is JSON with a JSON schema. Times are step-based: a message about step
//! `k` has log time `k` seconds ([`log_time_ns`]). Channels ([`Topic`]):
//! - Foxglove's well-known schemas, so the file opens in Foxglove as a scene: `/scene`
//!   (`foxglove.SceneUpdate`), `/centre/plan` (`foxglove.PosesInFrame`), `/tf`
//!   (`foxglove.FrameTransform`);
//! - the project's own, lossless: `/formation/scenario` (the scenario as run, its
//!   resolved TOML), `/formation/plan` (the first centre plan), `/formation/step` (every
//!   agent at the end of a step, each move's exact waypoints), `/formation/fault`,
//!   `/formation/replan`, `/formation/wait`, `/formation/found`, `/formation/turns` (each
//!   answered turn's latency and compute, a step at a time), `/formation/end` (the run
//!   ended).
//!
//! One concept per file: the own messages in `records`, Foxglove's in `foxglove`, the
//! writer in `writer` (its thread in `thread`, its syncing in `sync`), the reader in
//! `reader`.

mod foxglove;
mod reader;
mod records;
mod sync;
mod thread;
mod writer;

pub use reader::{LoggedRun, MAX_RUN_LOG_BYTES, ReadLogError, StepMarks, read_run_log};
pub use records::{LOG_FORMAT_VERSION, LoggedOptions, StepMessage, TurnMessage};
pub use thread::LogThread;
pub use writer::{CourseSoFar, LogOptions, RunLogError, RunLogWriter, SyncPolicy};

use serde_json::{Value, json};

/// The log's file name in a run folder.
pub const RUN_LOG_FILE: &str = "run.mcap";

/// The log time of step `step`: `step` seconds, in nanoseconds.
pub fn log_time_ns(step: usize) -> u64 {
    (step as u64).saturating_mul(1_000_000_000)
}

/// A channel of the log.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Topic {
    /// `/formation/scenario`: the scenario as run.
    Scenario,
    /// `/formation/plan`: the centre path planned before the run.
    Plan,
    /// `/formation/step`: every agent at the end of a step.
    Step,
    /// `/formation/fault`: a fault.
    Fault,
    /// `/formation/replan`: a replanning of the centre path.
    Replan,
    /// `/formation/wait`: a step the centre held.
    Wait,
    /// `/formation/found`: an unknown obstacle became known.
    Found,
    /// `/formation/turns`: the timing of every turn answered in a step.
    Turn,
    /// `/formation/end`: the run ended.
    End,
    /// `/scene`: the scene (`foxglove.SceneUpdate`).
    Scene,
    /// `/centre/plan`: the centre's plan and each replan (`foxglove.PosesInFrame`).
    CentrePlan,
    /// `/tf`: the formation frame (`foxglove.FrameTransform`).
    Tf,
}

impl Topic {
    /// Every channel, in the order they are added.
    pub const ALL: [Topic; 12] = [
        Self::Scenario,
        Self::Plan,
        Self::Step,
        Self::Fault,
        Self::Replan,
        Self::Wait,
        Self::Found,
        Self::Turn,
        Self::End,
        Self::Scene,
        Self::CentrePlan,
        Self::Tf,
    ];

    /// The channel's topic.
    pub fn name(self) -> &'static str {
        match self {
            Self::Scenario => "/formation/scenario",
            Self::Plan => "/formation/plan",
            Self::Step => "/formation/step",
            Self::Fault => "/formation/fault",
            Self::Replan => "/formation/replan",
            Self::Wait => "/formation/wait",
            Self::Found => "/formation/found",
            Self::Turn => "/formation/turns",
            Self::End => "/formation/end",
            Self::Scene => "/scene",
            Self::CentrePlan => "/centre/plan",
            Self::Tf => "/tf",
        }
    }

    /// The topic called `name`, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Its schema's name.
    pub fn schema_name(self) -> &'static str {
        match self {
            Self::Scenario => "formation.Scenario",
            Self::Plan => "formation.Plan",
            Self::Step => "formation.Step",
            Self::Fault => "formation.Fault",
            Self::Replan => "formation.Replan",
            Self::Wait => "formation.Wait",
            Self::Found => "formation.Found",
            Self::Turn => "formation.Turns",
            Self::End => "formation.End",
            Self::Scene => "foxglove.SceneUpdate",
            Self::CentrePlan => "foxglove.PosesInFrame",
            Self::Tf => "foxglove.FrameTransform",
        }
    }

    /// Its JSON schema (the project's own channels: an object with the keys it always has).
    pub fn schema(self) -> Value {
        let own = |keys: &[&str]| json!({"title": self.schema_name(), "type": "object", "required": keys});
        match self {
            Self::Scenario => own(&["toml", "source", "format_version", "options"]),
            Self::Plan => own(&["path"]),
            Self::Step => own(&["step", "centre", "agents", "groups", "moving", "struck"]),
            Self::Fault => own(&["agent", "step", "kind", "detail"]),
            Self::Replan => own(&["step", "reason", "planning_ms", "found", "path"]),
            Self::Wait => own(&["step", "reason"]),
            Self::Found => own(&["obstacle", "step"]),
            Self::Turn => own(&["step", "turns"]),
            Self::End => own(&["completed", "gave_up"]),
            Self::Scene => foxglove::scene_update_schema(),
            Self::CentrePlan => foxglove::poses_in_frame_schema(),
            Self::Tf => foxglove::frame_transform_schema(),
        }
    }
}
