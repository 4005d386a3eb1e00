//! The log written by a thread of its own ([`LogThread`]), so that a step's messages are
//! serialised while the next step's turns go on.
//!
//! The step loop hands each ended step over through a rendezvous channel: the hand-over
//! waits until the thread has written the step before, so at most one ended step is
//! being written at any time. The thread tells each step written (the coordinator's
//! `step N done` line comes from there): every step told is in the file. A crash loses
//! the step under way and at most the one before it, still being written.

use std::sync::mpsc::{self, SyncSender};
use std::thread::JoinHandle;

use shared::run::record::{Fault, Step};
use shared::world::course::{Replan, Wait};

use super::records::TurnMessage;
use super::writer::{CourseSoFar, RunLogError, RunLogWriter};

/// What the thread needs of an ended step: the step, and what was recorded since the
/// step before.
struct Ended {
    step: Step,
    new_faults: Vec<Fault>,
    /// `None` before the course has begun (step 0).
    course: Option<CourseNews>,
    turns: Vec<TurnMessage>,
}

/// What the course did since the step before.
struct CourseNews {
    new_replans: Vec<Replan>,
    new_waits: Vec<Wait>,
    found_at: Vec<Option<usize>>,
}

/// The log's writer on a thread of its own.
pub struct LogThread {
    sender: Option<SyncSender<Ended>>,
    thread: Option<JoinHandle<Result<RunLogWriter, RunLogError>>>,
    /// How much of each growing list has been handed over.
    faults: usize,
    replans: usize,
    waits: usize,
}

impl LogThread {
    /// Hand `writer` to a thread of its own; `written(step)` is called there once each
    /// step is in the file.
    pub fn start(
        writer: RunLogWriter,
        written: impl Fn(usize) + Send + 'static,
    ) -> Result<Self, RunLogError> {
        let path = writer.path().to_path_buf();
        let (sender, receiver) = mpsc::sync_channel::<Ended>(0);
        let thread = std::thread::Builder::new()
            .name("run-log".into())
            .spawn(move || {
                lower_own_priority();
                let mut writer = writer;
                let (mut faults, mut replans, mut waits) = (Vec::new(), Vec::new(), Vec::new());
                for ended in receiver {
                    faults.extend(ended.new_faults);
                    let course = ended.course.map(|news| {
                        replans.extend(news.new_replans);
                        waits.extend(news.new_waits);
                        news.found_at
                    });
                    let view = course.as_ref().map(|found_at| CourseSoFar {
                        replans: &replans,
                        waits: &waits,
                        found_at,
                    });
                    writer.log_step(&ended.step, &faults, view, ended.turns)?;
                    written(ended.step.step);
                }
                Ok(writer)
            })
            .map_err(|source| RunLogError::Io { path, source })?;
        Ok(Self {
            sender: Some(sender),
            thread: Some(thread),
            faults: 0,
            replans: 0,
            waits: 0,
        })
    }

    /// Hand the ended `step` over, with every fault so far (`faults`), the course so far
    /// (`None` before it has begun) and the turns answered since the step before. Waits
    /// until the thread has written the step before; fails if writing failed.
    pub fn log_step(
        &mut self,
        step: &Step,
        faults: &[Fault],
        course: Option<CourseSoFar<'_>>,
        turns: Vec<TurnMessage>,
    ) -> Result<(), RunLogError> {
        let course = course.map(|c| {
            let news = CourseNews {
                new_replans: c.replans.get(self.replans..).unwrap_or_default().to_vec(),
                new_waits: c.waits.get(self.waits..).unwrap_or_default().to_vec(),
                found_at: c.found_at.to_vec(),
            };
            self.replans = self.replans.max(c.replans.len());
            self.waits = self.waits.max(c.waits.len());
            news
        });
        let ended = Ended {
            step: step.clone(),
            new_faults: faults.get(self.faults..).unwrap_or_default().to_vec(),
            course,
            turns,
        };
        self.faults = self.faults.max(faults.len());
        let sent = self
            .sender
            .as_ref()
            .is_some_and(|sender| sender.send(ended).is_ok());
        match sent {
            true => Ok(()),
            // The thread has stopped: it failed; its error says why.
            false => match self.stop() {
                Err(e) => Err(e),
                Ok(_) => Err(RunLogError::Stopped),
            },
        }
    }

    /// Wait for the thread to write what it was handed, and take the writer back.
    fn stop(&mut self) -> Result<RunLogWriter, RunLogError> {
        self.sender.take();
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(RunLogError::Stopped),
            None => Err(RunLogError::Stopped),
        }
    }

    /// Every step handed over written, end the log ([`RunLogWriter::finish`]).
    pub fn finish(
        mut self,
        completed: bool,
        gave_up: bool,
    ) -> Result<std::path::PathBuf, RunLogError> {
        self.stop()?.finish(completed, gave_up)
    }
}

/// Lower this thread's scheduling priority (nice 10): on a machine whose cores the
/// coordinator and the agent whose turn it is keep busy, the log waits rather than
/// delays a turn; the rendezvous hand-over gives it a core whenever it falls behind.
fn lower_own_priority() {
    // SAFETY: gettid(2) and setpriority(2) on this thread's own id; a failure only leaves
    // the priority as it was.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        libc::setpriority(libc::PRIO_PROCESS, tid, 10);
    }
}

impl Drop for LogThread {
    fn drop(&mut self) {
        // Whatever was handed over is written before the thread goes.
        let _ = self.stop();
    }
}
