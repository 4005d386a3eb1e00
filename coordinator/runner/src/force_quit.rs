//! The way out of a coordinator that does not stop: the second SIGINT or SIGTERM ends the
//! process at once.
//!
//! The first signal asks the run to stop cleanly: iceoryx2's handler notes it, the run's
//! loops see it, the agents are told to quit and the outputs are written. A coordinator
//! stuck where no loop looks (inside a library's wait, or writing to a full pipe) never
//! sees it. So the coordinator also counts the signals, in a handler of its own that
//! passes each one on to iceoryx2's; at the second, a thread of its own kills the run's
//! processes, removes the run's control group and its files in /dev/shm, and exits with
//! [`FORCED_EXIT_CODE`], without the outputs (a run log keeps every step it wrote).

use std::os::fd::{AsRawFd, OwnedFd};
use std::sync::atomic::{AtomicI32, AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::Duration;

use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use wire::cgroup::CgroupDirs;

use crate::procfs::{ProcStat, live_processes_of_run};

/// The exit code of a coordinator ended by a second interrupt (128 + SIGINT, as a shell
/// reports a process killed by Ctrl-C).
pub const FORCED_EXIT_CODE: i32 = 130;

/// How long the forced exit waits for the run's processes to die.
const KILL_TIMEOUT: Duration = Duration::from_secs(2);

/// SIGINT and SIGTERM received since [`install`].
static SIGNALS: AtomicUsize = AtomicUsize::new(0);

/// The write end of the pipe that wakes the exit thread (-1 before [`install`]).
static WAKE_FD: AtomicI32 = AtomicI32::new(-1);

/// The handlers in place before ours (iceoryx2's) as function addresses, by signal
/// (SIGINT, SIGTERM); 0 for none.
static PREVIOUS: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];

/// The signals counted, in the order of [`PREVIOUS`].
const COUNTED: [libc::c_int; 2] = [libc::SIGINT, libc::SIGTERM];

/// What a forced exit removes: the run under way, if any.
static RUN: Mutex<Option<Run>> = Mutex::new(None);

/// The run under way, as a forced exit must find what it left.
struct Run {
    prefix: String,
    cgroup: Option<CgroupDirs>,
}

/// Count the signal, wake the exit thread at the second, and pass the signal on to the
/// handler installed before (async-signal-safe: an atomic add, write(2), a call).
extern "C" fn count_and_pass_on(signal: libc::c_int) {
    if SIGNALS.fetch_add(1, Ordering::SeqCst) + 1 >= 2 {
        let fd = WAKE_FD.load(Ordering::SeqCst);
        if fd >= 0 {
            // SAFETY: write(2) of one static byte to the pipe this module keeps open.
            unsafe { libc::write(fd, [1u8].as_ptr().cast(), 1) };
        }
    }
    let k = usize::from(signal != COUNTED[0]);
    let previous = PREVIOUS[k].load(Ordering::SeqCst);
    if previous != 0 {
        // SAFETY: the address of a plain handler, read from sigaction(2) in `install`.
        let handler: extern "C" fn(libc::c_int) = unsafe { std::mem::transmute(previous) };
        handler(signal);
    }
}

/// Count SIGINT and SIGTERM from now on and end the process at the second (see the
/// module). Call once iceoryx2's handlers are in place (after a node's first wait); a
/// second call does nothing. A signal whose handler is not a plain function (the
/// default, say) is left alone: the first one still ends the process.
pub fn install() {
    static INSTALLED: OnceLock<()> = OnceLock::new();
    INSTALLED.get_or_init(|| {
        let Ok((read_end, write_end)) = nix::unistd::pipe2(nix::fcntl::OFlag::O_CLOEXEC) else {
            tracing::warn!("no pipe for the forced exit: a second Ctrl-C will not end a stuck run");
            return;
        };
        let spawned = std::thread::Builder::new()
            .name("force-quit".into())
            .spawn(move || wait_for_the_second_signal(read_end));
        if spawned.is_err() {
            tracing::warn!(
                "no thread for the forced exit: a second Ctrl-C will not end a stuck run"
            );
            return;
        }
        WAKE_FD.store(write_end.as_raw_fd(), Ordering::SeqCst);
        // Kept open for the life of the process.
        std::mem::forget(write_end);
        for (k, &signal) in COUNTED.iter().enumerate() {
            // SAFETY: sigaction(2) with a zeroed struct to read into, then with a copy of
            // the action read whose handler is replaced by one that calls it.
            unsafe {
                let mut previous: libc::sigaction = std::mem::zeroed();
                if libc::sigaction(signal, std::ptr::null(), &mut previous) != 0 {
                    continue;
                }
                let plain = previous.sa_flags & libc::SA_SIGINFO == 0
                    && previous.sa_sigaction != libc::SIG_DFL
                    && previous.sa_sigaction != libc::SIG_IGN;
                if !plain {
                    continue;
                }
                PREVIOUS[k].store(previous.sa_sigaction, Ordering::SeqCst);
                let mut ours = previous;
                ours.sa_sigaction = count_and_pass_on as extern "C" fn(libc::c_int) as usize;
                libc::sigaction(signal, &ours, std::ptr::null_mut());
            }
        }
    });
}

/// While alive, a forced exit kills the processes of run `prefix` and removes `cgroup`
/// and the run's files.
pub struct RunGuard;

impl RunGuard {
    /// Name run `prefix` (its sandboxed agents in `cgroup`) as the one under way.
    pub fn new(prefix: &str, cgroup: Option<CgroupDirs>) -> Self {
        if let Ok(mut run) = RUN.lock() {
            *run = Some(Run {
                prefix: prefix.to_string(),
                cgroup,
            });
        }
        RunGuard
    }
}

impl Drop for RunGuard {
    fn drop(&mut self) {
        if let Ok(mut run) = RUN.lock() {
            *run = None;
        }
    }
}

/// The exit thread: block on the pipe until the second signal, then end the process.
fn wait_for_the_second_signal(read_end: OwnedFd) {
    let mut byte = [0u8; 1];
    loop {
        match nix::unistd::read(&read_end, &mut byte) {
            Ok(0) => return,
            Ok(_) if SIGNALS.load(Ordering::SeqCst) >= 2 => force_exit(),
            Ok(_) | Err(nix::errno::Errno::EINTR) => {}
            Err(_) => return,
        }
    }
}

/// Say why (from a thread of its own: stderr may be a full pipe, or locked by a thread
/// blocked writing to it), remove what the run under way left, and end the process
/// without running anything else.
fn force_exit() -> ! {
    let _ = std::thread::Builder::new().spawn(|| {
        let line =
            b"coordinator: interrupted a second time: leaving now, without the run's outputs\n";
        // SAFETY: write(2) to stderr of a static buffer.
        unsafe { libc::write(2, line.as_ptr().cast(), line.len()) };
    });
    // A thread that panicked holding the lock left a usable value all the same.
    let run = match RUN.lock() {
        Ok(mut run) => run.take(),
        Err(poisoned) => poisoned.into_inner().take(),
    };
    if let Some(run) = run {
        remove_run(&run);
    }
    // SAFETY: _exit(2) ends the process at once: no destructor or exit handler runs.
    unsafe { libc::_exit(FORCED_EXIT_CODE) }
}

/// Kill every process of `run` (found by [`wire::RUN_ENV`] in its environment: agents,
/// relays and what they started), remove its control group, wait for them to die, and
/// remove its files in /dev/shm.
fn remove_run(run: &Run) {
    let killed = live_processes_of_run(&run.prefix);
    for p in &killed {
        let _ = kill(Pid::from_raw(p.pid as i32), Signal::SIGKILL);
    }
    if let Some(group) = &run.cgroup {
        let _ = group.remove(KILL_TIMEOUT);
    }
    // Dead once a zombie or gone (or another process under that pid).
    wire::poll_until(KILL_TIMEOUT, || {
        killed
            .iter()
            .all(|p| ProcStat::read(p.pid).is_none_or(|now| now.start != p.start || now.zombie()))
    });
    wire::remove_run_files_in_shm(&run.prefix);
    let _ = wire::remove_run_root(&run.prefix);
}
