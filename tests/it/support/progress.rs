//! Following a `coordinator run` process by its progress, to time kills and signals by
//! the steps it has run rather than by a guess of how long a run takes.
//!
//! The coordinator logs `step N done` on stderr as each step ends when `RUST_LOG` lets
//! the target [`runner::turns::PROGRESS_TARGET`] through at `info`. [`Watched`]
//! runs it with that filter and its stderr on a pipe of [`PIPE_BYTES`], read by a
//! thread that keeps every byte (for the assertions, so nothing blocks on a full pipe)
//! and stops reading at each step the test asked to hold at until the test has acted.
//!
//! The coordinator's stderr is unbuffered (`std::io::stderr`), so each line is in the
//! pipe once it is logged, and a full pipe blocks the coordinator at its next line.
//! While the reader holds at step N, the lines of the steps after N can only be in the
//! pipe or in the reader's last chunk, at least [`SHORTEST_PROGRESS_LINE`] bytes each:
//! the coordinator can have ended at most [`RUN_AHEAD_STEPS`] steps after N (the last of
//! them with its line not yet written). So a kill sent during a hold at a step no later
//! than [`latest_hold_step`] lands while a step is still to come, by construction.

use std::collections::VecDeque;
use std::fs::File;
use std::io::Read;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::thread::JoinHandle;
use std::time::Duration;

use nix::fcntl::{FcntlArg, OFlag, fcntl};

/// The capacity the coordinator's stderr pipe is set to (the smallest Linux allows on
/// 4 KiB pages).
pub const PIPE_BYTES: usize = 4096;

/// The most bytes the reader takes off the pipe at once.
const READ_CHUNK: usize = 64;

/// The shortest progress line the coordinator writes: the line of step 1 as its logger
/// formats it without colours (a timestamp of fixed width, to the microsecond, the level
/// right-aligned in five columns, the message and the newline; coloured lines are
/// longer). The reader checks every progress line it takes against it
/// ([`assert_long_enough`]), so a change of the log's format fails loudly instead of
/// breaking [`RUN_AHEAD_STEPS`] unseen.
pub const SHORTEST_PROGRESS_LINE: usize = "2026-01-01T00:00:00.000000Z  INFO step 1 done\n".len();

/// How many steps past a held step the coordinator can have ended while the reader
/// holds: the whole lines that fit in the pipe and the reader's last chunk, one more
/// step ended whose line is blocked, and one more ended and handed to the log's thread
/// (which tells a step done once it is written, and takes the next only after telling).
pub const RUN_AHEAD_STEPS: usize = (PIPE_BYTES + READ_CHUNK) / SHORTEST_PROGRESS_LINE + 2;

/// How long [`Watched::hold`] waits for a step before it fails the test: a run that
/// never reports the step is stuck (the deadline only keeps a broken run from hanging
/// the suite).
const HOLD_DEADLINE: Duration = Duration::from_secs(300);

/// The `RUST_LOG` a watched coordinator runs with: the default level for everything
/// (warnings, as a user sees them) and the progress lines.
pub fn progress_filter() -> String {
    format!("warn,{}=info", runner::turns::PROGRESS_TARGET)
}

/// The latest step to hold at in a run of `last_step` steps so that whatever the test
/// does during the hold lands before the run's last step begins: the coordinator can be
/// at most [`RUN_AHEAD_STEPS`] further on, and one step must remain after that.
pub fn latest_hold_step(last_step: usize) -> usize {
    let latest = last_step.saturating_sub(RUN_AHEAD_STEPS + 1);
    assert!(
        latest >= 1,
        "a run of {last_step} steps is too short to hold at a step and act before its end \
         (the coordinator may run {RUN_AHEAD_STEPS} steps ahead of what is read)"
    );
    latest
}

/// The steps of the centre path planned for the scenario in `file` (its last step's
/// number): the steps a run without waits or replanning has.
pub fn centre_path_steps(file: &Path) -> usize {
    let scenario = shared::world::scenario::Scenario::load(file).expect("the scenario");
    let path = shared::run::simulate::plan_centre_path(&scenario).expect("centre path");
    path.len() - 1
}

/// Fails the test if a progress line (without its newline) is shorter than
/// [`SHORTEST_PROGRESS_LINE`] allows.
fn assert_long_enough(line: &[u8]) {
    assert!(
        line.len() + 1 >= SHORTEST_PROGRESS_LINE,
        "a progress line of {} bytes, shorter than the {SHORTEST_PROGRESS_LINE} that \
         RUN_AHEAD_STEPS counts on (the log's format changed): {:?}",
        line.len() + 1,
        String::from_utf8_lossy(line)
    );
}

/// The step number in a progress line (`... INFO ... step N done`, with or without
/// colours), if it is one.
fn progress_step(line: &[u8]) -> Option<usize> {
    let text = std::str::from_utf8(line).ok()?.trim_end();
    let (head, number) = text.strip_suffix(" done")?.rsplit_once(' ')?;
    if !head.strip_suffix(" step")?.contains("INFO") {
        return None;
    }
    number.parse().ok()
}

/// The reader: every byte of `pipe` until every writer has closed it; at each step of
/// `holds` (sorted) once reported, `reached` is told the step and no more is read until
/// `resume` says so (or is gone).
fn read_progress(
    mut pipe: File,
    mut holds: VecDeque<usize>,
    reached: Sender<usize>,
    resume: Receiver<()>,
) -> Vec<u8> {
    let mut all = Vec::new();
    let mut line_start = 0;
    let mut chunk = [0u8; READ_CHUNK];
    loop {
        let n = match pipe.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(_) => break,
        };
        all.extend_from_slice(&chunk[..n]);
        while let Some(at) = all[line_start..].iter().position(|&b| b == b'\n') {
            let line = &all[line_start..line_start + at];
            let step = progress_step(line);
            if step.is_some() {
                assert_long_enough(line);
            }
            line_start += at + 1;
            let Some(step) = step else { continue };
            while holds.front().is_some_and(|&h| h <= step) {
                holds.pop_front();
                if reached.send(step).is_err() {
                    // Nobody holds any more: read on.
                    holds.clear();
                    break;
                }
                let _ = resume.recv();
            }
        }
    }
    all
}

/// A coordinator process followed by its progress: started with the progress lines on,
/// its stderr read (and kept) by a thread that holds at the steps given.
pub struct Watched {
    child: Child,
    status: Option<ExitStatus>,
    reached: Option<Receiver<usize>>,
    resume: Option<Sender<()>>,
    stderr: Option<JoinHandle<Vec<u8>>>,
    stdout: Option<JoinHandle<Vec<u8>>>,
}

/// A hold at a reported step: the coordinator's stderr is not read (so the coordinator
/// gets at most [`RUN_AHEAD_STEPS`] further) until this is dropped.
pub struct Held {
    /// The step reported.
    pub step: usize,
    resume: Sender<()>,
}

impl Drop for Held {
    fn drop(&mut self) {
        let _ = self.resume.send(());
    }
}

impl Watched {
    /// Start `command` (a `coordinator run`, see [`super::coordinator`]) with the
    /// progress lines on and its stderr on a pipe of [`PIPE_BYTES`]; the reader holds at
    /// each step of `holds` (a step listed twice is held twice), in order.
    pub fn spawn(mut command: Command, holds: &[usize]) -> Watched {
        let (read_end, write_end) = nix::unistd::pipe2(OFlag::O_CLOEXEC).expect("a pipe");
        let size = fcntl(&read_end, FcntlArg::F_SETPIPE_SZ(PIPE_BYTES as i32))
            .expect("set the pipe's size");
        assert_eq!(
            size as usize, PIPE_BYTES,
            "the pipe's capacity: RUN_AHEAD_STEPS counts on {PIPE_BYTES} bytes"
        );
        command
            .env("RUST_LOG", progress_filter())
            .stdout(Stdio::piped())
            .stderr(Stdio::from(write_end));
        let mut child = command.spawn().expect("start the coordinator");
        // The command holds the pipe's write end: dropped, only the coordinator (and the
        // agents it starts) hold it, and the reader sees the end when they are gone.
        drop(command);
        let mut holds: Vec<usize> = holds.to_vec();
        holds.sort_unstable();
        let (reached_tx, reached_rx) = channel();
        let (resume_tx, resume_rx) = channel();
        let pipe = File::from(read_end);
        let stderr =
            std::thread::spawn(move || read_progress(pipe, holds.into(), reached_tx, resume_rx));
        let mut out = child.stdout.take().expect("stdout is piped");
        let stdout = std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = out.read_to_end(&mut bytes);
            bytes
        });
        Watched {
            child,
            status: None,
            reached: Some(reached_rx),
            resume: Some(resume_tx),
            stderr: Some(stderr),
            stdout: Some(stdout),
        }
    }

    /// The coordinator's process id.
    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// Wait until the next step to hold at is reported, and hold there until the
    /// returned guard is dropped. Fails the test if the run ends first.
    pub fn hold(&mut self) -> Held {
        let reached = self.reached.as_ref().expect("not waited yet");
        match reached.recv_timeout(HOLD_DEADLINE) {
            Ok(step) => Held {
                step,
                resume: self.resume.clone().expect("not waited yet"),
            },
            Err(RecvTimeoutError::Disconnected) => {
                let stderr = self.stderr.take().map(|h| h.join().unwrap_or_default());
                panic!(
                    "the run ended before the step to hold at was reported: {}",
                    String::from_utf8_lossy(&stderr.unwrap_or_default())
                );
            }
            Err(RecvTimeoutError::Timeout) => {
                panic!("no step to hold at reported in {HOLD_DEADLINE:?}: the run is stuck")
            }
        }
    }

    /// Wait for the coordinator process to exit (and reap it), without waiting for its
    /// outputs to close; a run still going after [`super::HUNG_RUN`] is killed and the
    /// test fails.
    pub fn wait(&mut self) -> ExitStatus {
        if let Some(status) = self.status {
            return status;
        }
        // Dropping `self` after the panic kills and reaps the run.
        let mut status = None;
        super::wait_until(super::HUNG_RUN, "the run was killed as hung", || {
            status = self.child.try_wait().expect("wait for the coordinator");
            status.is_some()
        });
        self.status = status;
        status.expect("the run ended")
    }

    /// Wait for the coordinator to exit and for its stdout and stderr to close (the
    /// agents it started hold its stderr too); holds not yet taken are let go.
    pub fn wait_with_output(mut self) -> Output {
        // Let the reader go on past any hold left.
        self.reached = None;
        self.resume = None;
        let status = self.wait();
        let join = |h: Option<JoinHandle<Vec<u8>>>| {
            h.map(|h| h.join().expect("a reader thread"))
                .unwrap_or_default()
        };
        Output {
            status,
            stdout: join(self.stdout.take()),
            stderr: join(self.stderr.take()),
        }
    }
}

impl Drop for Watched {
    /// A test that fails mid-run leaves no coordinator behind (its agents leave when it
    /// is gone).
    fn drop(&mut self) {
        if self.status.is_none() {
            self.reached = None;
            self.resume = None;
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
