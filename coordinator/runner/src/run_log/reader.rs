//! Reading `run.mcap` back ([`read_run_log`]): every complete chunk, each checked against
//! its CRC before any of its messages is used; a last chunk cut short (the run was
//! killed while writing it) is dropped whole.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mcap::read::{ChunkReader, LinearReader, Options};
use mcap::records::Record;
use shared::geometry::Pose;
use shared::input_file::{Links, ReadInputError, read_input};
use shared::run::record::{CourseRecord, Fault, Run, Step};
use shared::world::course::{Replan, Wait};
use shared::world::scenario::MAX_SCENARIO_BYTES;

use super::Topic;
use super::records::{
    EndMessage, FaultMessage, FoundMessage, LoggedOptions, PlanMessage, RecordError, ReplanMessage,
    ScenarioMessage, StepMessage, TurnMessage, TurnsMessage, WaitMessage,
};

/// What a run's log holds, read back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoggedRun {
    /// The scenario as run (its resolved TOML).
    pub scenario_toml: String,
    /// The scenario file as the run was given it.
    pub source: Option<String>,
    /// The version of the format the log was written in (`None`: an older program's).
    pub format_version: Option<u32>,
    /// The run's options that change its record (`None`: an older program's log).
    pub options: Option<LoggedOptions>,
    /// The centre path planned before the run.
    pub first_plan: Vec<Pose>,
    /// Every step logged, from step 0, in order.
    pub steps: Vec<Step>,
    /// Every fault, in order.
    pub faults: Vec<Fault>,
    /// Every replanning.
    pub replans: Vec<Replan>,
    /// Every wait.
    pub waits: Vec<Wait>,
    /// `(obstacle, step)` for each unknown obstacle found.
    pub found: Vec<(usize, usize)>,
    /// Every answered turn's timing.
    pub turns: Vec<TurnMessage>,
    /// How the run ended; `None` when it was killed (or is still under way).
    pub end: Option<EndMessage>,
    /// Whether an incomplete last chunk was dropped.
    pub truncated: bool,
    /// For each step, how much of each list was logged up to and with it: the log of a
    /// resumed run is written again chunk for chunk from these.
    pub marks: Vec<StepMarks>,
}

/// How many faults, replans, waits, obstacles found and turns a log holds up to and with
/// a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepMarks {
    /// Faults.
    pub faults: usize,
    /// Replannings.
    pub replans: usize,
    /// Waits.
    pub waits: usize,
    /// Obstacles found.
    pub found: usize,
    /// Turns.
    pub turns: usize,
}

/// The largest log read back (`render`, `run --resume`), in bytes: a run of a thousand
/// agents over a few thousand steps logs far less; a larger file is refused before it is
/// read, whatever its length on disk (a sparse file, a device).
pub const MAX_RUN_LOG_BYTES: u64 = 1 << 30;

/// Why a log cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadLogError {
    /// The file cannot be read: missing, not a regular file, a symbolic link, too large.
    #[error("{}: {reason}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: ReadInputError,
    },
    /// The file is not an MCAP file at all.
    #[error("{}: not an MCAP file (no magic bytes at the start)", .0.display())]
    NotMcap(PathBuf),
    /// A complete chunk whose bytes do not match its CRC.
    #[error("{}: the chunk at byte {offset} is corrupted (CRC {found:08x}, expected {expected:08x})", path.display())]
    BadCrc {
        /// The file.
        path: PathBuf,
        /// Where the chunk's data starts in the file (approximately: the record).
        offset: usize,
        /// The CRC of the bytes.
        found: u32,
        /// The CRC the chunk names.
        expected: u32,
    },
    /// A chunk compressed (this program writes none).
    #[error("{}: a chunk compressed with `{compression}` (this program writes uncompressed chunks)", path.display())]
    Compressed {
        /// The file.
        path: PathBuf,
        /// The compression.
        compression: String,
    },
    /// A record or message that is not what this program writes.
    #[error("{}: {what}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

/// Read the log at `path`: every message of every complete chunk, the last chunk dropped
/// if it was cut short.
///
/// The file is read only if it is a regular file (not a symbolic link: the folder may be
/// someone else's) of at most [`MAX_RUN_LOG_BYTES`].
pub fn read_run_log(path: &Path) -> Result<LoggedRun, ReadLogError> {
    let bytes = read_input(path, MAX_RUN_LOG_BYTES, Links::Refuse).map_err(|reason| {
        ReadLogError::Unreadable {
            path: path.to_path_buf(),
            reason,
        }
    })?;
    if !bytes.starts_with(mcap::MAGIC) {
        return Err(ReadLogError::NotMcap(path.to_path_buf()));
    }
    let malformed = |what: String| ReadLogError::Malformed {
        path: path.to_path_buf(),
        what,
    };
    let mut log = LoggedRun::default();
    let mut channels: BTreeMap<u16, Topic> = BTreeMap::new();
    let reader = LinearReader::new_with_options(&bytes, Options::IgnoreEndMagic.into())
        .map_err(|e| malformed(e.to_string()))?;
    let mut offset = mcap::MAGIC.len();
    for record in reader {
        let record = match record {
            Ok(record) => record,
            // Cut short: what follows the last complete record is dropped.
            Err(_) => {
                log.truncated = true;
                break;
            }
        };
        match record {
            Record::Channel(channel) => note_channel(&mut channels, &channel)?,
            Record::Chunk { header, data } => {
                if !header.compression.is_empty() {
                    return Err(ReadLogError::Compressed {
                        path: path.to_path_buf(),
                        compression: header.compression.clone(),
                    });
                }
                let found = crc32fast::hash(&data);
                if header.uncompressed_crc != 0 && found != header.uncompressed_crc {
                    return Err(ReadLogError::BadCrc {
                        path: path.to_path_buf(),
                        offset,
                        found,
                        expected: header.uncompressed_crc,
                    });
                }
                offset += data.len();
                let inner =
                    ChunkReader::new(header, &data).map_err(|e| malformed(e.to_string()))?;
                for record in inner {
                    match record.map_err(|e| malformed(e.to_string()))? {
                        Record::Channel(channel) => note_channel(&mut channels, &channel)?,
                        Record::Message { header, data } => {
                            let topic =
                                channels.get(&header.channel_id).copied().ok_or_else(|| {
                                    malformed(format!(
                                        "a message on unknown channel {}",
                                        header.channel_id
                                    ))
                                })?;
                            take_message(&mut log, topic, &data).map_err(&malformed)?;
                        }
                        _ => {}
                    }
                }
            }
            _ => {}
        }
    }
    for (i, step) in log.steps.iter().enumerate() {
        if step.step != i {
            return Err(malformed(format!(
                "step {} logged where step {i} was expected",
                step.step
            )));
        }
    }
    Ok(log)
}

fn note_channel(
    channels: &mut BTreeMap<u16, Topic>,
    channel: &mcap::records::Channel,
) -> Result<(), ReadLogError> {
    // A channel of another program's is ignored: its messages are then refused.
    if let Some(topic) = Topic::from_name(&channel.topic) {
        channels.insert(channel.id, topic);
    }
    Ok(())
}

fn take_message(log: &mut LoggedRun, topic: Topic, data: &[u8]) -> Result<(), String> {
    fn parse<'a, T: serde::Deserialize<'a>>(topic: Topic, data: &'a [u8]) -> Result<T, String> {
        serde_json::from_slice(data).map_err(|e| format!("{}: {e}", topic.name()))
    }
    let record = |e: RecordError| format!("{}: {e}", topic.name());
    match topic {
        Topic::Scenario => {
            let message = parse::<ScenarioMessage>(topic, data)?;
            // Read back as a scenario file is: no longer than one may be.
            if message.toml.len() as u64 > MAX_SCENARIO_BYTES {
                return Err(format!(
                    "{}: a scenario of {} bytes, more than the {MAX_SCENARIO_BYTES} a scenario file may hold",
                    topic.name(),
                    message.toml.len()
                ));
            }
            log.scenario_toml = message.toml;
            log.format_version = message.format_version;
            log.source = message.source;
            log.options = message.options;
        }
        Topic::Plan => log.first_plan = parse::<PlanMessage>(topic, data)?.to_path(),
        Topic::Step => {
            log.steps.push(
                parse::<StepMessage>(topic, data)?
                    .to_step()
                    .map_err(record)?,
            );
            log.marks.push(StepMarks {
                faults: log.faults.len(),
                replans: log.replans.len(),
                waits: log.waits.len(),
                found: log.found.len(),
                turns: log.turns.len(),
            });
        }
        Topic::Fault => log
            .faults
            .push(parse::<FaultMessage>(topic, data)?.to_fault()),
        Topic::Replan => log.replans.push(
            parse::<ReplanMessage>(topic, data)?
                .to_replan()
                .map_err(record)?,
        ),
        Topic::Wait => log.waits.push(
            parse::<WaitMessage>(topic, data)?
                .to_wait()
                .map_err(record)?,
        ),
        Topic::Found => {
            let found = parse::<FoundMessage>(topic, data)?;
            log.found.push((found.obstacle, found.step));
        }
        Topic::Turn => log
            .turns
            .extend(parse::<TurnsMessage>(topic, data)?.to_turns()),
        Topic::End => log.end = Some(parse(topic, data)?),
        Topic::Scene | Topic::CentrePlan | Topic::Tf => {}
    }
    Ok(())
}

impl LoggedRun {
    /// The run's record as far as the log goes, for a scenario of `unknown` unknown
    /// obstacles: complete only if the log says the run ended complete.
    pub fn to_run(&self, scenario_name: &str, unknown: usize) -> Run {
        let mut found_at = vec![None; unknown];
        for &(obstacle, step) in &self.found {
            if let Some(slot) = found_at.get_mut(obstacle) {
                *slot = Some(step);
            }
        }
        Run {
            scenario: scenario_name.to_string(),
            centre_path: self.steps.iter().map(|s| s.centre).collect(),
            steps: self.steps.clone(),
            faults: self.faults.clone(),
            completed: self.end.as_ref().is_some_and(|e| e.completed),
            course: CourseRecord {
                replans: self.replans.clone(),
                waits: self.waits.clone(),
                found_at,
                gave_up: self.end.as_ref().is_some_and(|e| e.gave_up),
            },
        }
    }
}
