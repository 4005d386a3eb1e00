//! CPU time of processes, from `/proc`: shows that idle agents block instead of polling.

use std::time::{Duration, Instant};

use serde::Serialize;

/// Clock ticks per second of `/proc/PID/stat` times (`USER_HZ`, fixed at 100 by the
/// Linux ABI whatever the kernel's `HZ`).
const USER_HZ: f64 = 100.0;

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

#[derive(Clone, Copy)]
struct Snapshot {
    ticks: u64,
    run_ns: u64,
    switches: u64,
}

fn snapshot(pid: u32) -> Option<Snapshot> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // pid (comm) state ppid ...: fields after the command, from `state` (field 3) on.
    let rest: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let utime: u64 = rest.get(11)?.parse().ok()?;
    let stime: u64 = rest.get(12)?.parse().ok()?;
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
        ticks: utime + stime,
        run_ns,
        switches,
    })
}

impl IdleCpu {
    /// Sleep `hold` and measure the CPU time processes `pids` used meanwhile.
    pub fn measure(pids: &[u32], hold: Duration) -> Self {
        let before: Vec<Option<Snapshot>> = pids.iter().map(|&p| snapshot(p)).collect();
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
