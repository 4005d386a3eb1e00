//! A run's doorbells: how the coordinator wakes an agent and an agent wakes the
//! coordinator. One file in the run's private folder ([`crate::run_root`]), mapped shared
//! by the coordinator and every agent process (or relay) of the run, holds futex words,
//! each on a cache line of its own:
//!
//! - one word per agent: the events rung for it and not yet taken, one bit per event id
//!   ([`crate::EVENT_TURN`], ...); the coordinator sets a bit and wakes the agent, the
//!   agent takes every bit at once and sleeps on the word while it is zero;
//! - the run's answer counter: an agent counts one after each state it publishes, and
//!   wakes the coordinator if it sleeps; the coordinator sleeps while the counter holds
//!   what it saw, and then looks at the state channel of the agent it waits for;
//! - how the run rings ([`WakeBy`]): the coordinator makes the file in either case, and
//!   an agent reads there whether to wait on its word or on iceoryx2's event services.
//!
//! A ring is a store and, at most, one system call on each side: no socket, no buffer.
//! The words carry no data: the samples stay on the iceoryx2 channels, checked as ever.
//! The file is private to the run's user, so a sandboxed agent cannot reach it (its
//! relay, the coordinator's child, rings for it). A trusted agent, which runs as that
//! user, can: by writing another agent's word it can wake it for nothing (it finds no
//! world for it and sleeps again), take its turn's ring (it then misses the turn) or ring
//! it `quit` (it leaves, and is recorded dead), as it could already signal or kill that
//! agent; by writing the counter it wakes the coordinator for nothing or delays it by a
//! liveness slice. Nothing it writes is used but as a reason to look again.

use std::num::NonZeroUsize;
use std::path::PathBuf;
use std::ptr::NonNull;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use crate::run_folder::{RunFilesError, check_run_root, private_file_problem, run_root};

/// The file's name in the run's private folder.
const DOORBELL_FILE_NAME: &str = "doorbells";

/// Bytes of a cache line: every agent's word has a line of its own, so that ringing one
/// agent or its taking the ring does not pull the line from under its neighbours.
const LINE_BYTES: usize = 64;
/// Words in a line.
const LINE_WORDS: usize = LINE_BYTES / std::mem::size_of::<AtomicU32>();
/// The first line holds the answer counter and whether the coordinator sleeps on it;
/// agent `i`'s word is the first of line `i + 1`.
const ANSWERS: usize = 0;
const SLEEPING: usize = 1;
const WAKE_BY: usize = 2;

/// How a run's processes ring each other, as the coordinator wrote it in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WakeBy {
    /// By these doorbells.
    Doorbells,
    /// By iceoryx2's event services (the `turn` service of each channel, the run's done
    /// service); the file then holds only this.
    Events,
}

impl WakeBy {
    fn word(self) -> u32 {
        match self {
            Self::Doorbells => 1,
            Self::Events => 2,
        }
    }
}

/// Why the doorbells cannot be made or used.
#[derive(Debug, thiserror::Error)]
pub enum DoorbellError {
    /// The run has no private folder (no `/dev/shm`, or an invalid prefix).
    #[error("run {0:?} has no private folder for its doorbells")]
    NoRunFolder(String),
    /// The run's folder is not the private folder the run made.
    #[error(transparent)]
    Folder(#[from] RunFilesError),
    /// Reading, writing or mapping the file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The failure.
        source: std::io::Error,
    },
    /// The file is not what the coordinator made.
    #[error("{}: {why}: refusing it", path.display())]
    Untrusted {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        why: String,
    },
    /// An agent index beyond the run's agents.
    #[error("agent {agent} has no doorbell (the run has {agents})")]
    NoSuchAgent {
        /// The index asked for.
        agent: usize,
        /// The run's agents.
        agents: usize,
    },
}

/// How a wait on a doorbell ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Woken {
    /// Rung, or woken for nothing (spurious or stale), or the timeout passed: look.
    Look,
    /// A signal interrupted the wait.
    Interrupted,
}

/// A run's doorbells, mapped.
pub struct Doorbells {
    words: NonNull<AtomicU32>,
    len: usize,
    agents: usize,
}

// SAFETY: the mapping is reached only through atomics, and lives as long as the value
// (unmapped in `drop`); another thread may ring, wait and count as well as this one.
unsafe impl Send for Doorbells {}
// SAFETY: as above.
unsafe impl Sync for Doorbells {}

impl std::fmt::Debug for Doorbells {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Doorbells")
            .field("agents", &self.agents)
            .finish()
    }
}

/// The path of run `prefix`'s doorbell file.
fn doorbell_path(prefix: &str) -> Result<PathBuf, DoorbellError> {
    let root = run_root(prefix).ok_or_else(|| DoorbellError::NoRunFolder(prefix.into()))?;
    check_run_root(&root)?;
    Ok(root.join(DOORBELL_FILE_NAME))
}

impl Doorbells {
    /// Make run `prefix`'s doorbells for `agents` agents, rung as `wake_by` says (the
    /// coordinator, once, after the run's private folder exists): a new file, readable
    /// and writable by its owner only.
    pub fn create(prefix: &str, agents: usize, wake_by: WakeBy) -> Result<Self, DoorbellError> {
        use std::os::unix::fs::OpenOptionsExt;
        let path = doorbell_path(prefix)?;
        let io = |source| DoorbellError::Io {
            path: path.clone(),
            source,
        };
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .mode(0o600)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
            .map_err(io)?;
        let len = (1 + agents) * LINE_BYTES;
        file.set_len(len as u64).map_err(io)?;
        let doorbells = Self::map(&file, len, agents).map_err(io)?;
        doorbells
            .word(WAKE_BY)
            .store(wake_by.word(), Ordering::SeqCst);
        Ok(doorbells)
    }

    /// Open run `prefix`'s doorbells as agent `agent` (or its relay): refused unless the
    /// file is a regular file of this user, private, with a word for `agent`.
    pub fn open(prefix: &str, agent: usize) -> Result<Self, DoorbellError> {
        use std::os::unix::fs::OpenOptionsExt;
        let path = doorbell_path(prefix)?;
        let io = |source| DoorbellError::Io {
            path: path.clone(),
            source,
        };
        let untrusted = |why: String| DoorbellError::Untrusted {
            path: path.clone(),
            why,
        };
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
            .map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        if let Some(why) = private_file_problem(&meta) {
            return Err(untrusted(why));
        }
        let line = LINE_BYTES as u64;
        let len = meta.len();
        if len % line != 0 || len / line < agent as u64 + 2 {
            return Err(untrusted(format!("{len} bytes: no word for agent {agent}")));
        }
        let len = usize::try_from(len).map_err(|_| untrusted(format!("{len} bytes")))?;
        let agents = len / LINE_BYTES - 1;
        Self::map(&file, len, agents).map_err(io)
    }

    fn map(file: &std::fs::File, len: usize, agents: usize) -> std::io::Result<Self> {
        use std::os::fd::AsRawFd;
        let Some(size) = NonZeroUsize::new(len) else {
            return Err(std::io::Error::other("an empty doorbell file"));
        };
        // SAFETY: a shared mapping of the whole file (its length checked above); the
        // file may be closed afterwards, the mapping stays until `drop`.
        let base = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                size.get(),
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_SHARED,
                file.as_raw_fd(),
                0,
            )
        };
        if base == libc::MAP_FAILED {
            return Err(std::io::Error::last_os_error());
        }
        let words = NonNull::new(base.cast::<AtomicU32>())
            .ok_or_else(|| std::io::Error::other("a null mapping"))?;
        Ok(Self { words, len, agents })
    }

    /// How the run rings, as the coordinator wrote it; `None` if the word says neither.
    pub fn wake_by(&self) -> Option<WakeBy> {
        let word = self.word(WAKE_BY).load(Ordering::SeqCst);
        [WakeBy::Doorbells, WakeBy::Events]
            .into_iter()
            .find(|w| w.word() == word)
    }

    /// As the coordinator, before agent `agent`'s new process starts: nothing rung for it
    /// (a ring its predecessor left untaken is not the new process's).
    pub fn clear(&self, agent: usize) -> Result<(), DoorbellError> {
        self.agent_word(agent)?.store(0, Ordering::SeqCst);
        Ok(())
    }

    fn word(&self, index: usize) -> &AtomicU32 {
        debug_assert!(index < (1 + self.agents) * LINE_WORDS);
        // SAFETY: `index` is within the mapping (callers check it against `agents`), the
        // mapping is page-aligned and lives as long as `self`, and `AtomicU32` has the
        // layout of `u32`.
        unsafe { &*self.words.as_ptr().add(index) }
    }

    fn agent_word(&self, agent: usize) -> Result<&AtomicU32, DoorbellError> {
        if agent >= self.agents {
            return Err(DoorbellError::NoSuchAgent {
                agent,
                agents: self.agents,
            });
        }
        Ok(self.word((1 + agent) * LINE_WORDS))
    }

    /// Ring event `event` (an id below 32) for agent `agent`, and wake it.
    pub fn ring(&self, agent: usize, event: usize) -> Result<(), DoorbellError> {
        let word = self.agent_word(agent)?;
        word.fetch_or(1 << (event % 32), Ordering::SeqCst);
        futex_wake(word);
        Ok(())
    }

    /// As agent `agent`: take the events rung, sleeping up to `timeout` while there are
    /// none. The events as bits (`1 << id`; none after a timeout or a wake-up for
    /// nothing), and how the wait ended.
    pub fn wait(&self, agent: usize, timeout: Duration) -> Result<(u32, Woken), DoorbellError> {
        let word = self.agent_word(agent)?;
        let rung = word.swap(0, Ordering::SeqCst);
        if rung != 0 {
            return Ok((rung, Woken::Look));
        }
        let woken = futex_wait(word, 0, timeout);
        Ok((word.swap(0, Ordering::SeqCst), woken))
    }

    /// As an agent: count a published state, and wake the coordinator if it sleeps.
    pub fn answer(&self) {
        self.word(ANSWERS).fetch_add(1, Ordering::SeqCst);
        if self.word(SLEEPING).load(Ordering::SeqCst) != 0 {
            futex_wake(self.word(ANSWERS));
        }
    }

    /// The answer counter now: read it before looking at a channel, then sleep with
    /// [`Self::wait_answer`].
    pub fn answers(&self) -> u32 {
        self.word(ANSWERS).load(Ordering::SeqCst)
    }

    /// As the coordinator: sleep up to `timeout` while the answer counter still holds
    /// `seen`.
    pub fn wait_answer(&self, seen: u32, timeout: Duration) -> Woken {
        let sleeping = self.word(SLEEPING);
        sleeping.store(1, Ordering::SeqCst);
        let woken = futex_wait(self.word(ANSWERS), seen, timeout);
        sleeping.store(0, Ordering::SeqCst);
        woken
    }
}

impl Drop for Doorbells {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `map`, with its length; no reference outlives
        // `self`.
        unsafe { libc::munmap(self.words.as_ptr().cast(), self.len) };
    }
}

/// Sleep while `word` holds `expected`, at most `timeout`.
fn futex_wait(word: &AtomicU32, expected: u32, timeout: Duration) -> Woken {
    let ts = libc::timespec {
        tv_sec: libc::time_t::try_from(timeout.as_secs()).unwrap_or(libc::time_t::MAX),
        tv_nsec: libc::c_long::from(timeout.subsec_nanos() as i32),
    };
    // SAFETY: a futex wait on a valid, aligned word of a shared mapping, with a valid
    // timeout; whatever it returns, the caller looks at the word again.
    let r = unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT,
            expected,
            &ts as *const libc::timespec,
        )
    };
    if r == -1 && std::io::Error::last_os_error().raw_os_error() == Some(libc::EINTR) {
        Woken::Interrupted
    } else {
        Woken::Look
    }
}

/// Wake every sleeper on `word` (there is one at most: its owner).
fn futex_wake(word: &AtomicU32) {
    // SAFETY: a futex wake on a valid, aligned word of a shared mapping.
    unsafe { libc::syscall(libc::SYS_futex, word.as_ptr(), libc::FUTEX_WAKE, i32::MAX) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EVENT_ECHO, EVENT_QUIT, EVENT_TURN, RunPrefix, RunRoot, WakeBy};

    /// A run folder of its own, removed with its files when dropped.
    fn run() -> (String, RunRoot) {
        let prefix = RunPrefix::new_random().expect("a prefix").to_string();
        let root = RunRoot::create(&prefix).expect("the run folder");
        (prefix, root)
    }

    #[test]
    fn a_ring_is_taken_once_with_every_event_rung_since() {
        let (prefix, _root) = run();
        let coordinator = Doorbells::create(&prefix, 3, WakeBy::Doorbells).expect("made");
        let agent = Doorbells::open(&prefix, 2).expect("opened");
        coordinator.ring(2, EVENT_TURN).expect("rung");
        coordinator.ring(2, EVENT_ECHO).expect("rung");
        let (rung, woken) = agent.wait(2, Duration::from_secs(5)).expect("waited");
        assert_eq!(rung, (1 << EVENT_TURN) | (1 << EVENT_ECHO));
        assert_eq!(woken, Woken::Look);
        // Taken: nothing is left, and the wait times out with nothing.
        let (rung, _) = agent.wait(2, Duration::from_millis(5)).expect("waited");
        assert_eq!(rung, 0);
        // Another agent's word is untouched by these rings.
        assert_eq!(agent.wait(1, Duration::ZERO).expect("waited").0, 0);
        assert!(matches!(
            coordinator.ring(3, EVENT_QUIT),
            Err(DoorbellError::NoSuchAgent {
                agent: 3,
                agents: 3
            })
        ));
        // A ring left for a process that is gone is cleared before its replacement runs.
        coordinator.ring(2, EVENT_QUIT).expect("rung");
        coordinator.clear(2).expect("cleared");
        assert_eq!(agent.wait(2, Duration::ZERO).expect("waited").0, 0);
    }

    #[test]
    fn an_agent_reads_how_the_run_rings() {
        for wake_by in [WakeBy::Doorbells, WakeBy::Events] {
            let (prefix, _root) = run();
            let _coordinator = Doorbells::create(&prefix, 1, wake_by).expect("made");
            let agent = Doorbells::open(&prefix, 0).expect("opened");
            assert_eq!(agent.wake_by(), Some(wake_by));
        }
    }

    #[test]
    fn a_ring_from_another_thread_wakes_the_sleeper() {
        let (prefix, _root) = run();
        let coordinator = Doorbells::create(&prefix, 1, WakeBy::Doorbells).expect("made");
        let agent = Doorbells::open(&prefix, 0).expect("opened");
        std::thread::scope(|s| {
            let waiter = s.spawn(|| {
                let started = std::time::Instant::now();
                let waited = agent.wait(0, Duration::from_secs(60)).expect("waited");
                (waited, started.elapsed())
            });
            std::thread::sleep(Duration::from_millis(20));
            coordinator.ring(0, EVENT_QUIT).expect("rung");
            let ((rung, _), slept) = waiter.join().expect("joined");
            assert_eq!(rung, 1 << EVENT_QUIT);
            // Woken by the ring, not by the end of its minute.
            assert!(slept < Duration::from_secs(50), "{slept:?}");
        });
    }

    #[test]
    fn an_answer_counted_ends_the_coordinators_sleep() {
        let (prefix, _root) = run();
        let coordinator = Doorbells::create(&prefix, 2, WakeBy::Doorbells).expect("made");
        let agent = Doorbells::open(&prefix, 1).expect("opened");
        let seen = coordinator.answers();
        // Counted before the sleep: the sleep ends at once.
        agent.answer();
        let started = std::time::Instant::now();
        assert_eq!(
            coordinator.wait_answer(seen, Duration::from_secs(30)),
            Woken::Look
        );
        assert!(started.elapsed() < Duration::from_secs(30));
        assert_eq!(coordinator.answers(), seen + 1);
        // Counted while it sleeps: woken.
        let seen = coordinator.answers();
        std::thread::scope(|s| {
            let sleeper = s.spawn(|| {
                let started = std::time::Instant::now();
                let woken = coordinator.wait_answer(seen, Duration::from_secs(60));
                (woken, started.elapsed())
            });
            std::thread::sleep(Duration::from_millis(20));
            agent.answer();
            let (woken, slept) = sleeper.join().expect("joined");
            assert_eq!(woken, Woken::Look);
            // Woken by the answer, not by the end of its minute.
            assert!(slept < Duration::from_secs(50), "{slept:?}");
        });
        assert_eq!(coordinator.answers(), seen + 1);
    }

    #[test]
    fn a_file_not_as_made_is_refused() {
        use std::os::unix::fs::PermissionsExt;
        let (prefix, _root) = run();
        // None yet: not found (a run rung by events).
        assert!(matches!(
            Doorbells::open(&prefix, 0),
            Err(DoorbellError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound
        ));
        let made = Doorbells::create(&prefix, 2, WakeBy::Doorbells).expect("made");
        // No word for an agent beyond the run's.
        assert!(matches!(
            Doorbells::open(&prefix, 2),
            Err(DoorbellError::Untrusted { .. })
        ));
        // Made once only.
        assert!(Doorbells::create(&prefix, 2, WakeBy::Doorbells).is_err());
        let path = doorbell_path(&prefix).expect("the path");
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).expect("chmod");
        assert!(matches!(
            Doorbells::open(&prefix, 0),
            Err(DoorbellError::Untrusted { .. })
        ));
        drop(made);
        std::fs::remove_file(&path).expect("removed");
        std::os::unix::fs::symlink("/dev/null", &path).expect("a link");
        assert!(Doorbells::open(&prefix, 0).is_err());
        std::fs::remove_file(&path).expect("removed");
    }
}
