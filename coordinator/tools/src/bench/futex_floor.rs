//! The wake-up floor of the operating system itself (`bench --scale`): N forked
//! processes rung through doorbells of their own ([`wire::Doorbells`]: a futex word
//! each, and an answer counter) group by group in the group sizes a run's steps had,
//! each answering by counting itself. No iceoryx2 channel, no sample: the least that
//! waking N processes once a step can cost on this machine, to set beside the same
//! wake-ups in the real run (the `wake_floor_s` of the scale report).
//!
//! A forked child runs only atomics and raw system calls (the doorbells' futex calls,
//! `prctl`, `getppid`, `_exit`), which are safe after `fork` in a process with threads;
//! it dies with this process (`PR_SET_PDEATHSIG`) and leaves on its own when told or
//! when its parent is gone.

use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use wire::{Doorbells, EVENT_QUIT, EVENT_TURN, RunPrefix, RunRoot, WakeBy};

/// How long the floor waits for a group's answers before it gives up.
const GROUP_DEADLINE: Duration = Duration::from_secs(5);

/// How long a child sleeps before it looks whether its parent is still there.
const CHILD_LIVENESS: Duration = Duration::from_secs(1);

/// A child's life as agent `agent`: sleep on its doorbell, count itself at each turn
/// rung, leave when told to quit or when the parent is gone. Only atomics and raw
/// system calls.
fn child(doorbells: &Doorbells, agent: usize, parent: libc::pid_t) -> ! {
    // SAFETY: async-signal-safe system calls only.
    unsafe {
        // Not the parent's handlers: an interrupt ends a child at once.
        libc::signal(libc::SIGINT, libc::SIG_DFL);
        libc::signal(libc::SIGTERM, libc::SIG_DFL);
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
        if libc::getppid() != parent {
            libc::_exit(0);
        }
    }
    loop {
        let rung = match doorbells.wait(agent, CHILD_LIVENESS) {
            Ok((rung, _)) => rung,
            // SAFETY: leaving without running anything of the parent's.
            Err(_) => unsafe { libc::_exit(1) },
        };
        if rung & (1 << EVENT_QUIT) != 0 {
            // SAFETY: as above.
            unsafe { libc::_exit(0) };
        }
        if rung & (1 << EVENT_TURN) != 0 {
            doorbells.answer();
            continue;
        }
        // Nothing rung: a timeout (or a wake-up for nothing); is the parent still there?
        // SAFETY: plain system calls.
        unsafe {
            if libc::getppid() != parent {
                libc::_exit(0);
            }
        }
    }
}

/// The forked children, killed and reaped however the floor ends.
struct Children(Vec<libc::pid_t>);

impl Children {
    /// Reap every child (each told to leave, or killed), however often a signal
    /// interrupts the wait.
    fn reap(&mut self) {
        for pid in self.0.drain(..) {
            // SAFETY: our own child, not reaped yet.
            while unsafe { libc::waitpid(pid, std::ptr::null_mut(), 0) } == -1
                && std::io::Error::last_os_error().raw_os_error() == Some(libc::EINTR)
            {}
        }
    }
}

impl Drop for Children {
    fn drop(&mut self) {
        for &pid in &self.0 {
            // SAFETY: our own children, not reaped yet.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        self.reap();
    }
}

/// Ring `agents` forked processes step by step, each step's groups of the sizes in
/// `steps` one after the other (a group's rings at once, then its answers awaited): the
/// wall time of the timed steps, seconds. One untimed round of every process comes
/// first.
pub fn futex_floor(agents: usize, steps: &[Vec<usize>]) -> anyhow::Result<f64> {
    // Doorbells of their own, in a private folder of their own, removed at the end.
    let prefix = RunPrefix::new_random()?.to_string();
    let _root = RunRoot::create(&prefix).context("the floor's folder")?;
    let doorbells =
        Doorbells::create(&prefix, agents, WakeBy::Doorbells).context("the floor's doorbells")?;
    // SAFETY: a plain system call.
    let parent = unsafe { libc::getpid() };
    let mut children = Children(Vec::with_capacity(agents));
    for agent in 0..agents {
        // SAFETY: the child runs `child` only (atomics and raw system calls on the
        // inherited shared mapping), never returns into this process's code, and ends
        // with `_exit`.
        match unsafe { libc::fork() } {
            -1 => return Err(std::io::Error::last_os_error()).context("forking a floor process"),
            0 => child(&doorbells, agent, parent),
            pid => children.0.push(pid),
        }
    }
    let mut expected = doorbells.answers();
    let mut round = |sizes: &[usize]| -> anyhow::Result<()> {
        let mut first = 0;
        for &size in sizes {
            let group = first..first + size;
            if group.end > agents {
                bail!("a group of the floor beyond its {agents} processes");
            }
            first += size;
            for agent in group {
                doorbells.ring(agent, EVENT_TURN)?;
            }
            expected = expected.wrapping_add(size as u32);
            let deadline = Instant::now() + GROUP_DEADLINE;
            loop {
                let got = doorbells.answers();
                if got == expected {
                    break;
                }
                let now = Instant::now();
                if now >= deadline {
                    bail!(
                        "the futex floor: {} process(es) did not answer",
                        expected.wrapping_sub(got)
                    );
                }
                doorbells.wait_answer(got, deadline - now);
            }
        }
        Ok(())
    };
    round(&[agents])?;
    let started = Instant::now();
    for sizes in steps {
        round(sizes)?;
    }
    let floor_s = started.elapsed().as_secs_f64();
    for agent in 0..agents {
        doorbells.ring(agent, EVENT_QUIT)?;
    }
    children.reap();
    Ok(floor_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_process_answers_every_step_and_a_group_beyond_them_is_refused() {
        let floor_s = futex_floor(5, &[vec![2, 3], vec![5], vec![1, 1, 3]]).expect("the floor");
        assert!(floor_s > 0.0);
        assert!(futex_floor(2, &[vec![3]]).is_err());
    }
}
