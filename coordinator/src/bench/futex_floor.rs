//! The wake-up floor of the operating system itself (`bench --scale`): N forked
//! processes, each asleep on a futex word of its own in shared memory, woken group by
//! group in the group sizes a run's steps had, each answering by counting itself on a
//! shared counter and waking this process. No channel, no sample, no socket: the least
//! that waking N processes once a step can cost on this machine, to set beside the same
//! wake-ups over the run's iceoryx2 events (the `wake_floor_s` of the scale report).
//!
//! A forked child runs only atomics and raw system calls (futex, `prctl`, `getppid`,
//! `_exit`), which are safe after `fork` in a process with threads; it dies with this
//! process (`PR_SET_PDEATHSIG`) and leaves on its own when told or when its parent is
//! gone.

use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};

/// What a child's word holds to tell it to leave.
const LEAVE: u32 = u32::MAX;

/// How long the floor waits for a group's answers before it gives up.
const GROUP_DEADLINE: Duration = Duration::from_secs(5);

/// How long a child sleeps before it looks whether its parent is still there.
const CHILD_LIVENESS: Duration = Duration::from_secs(1);

/// Shared words: one per child, then the answer counter.
struct SharedWords {
    base: *mut libc::c_void,
    len: usize,
}

impl SharedWords {
    fn new(words: usize) -> anyhow::Result<Self> {
        let len = words * std::mem::size_of::<AtomicU32>();
        // SAFETY: an anonymous shared mapping of `len` bytes, zeroed by the kernel;
        // unmapped in `drop`.
        let base = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_SHARED | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        if base == libc::MAP_FAILED {
            return Err(std::io::Error::last_os_error()).context("mapping the futex words");
        }
        Ok(Self { base, len })
    }

    fn words(&self) -> &[AtomicU32] {
        // SAFETY: the mapping holds `len` bytes, page-aligned, zero-initialised, and
        // `AtomicU32` has the layout of `u32`.
        unsafe {
            std::slice::from_raw_parts(
                self.base as *const AtomicU32,
                self.len / std::mem::size_of::<AtomicU32>(),
            )
        }
    }
}

impl Drop for SharedWords {
    fn drop(&mut self) {
        // SAFETY: the mapping made in `new`, no longer borrowed.
        unsafe { libc::munmap(self.base, self.len) };
    }
}

/// Sleep while `word` holds `expected`, at most `timeout`.
fn futex_wait(word: &AtomicU32, expected: u32, timeout: Duration) {
    let ts = libc::timespec {
        tv_sec: timeout.as_secs() as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: a futex wait on a valid, aligned word with a valid timeout; the result
    // (woken, timed out, interrupted, value changed) is read by the caller from the word.
    unsafe {
        libc::syscall(
            libc::SYS_futex,
            word.as_ptr(),
            libc::FUTEX_WAIT,
            expected,
            &ts as *const libc::timespec,
        )
    };
}

/// Wake one sleeper on `word`.
fn futex_wake(word: &AtomicU32) {
    // SAFETY: a futex wake on a valid, aligned word.
    unsafe { libc::syscall(libc::SYS_futex, word.as_ptr(), libc::FUTEX_WAKE, 1) };
}

/// A child's life: sleep on `mine`, and at each new value count itself on `answers`
/// and wake the parent; leave when told or when the parent is gone. Only atomics and
/// raw system calls.
fn child(mine: &AtomicU32, answers: &AtomicU32, parent: libc::pid_t) -> ! {
    // SAFETY: async-signal-safe system calls only.
    unsafe {
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
        if libc::getppid() != parent {
            libc::_exit(0);
        }
    }
    let mut seen = 0;
    loop {
        let now = mine.load(Ordering::Acquire);
        if now == LEAVE {
            // SAFETY: leaving without running anything of the parent's.
            unsafe { libc::_exit(0) };
        }
        if now == seen {
            futex_wait(mine, seen, CHILD_LIVENESS);
            // SAFETY: a plain system call.
            if unsafe { libc::getppid() } != parent {
                // SAFETY: as above.
                unsafe { libc::_exit(0) };
            }
            continue;
        }
        seen = now;
        answers.fetch_add(1, Ordering::AcqRel);
        futex_wake(answers);
    }
}

/// The forked children, killed and reaped however the floor ends.
struct Children(Vec<libc::pid_t>);

impl Drop for Children {
    fn drop(&mut self) {
        for &pid in &self.0 {
            // SAFETY: our own children, not reaped yet.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        for &pid in &self.0 {
            // SAFETY: as above.
            unsafe { libc::waitpid(pid, std::ptr::null_mut(), 0) };
        }
    }
}

/// Wake `agents` forked processes step by step, each step's groups of the sizes in
/// `steps` one after the other (a group's wake-ups at once, then its answers awaited):
/// the wall time of the timed steps, seconds. One untimed round of every process comes
/// first.
pub fn futex_floor(agents: usize, steps: &[Vec<usize>]) -> anyhow::Result<f64> {
    let shared = SharedWords::new(agents + 1)?;
    let words = shared.words();
    let (mine, answers) = words.split_at(agents);
    let answers = &answers[0];
    // SAFETY: a plain system call.
    let parent = unsafe { libc::getpid() };
    let mut children = Children(Vec::with_capacity(agents));
    for word in mine {
        // SAFETY: the child runs `child` only (atomics and raw system calls), never
        // returns into this process's code, and ends with `_exit`.
        match unsafe { libc::fork() } {
            -1 => return Err(std::io::Error::last_os_error()).context("forking a floor process"),
            0 => child(word, answers, parent),
            pid => children.0.push(pid),
        }
    }
    let mut seq = 0;
    let mut expected = 0;
    let mut round = |sizes: &[usize], seq: u32| -> anyhow::Result<()> {
        let mut first = 0;
        for &size in sizes {
            let group = mine
                .get(first..first + size)
                .context("a group beyond the processes")?;
            first += size;
            for word in group {
                word.store(seq, Ordering::Release);
                futex_wake(word);
            }
            expected += size as u32;
            let deadline = Instant::now() + GROUP_DEADLINE;
            loop {
                let got = answers.load(Ordering::Acquire);
                if got >= expected {
                    break;
                }
                let now = Instant::now();
                if now >= deadline {
                    bail!(
                        "the futex floor: {} process(es) did not answer",
                        expected - got
                    );
                }
                futex_wait(answers, got, deadline - now);
            }
        }
        Ok(())
    };
    seq += 1;
    round(&[agents], seq)?;
    let started = Instant::now();
    for sizes in steps {
        seq += 1;
        round(sizes, seq)?;
    }
    let floor_s = started.elapsed().as_secs_f64();
    for word in mine {
        word.store(LEAVE, Ordering::Release);
        futex_wake(word);
    }
    for &pid in &children.0 {
        // SAFETY: our own child, told to leave.
        unsafe { libc::waitpid(pid, std::ptr::null_mut(), 0) };
    }
    children.0.clear();
    Ok(floor_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_process_answers_every_step_and_a_group_beyond_them_is_refused() {
        let floor_s = futex_floor(5, &[vec![2, 3], vec![5], vec![1, 1, 3]]).expect("the floor");
        assert!(floor_s > 0.0);
        // Groups larger than the processes are refused, not run past the end.
        assert!(futex_floor(2, &[vec![3]]).is_err());
    }
}
