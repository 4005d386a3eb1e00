//! Everything the coordinator reads from `/proc`, in one place: processes (state, parent,
//! group, start time, CPU time), their environment and command line, this process's open
//! descriptors, memory, the load average, and the CPU time of idle agents ([`IdleCpu`]).
//! Every reader returns `None` (or nothing) for what it cannot read: a process that is
//! gone, another user's.

use std::time::{Duration, Instant};

use serde::Serialize;

/// Clock ticks per second of `/proc/PID/stat` times (`USER_HZ`, fixed at 100 by the
/// Linux ABI whatever the kernel's `HZ`).
const USER_HZ: f64 = 100.0;

/// What `/proc/PID/stat` says about a process.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProcStat {
    /// The process id.
    pub pid: u32,
    /// `R`, `S`, `D`, `Z` (zombie), ...
    pub state: u8,
    /// The parent's process id.
    pub ppid: u32,
    /// The process group id.
    pub pgid: u32,
    /// CPU time so far, user and system (`utime + stime`), in clock ticks (`USER_HZ`, 100 a second).
    pub cpu_ticks: u64,
    /// Start time since boot, in clock ticks: with the pid, names one process for good.
    pub start: u64,
}

impl ProcStat {
    /// Process `pid`'s status, if it exists.
    pub fn read(pid: u32) -> Option<Self> {
        let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
        // pid (comm) state ppid pgrp ...: fields from `state` (field 3) on; the command
        // may hold spaces and parentheses, the last `)` ends it.
        let rest: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
        let utime: u64 = rest.get(11)?.parse().ok()?;
        let stime: u64 = rest.get(12)?.parse().ok()?;
        Some(Self {
            pid,
            state: *rest.first()?.as_bytes().first()?,
            ppid: rest.get(1)?.parse().ok()?,
            pgid: rest.get(2)?.parse().ok()?,
            cpu_ticks: utime + stime,
            start: rest.get(19)?.parse().ok()?,
        })
    }

    /// Whether the process is dead and not yet reaped.
    pub fn zombie(&self) -> bool {
        matches!(self.state, b'Z' | b'X')
    }
}

/// Every user id some live process runs under now (real, effective, saved or file
/// system), as `/proc/PID/status` says (a process whose user changed is owned by root in
/// `/proc`, so its folder's owner would not tell).
pub fn user_ids_in_use() -> std::collections::HashSet<u32> {
    let mut uids = std::collections::HashSet::new();
    for pid in all_pids() {
        let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else {
            continue;
        };
        if let Some(line) = status.lines().find_map(|l| l.strip_prefix("Uid:")) {
            uids.extend(
                line.split_whitespace()
                    .filter_map(|u| u.parse::<u32>().ok()),
            );
        }
    }
    uids
}

/// The process ids listed in `/proc` now.
fn all_pids() -> Vec<u32> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse().ok())
        .collect()
}

/// Every process in `/proc` now.
pub fn all_processes() -> Vec<ProcStat> {
    all_pids().into_iter().filter_map(ProcStat::read).collect()
}

/// Whether process `pid` exists (zombie or not).
pub fn process_exists(pid: u32) -> bool {
    std::path::Path::new(&format!("/proc/{pid}")).exists()
}

/// Whether process `pid`'s environment holds exactly `entry` (`NAME=value`). False if it
/// cannot be read: a zombie's, another user's.
pub fn environment_has(pid: u32, entry: &[u8]) -> bool {
    std::fs::read(format!("/proc/{pid}/environ"))
        .is_ok_and(|env| env.split(|&b| b == 0).any(|e| e == entry))
}

/// Every live process of run `prefix` but this one: not a zombie, with
/// [`wire::RUN_ENV`]`=prefix` in its environment (agents, relays and what they started).
pub fn live_processes_of_run(prefix: &str) -> Vec<ProcStat> {
    let me = std::process::id();
    let marker = format!("{}={prefix}", wire::RUN_ENV).into_bytes();
    all_processes()
        .into_iter()
        .filter(|p| p.pid != me && !p.zombie() && environment_has(p.pid, &marker))
        .collect()
}

/// Whether some process's command line (`/proc/PID/cmdline`: arguments ended by NUL)
/// holds `needle`.
pub fn any_command_line_holds(needle: &[u8]) -> bool {
    all_pids().into_iter().any(|pid| {
        std::fs::read(format!("/proc/{pid}/cmdline"))
            .is_ok_and(|c| c.windows(needle.len()).any(|w| w == needle))
    })
}

/// The file descriptors this process has open (`/proc/self/fd`).
pub fn open_fds() -> Vec<i32> {
    let Ok(dir) = std::fs::read_dir("/proc/self/fd") else {
        return Vec::new();
    };
    dir.flatten()
        .filter_map(|e| e.file_name().to_string_lossy().parse().ok())
        .collect()
}

/// A process's memory, KiB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Memory {
    /// Resident set size.
    pub rss_kib: f64,
    /// Proportional set size: each page it shares counted as its share; what one more
    /// such process costs the machine.
    pub pss_kib: f64,
}

/// Process `pid`'s memory, both figures from one read of `/proc/PID/smaps_rollup` (its
/// `Rss` and `Pss` lines).
pub fn memory(pid: u32) -> Option<Memory> {
    let rollup = std::fs::read_to_string(format!("/proc/{pid}/smaps_rollup")).ok()?;
    let kib = |key: &str| -> Option<f64> {
        let line = rollup.lines().find(|l| l.starts_with(key))?;
        line.split_whitespace().nth(1)?.parse().ok()
    };
    Some(Memory {
        rss_kib: kib("Rss:")?,
        pss_kib: kib("Pss:")?,
    })
}

/// The CPU time process `pid` has used so far, from the scheduler's nanosecond counter
/// (`/proc/PID/schedstat`; its threads included), seconds.
pub fn cpu_s(pid: u32) -> Option<f64> {
    let schedstat = std::fs::read_to_string(format!("/proc/{pid}/schedstat")).ok()?;
    let ns: u64 = schedstat.split_whitespace().next()?.parse().ok()?;
    Some(ns as f64 * 1e-9)
}

/// The machine's CPU time so far, summed over its cores, in clock ticks: `(idle, total)`
/// (the `cpu` line of `/proc/stat`; idle counts `idle` and `iowait`, total the first
/// eight fields, guest time being counted in user time already).
pub fn machine_cpu_ticks() -> Option<(u64, u64)> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    let fields: Vec<u64> = stat
        .lines()
        .next()?
        .strip_prefix("cpu ")?
        .split_whitespace()
        .map(|f| f.parse().ok())
        .collect::<Option<_>>()?;
    let idle = fields.get(3)? + fields.get(4)?;
    Some((idle, fields.iter().take(8).sum()))
}

/// The share of the machine's CPU time that was idle between two readings of
/// [`machine_cpu_ticks`] (`None` when no tick passed).
pub fn idle_share(from: (u64, u64), to: (u64, u64)) -> Option<f64> {
    let total = to.1.checked_sub(from.1).filter(|&t| t > 0)?;
    let idle = to.0.checked_sub(from.0)?;
    Some(idle as f64 / total as f64)
}

/// The machine's load average over the last minute.
pub fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// What a set of processes did while held idle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct IdleCpu {
    /// How long they were held idle, seconds.
    pub held_s: f64,
    /// Processes measured.
    pub processes: usize,
    /// Their CPU time meanwhile, utime + stime from `/proc/PID/stat`, summed, seconds
    /// (10 ms resolution).
    pub cpu_s: f64,
    /// The same from the scheduler's nanosecond counter (`/proc/PID/schedstat`), seconds.
    pub exact_cpu_s: f64,
    /// How often they were woken meanwhile (context switches, summed): the liveness
    /// timeout of the blocking wait, nothing else, when nobody polls.
    pub wakeups: u64,
}

/// How long processes must go without a context switch to count as settled.
const SETTLE: Duration = Duration::from_millis(50);
/// How long to wait at most for processes to settle before a hold.
const SETTLE_LIMIT: Duration = Duration::from_secs(1);

#[derive(Clone, Copy)]
struct Snapshot {
    ticks: u64,
    run_ns: u64,
    switches: u64,
}

fn snapshot(pid: u32) -> Option<Snapshot> {
    let ticks = ProcStat::read(pid)?.cpu_ticks;
    let run_ns = std::fs::read_to_string(format!("/proc/{pid}/schedstat"))
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0);
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let switches = status
        .lines()
        .filter(|l| l.contains("ctxt_switches:"))
        .filter_map(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        .sum();
    Some(Snapshot {
        ticks,
        run_ns,
        switches,
    })
}

impl IdleCpu {
    /// Sleep `hold` and measure the CPU time processes `pids` used meanwhile.
    ///
    /// The hold starts once they have settled: a process that has just said it is ready
    /// may still be on its way into its wait, and the context switch of falling asleep is
    /// not a wake-up. Settled means no context switch in 50 ms, `SETTLE` (given up after
    /// 1 s, `SETTLE_LIMIT`).
    pub fn measure(pids: &[u32], hold: Duration) -> Self {
        let switches = |snaps: &[Option<Snapshot>]| -> Vec<Option<u64>> {
            snaps.iter().map(|s| s.map(|s| s.switches)).collect()
        };
        let settling = Instant::now();
        let mut before: Vec<Option<Snapshot>> = pids.iter().map(|&p| snapshot(p)).collect();
        while settling.elapsed() < SETTLE_LIMIT {
            std::thread::sleep(SETTLE);
            let now: Vec<Option<Snapshot>> = pids.iter().map(|&p| snapshot(p)).collect();
            let quiet = switches(&now) == switches(&before);
            before = now;
            if quiet {
                break;
            }
        }
        let started = Instant::now();
        std::thread::sleep(hold);
        let held_s = started.elapsed().as_secs_f64();
        let mut out = Self {
            held_s,
            ..Self::default()
        };
        for (&pid, b) in pids.iter().zip(before) {
            let (Some(b), Some(a)) = (b, snapshot(pid)) else {
                continue;
            };
            out.processes += 1;
            out.cpu_s += a.ticks.saturating_sub(b.ticks) as f64 / USER_HZ;
            out.exact_cpu_s += a.run_ns.saturating_sub(b.run_ns) as f64 / 1e9;
            out.wakeups += a.switches.saturating_sub(b.switches);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn this_process_shares_no_more_than_it_holds() {
        let m = memory(std::process::id()).expect("our own smaps_rollup");
        assert!(m.pss_kib > 0.0 && m.pss_kib <= m.rss_kib, "{m:?}");
        assert_eq!(memory(u32::MAX), None, "no such process");
    }

    #[test]
    fn the_machine_is_idle_while_this_thread_sleeps_and_busy_while_it_spins() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let before = machine_cpu_ticks().expect("/proc/stat");
        let spin_until = std::time::Instant::now() + Duration::from_millis(300);
        while std::time::Instant::now() < spin_until {
            std::hint::spin_loop();
        }
        let after = machine_cpu_ticks().expect("/proc/stat");
        let idle = idle_share(before, after).expect("ticks passed in 300 ms");
        // One core of `cores` spun the whole time: at most the others were idle.
        assert!((0.0..=1.0).contains(&idle), "{idle}");
        assert!(
            idle <= 1.0 - 0.5 / cores as f64,
            "{idle} with {cores} cores"
        );
        assert_eq!(idle_share(after, after), None, "no tick, no share");
        assert_eq!(idle_share((5, 10), (7, 20)), Some(0.2));
    }

    #[test]
    fn a_sleeping_child_uses_no_cpu() {
        let mut child = std::process::Command::new("sleep")
            .arg("5")
            .spawn()
            .expect("sleep");
        std::thread::sleep(Duration::from_millis(50));
        let idle = IdleCpu::measure(&[child.id()], Duration::from_millis(200));
        let _ = child.kill();
        let _ = child.wait();
        assert_eq!(idle.processes, 1);
        assert_eq!(idle.cpu_s, 0.0);
        assert!(idle.exact_cpu_s < 0.01, "{idle:?}");
    }
}
