//! Writing `run.mcap` ([`RunLogWriter`]): one chunk per step, closed and handed to the
//! file once the step is logged, synced to the disk about once a second by a thread of
//! its own (or every N steps), the summary section at the end. The run hands it its
//! steps through [`super::LogThread`].

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::Serialize;
use shared::geometry::{Point, Pose};
use shared::run::record::{Fault, Step};
use shared::world::course::{Course, Replan, Wait};
use shared::world::scenario::Scenario;

use super::foxglove;
use super::reader::LoggedRun;
use super::records::{
    EndMessage, FaultMessage, FoundMessage, LOG_FORMAT_VERSION, LoggedOptions, PlanMessage,
    ReplanMessage, ScenarioMessage, StepMessage, TurnMessage, TurnsMessage, WaitMessage,
};
use super::sync::BackgroundSync;
use super::{Topic, log_time_ns};

/// When the log is synced to the disk (`fsync`), besides at the end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SyncPolicy {
    /// At the end of a step when a second or more has passed since the last sync.
    EverySecond,
    /// At the end of every N-th step (`--sync-every-steps N`).
    EverySteps(u32),
}

/// Where and how a run writes its log.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogOptions {
    /// The file (`DIR/run.mcap`).
    pub path: PathBuf,
    /// The scenario file as given, named in the log's copy of the scenario.
    pub source: String,
    /// When it is synced to the disk.
    pub sync: SyncPolicy,
}

/// Why the log cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum RunLogError {
    /// The file cannot be created or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
    /// The MCAP writer refused a record.
    #[error("{}: {source}", path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// What it refused.
        source: mcap::McapError,
    },
    /// The log's thread stopped (it panicked, or an earlier error was reported).
    #[error("the run log's thread stopped")]
    Stopped,
    /// The scenario has no resolved form to keep in the log.
    #[error("the scenario as run: {0}")]
    Scenario(String),
}

/// What the centre's course has done so far, as the log takes it: from a [`Course`]
/// under way, or from a log read back.
#[derive(Clone, Copy, Debug)]
pub struct CourseSoFar<'a> {
    /// Every replanning so far.
    pub replans: &'a [Replan],
    /// Every wait so far.
    pub waits: &'a [Wait],
    /// For each unknown obstacle, the step it was found, if it was.
    pub found_at: &'a [Option<usize>],
}

impl<'a> CourseSoFar<'a> {
    /// What `course` has done so far.
    pub fn of(course: &'a Course<'_>) -> Self {
        Self {
            replans: course.replans(),
            waits: course.waits(),
            found_at: course.found_at(),
        }
    }
}

/// A run's log, open for writing.
pub struct RunLogWriter {
    path: PathBuf,
    writer: mcap::Writer<BufWriter<File>>,
    /// The same file, to sync.
    file: File,
    channels: BTreeMap<Topic, u16>,
    sequence: u32,
    sync: SyncPolicy,
    /// With [`SyncPolicy::EverySecond`], the thread that syncs.
    background: Option<BackgroundSync>,
    steps_since_sync: u32,
    scenario: Scenario,
    /// How much of each growing list is in the log already.
    faults: usize,
    replans: usize,
    waits: usize,
    found: Vec<bool>,
    /// The last step logged.
    last_step: usize,
    /// The slots last drawn in the scene, in the formation frame.
    slots_shown: Vec<Point>,
    /// Each message's JSON, written into this one buffer: a step's messages are tens of
    /// kilobytes, and allocating and freeing blocks that large every step made the
    /// allocator consolidate its free lists, most of the log thread's time (measured).
    json: Vec<u8>,
}

impl RunLogWriter {
    /// Create the log at `options.path` (a file there is replaced) and write what is known
    /// before the first step: the scenario as run, the options `run` that change its
    /// record, and the first centre plan.
    pub fn create(
        options: &LogOptions,
        scenario: &Scenario,
        first_plan: &[Pose],
        run: &LoggedOptions,
    ) -> Result<Self, RunLogError> {
        let toml = scenario
            .to_resolved_toml(&options.source)
            .map_err(|e| RunLogError::Scenario(e.to_string()))?;
        Self::create_at(
            options.path.clone(),
            options,
            scenario,
            toml,
            first_plan,
            run,
        )
    }

    /// The log of a run resumed from `logged` (the killed run's log at `options.path`): a
    /// new file beside it holding every step of `logged` as it was logged, then put in its
    /// place in one rename, so that a kill at any moment leaves a log with at least those
    /// steps. Goes on with the steps after them.
    pub fn create_resumed(
        options: &LogOptions,
        scenario: &Scenario,
        logged: &LoggedRun,
    ) -> Result<Self, RunLogError> {
        let mut part = options.path.clone().into_os_string();
        part.push(".resuming");
        let part = PathBuf::from(part);
        let run = logged.options.clone().unwrap_or_default();
        let toml = logged.scenario_toml.clone();
        let mut log = Self::create_at(
            part.clone(),
            options,
            scenario,
            toml,
            &logged.first_plan,
            &run,
        )?;
        let mut found_at = vec![None; scenario.unknown.len()];
        let mut turns_before = 0;
        for (step, marks) in logged.steps.iter().zip(&logged.marks) {
            for &(obstacle, at) in &logged.found[..marks.found] {
                if let Some(slot) = found_at.get_mut(obstacle) {
                    *slot = Some(at);
                }
            }
            let course = CourseSoFar {
                replans: &logged.replans[..marks.replans],
                waits: &logged.waits[..marks.waits],
                found_at: &found_at,
            };
            let turns = logged.turns[turns_before..marks.turns].iter().cloned();
            turns_before = marks.turns;
            log.log_step(step, &logged.faults[..marks.faults], Some(course), turns)?;
        }
        log.end_chunk(true)?;
        std::fs::rename(&part, &options.path).map_err(|source| RunLogError::Io {
            path: options.path.clone(),
            source,
        })?;
        log.path = options.path.clone();
        Ok(log)
    }

    fn create_at(
        path: PathBuf,
        options: &LogOptions,
        scenario: &Scenario,
        toml: String,
        first_plan: &[Pose],
        run: &LoggedOptions,
    ) -> Result<Self, RunLogError> {
        let io = |source| RunLogError::Io {
            path: path.clone(),
            source,
        };
        // Created new: a link at the name (`run.mcap.resuming` in a folder handed over) is
        // removed, never followed.
        let file = shared::output_file::create_new(&path).map_err(io)?;
        let sync_file = file.try_clone().map_err(io)?;
        let writer = mcap::WriteOptions::new()
            .profile("")
            .library(concat!("formation coordinator ", env!("CARGO_PKG_VERSION")))
            .compression(None)
            // Chunks are closed by hand, one a step.
            .chunk_size(None)
            .create(BufWriter::new(file))
            .map_err(|source| RunLogError::Mcap {
                path: path.clone(),
                source,
            })?;
        let mut log = Self {
            path,
            writer,
            file: sync_file,
            channels: BTreeMap::new(),
            sequence: 0,
            sync: options.sync,
            background: None,
            steps_since_sync: 0,
            scenario: scenario.clone(),
            faults: 0,
            replans: 0,
            waits: 0,
            found: vec![false; scenario.unknown.len()],
            last_step: 0,
            slots_shown: Vec::new(),
            json: Vec::new(),
        };
        for topic in Topic::ALL {
            let schema = topic.schema();
            let data = serde_json::to_vec(&schema).map_err(|e| RunLogError::Io {
                path: log.path.clone(),
                source: e.into(),
            })?;
            let schema_id = log
                .writer
                .add_schema(topic.schema_name(), "jsonschema", &data)
                .map_err(|source| log.mcap_error(source))?;
            let channel = log
                .writer
                .add_channel(schema_id, topic.name(), "json", &BTreeMap::new())
                .map_err(|source| log.mcap_error(source))?;
            log.channels.insert(topic, channel);
        }
        let message = ScenarioMessage {
            toml,
            source: Some(options.source.clone()),
            format_version: Some(LOG_FORMAT_VERSION),
            options: Some(run.clone()),
        };
        log.write(Topic::Scenario, 0, &message)?;
        log.write(Topic::Plan, 0, &PlanMessage::of(first_plan))?;
        log.write(
            Topic::CentrePlan,
            0,
            &foxglove::poses_in_frame(first_plan, 0),
        )?;
        log.end_chunk(true)?;
        if log.sync == SyncPolicy::EverySecond {
            let file = log.file.try_clone().map_err(|source| RunLogError::Io {
                path: log.path.clone(),
                source,
            })?;
            log.background = Some(BackgroundSync::start(file, Duration::from_secs(1)).map_err(
                |source| RunLogError::Io {
                    path: log.path.clone(),
                    source,
                },
            )?);
        }
        Ok(log)
    }

    fn mcap_error(&self, source: mcap::McapError) -> RunLogError {
        RunLogError::Mcap {
            path: self.path.clone(),
            source,
        }
    }

    fn write(
        &mut self,
        topic: Topic,
        step: usize,
        message: &impl Serialize,
    ) -> Result<(), RunLogError> {
        let mut json = std::mem::take(&mut self.json);
        json.clear();
        let written = serde_json::to_writer(&mut json, message).map_err(|e| RunLogError::Io {
            path: self.path.clone(),
            source: e.into(),
        });
        let result = written.and_then(|()| self.write_json(topic, step, &json));
        self.json = json;
        result
    }

    /// Write the message `data` (JSON) on `topic`, about `step`.
    fn write_json(&mut self, topic: Topic, step: usize, data: &[u8]) -> Result<(), RunLogError> {
        let header = mcap::records::MessageHeader {
            channel_id: self.channels[&topic],
            sequence: self.sequence,
            log_time: log_time_ns(step),
            publish_time: log_time_ns(step),
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.writer
            .write_to_known_channel(&header, data)
            .map_err(|source| self.mcap_error(source))
    }

    /// Close the chunk under way and hand it to the file; sync if `sync`.
    fn end_chunk(&mut self, sync: bool) -> Result<(), RunLogError> {
        self.writer
            .flush()
            .map_err(|source| self.mcap_error(source))?;
        if sync {
            self.file.sync_data().map_err(|source| RunLogError::Io {
                path: self.path.clone(),
                source,
            })?;
            self.steps_since_sync = 0;
        }
        Ok(())
    }

    /// Log the end of `step`, with what the run recorded since the last step: the faults
    /// (`faults`: every fault so far), the course's replans, waits and obstacles found,
    /// and the turns answered since the last step (`turns`). The step's chunk is closed and
    /// in the file when this returns.
    pub fn log_step(
        &mut self,
        step: &Step,
        faults: &[Fault],
        course: Option<CourseSoFar<'_>>,
        turns: impl IntoIterator<Item = TurnMessage>,
    ) -> Result<(), RunLogError> {
        let at = step.step;
        self.last_step = at;
        for fault in faults.iter().skip(self.faults) {
            self.write(Topic::Fault, at, &FaultMessage::of(fault))?;
        }
        self.faults = self.faults.max(faults.len());
        let found_before = self.found.iter().filter(|f| **f).count();
        if let Some(course) = course {
            for replan in course.replans.iter().skip(self.replans) {
                self.write(Topic::Replan, at, &ReplanMessage::of(replan))?;
                if replan.found {
                    self.write(
                        Topic::CentrePlan,
                        at,
                        &foxglove::poses_in_frame(&replan.path, log_time_ns(at)),
                    )?;
                }
            }
            self.replans = self.replans.max(course.replans.len());
            for wait in course.waits.iter().skip(self.waits) {
                self.write(Topic::Wait, at, &WaitMessage::of(wait))?;
            }
            self.waits = self.waits.max(course.waits.len());
            for (obstacle, found_at) in course.found_at.iter().enumerate() {
                if let (Some(found_step), Some(logged)) = (found_at, self.found.get(obstacle))
                    && !logged
                {
                    self.write(
                        Topic::Found,
                        at,
                        &FoundMessage {
                            obstacle,
                            step: *found_step,
                        },
                    )?;
                    self.found[obstacle] = true;
                }
            }
        }
        let turns: Vec<TurnMessage> = turns.into_iter().collect();
        for message in TurnsMessage::of(&turns) {
            self.write(Topic::Turn, at, &message)?;
        }
        self.write(Topic::Step, at, &StepMessage::of(step))?;
        let found_now = self.found.iter().filter(|f| **f).count();
        let with_obstacles = at == 0 || found_now != found_before;
        let slots = foxglove::slots_in_formation(step);
        let new_slots = (slots != self.slots_shown).then_some(slots.as_slice());
        let scene = foxglove::scene_update(
            &self.scenario,
            step,
            &self.found,
            with_obstacles,
            new_slots,
            log_time_ns(at),
        );
        if new_slots.is_some() {
            self.slots_shown = slots;
        }
        let mut json = std::mem::take(&mut self.json);
        json.clear();
        scene.write_json(&mut json);
        let written = self.write_json(Topic::Scene, at, &json);
        self.json = json;
        written?;
        self.write(
            Topic::Tf,
            at,
            &foxglove::frame_transform(&step.centre, log_time_ns(at)),
        )?;
        self.steps_since_sync += 1;
        let sync = match self.sync {
            SyncPolicy::EverySecond => false,
            SyncPolicy::EverySteps(n) => self.steps_since_sync >= n.max(1),
        };
        self.end_chunk(sync)?;
        if let Some(background) = &self.background {
            background.note_written();
        }
        Ok(())
    }

    /// End the log: the end message, the summary section, synced.
    pub fn finish(mut self, completed: bool, gave_up: bool) -> Result<PathBuf, RunLogError> {
        let end = EndMessage { completed, gave_up };
        // Stamped with the last step's time.
        self.write(Topic::End, self.last_step, &end)?;
        // The last sync is this one.
        self.background.take();
        self.writer
            .finish()
            .map_err(|source| self.mcap_error(source))?;
        // The summary section is written (and the buffer flushed) by `finish`; no chunk
        // may be closed after it.
        self.file.sync_data().map_err(|source| RunLogError::Io {
            path: self.path.clone(),
            source,
        })?;
        Ok(self.path)
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}
