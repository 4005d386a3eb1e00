//! The benchmark report: JSON for scripts, a table for people.

use std::fmt::Write as _;

use serde::Serialize;

use super::split::{EchoSplit, OverheadSplit};
use runner::procfs::IdleCpu;
use runner::stats::Distribution;

/// The whole report (`{"runs": [...], ...}`).
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// One entry per formation size.
    pub runs: Vec<RunReport>,
    /// `release` or `debug`: only release figures mean anything.
    pub build: &'static str,
    /// CPUs this process may run on.
    pub cpus: usize,
    /// One-minute load average at the start (how busy the machine was).
    pub load_average_1m: Option<f64>,
    /// Recorded round trips per ping-pong (after the warm-up).
    pub round_trips: usize,
    /// Round trips made and dropped (the first few of every block), per mechanism.
    pub warmup_round_trips: usize,
    /// The histogram, if written.
    pub histogram_svg: Option<String>,
    /// Sequential against parallel turns (`--turns-scenario`); absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turns: Option<super::turns::TurnsReport>,
    /// The step loop against `simulate()`, blocking and spinning (`--loop-scenario`);
    /// absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub loops: Option<super::loops::LoopsReport>,
    /// The step loop with the run log and without (`--log-scenario`); absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log_cost: Option<super::log_cost::LogCostReport>,
    /// The runtime against the number of agents (`--scale`); absent without it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<super::scale::ScaleReport>,
}

/// The figures of one formation size.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Agents (one process each).
    pub agents: usize,
    /// Steps of the path.
    pub steps: usize,
    /// Turns whose samples were dropped as warm-up (every agent's first turn: its
    /// controller is built then and its pages are touched for the first time).
    pub warmup_turns: usize,
    /// Turn latency: turn rung to move received, microseconds.
    pub turn_us: Distribution,
    /// The agents' compute time per turn, microseconds.
    pub compute_us: Distribution,
    /// Turn latency minus compute, per turn, microseconds.
    pub ipc_overhead_us: Distribution,
    /// Where the overhead goes, cut at the agent's timestamps.
    pub overhead_split: OverheadSplit,
    /// The echo: the same agents answering empty turns in turn order (waking a process
    /// that last ran N turns ago, nothing else), microseconds.
    pub echo_us: Distribution,
    /// The echo's two wake-ups.
    pub echo_split: EchoSplit,
    /// iceoryx2 publish-subscribe round trip between two processes, rung each way as the
    /// run's turns are ([`Self::floor_rung_by`]), microseconds.
    pub floor_us: Distribution,
    /// How the floor's round trips were rung: `doorbell` or `event` (`--wake`).
    pub floor_rung_by: &'static str,
    /// Unix domain socket round trip with turn-sized payloads, microseconds.
    pub uds_us: Distribution,
    /// Socket request size (a serialized world), bytes.
    pub uds_request_bytes: usize,
    /// Socket reply size (a serialized move), bytes.
    pub uds_reply_bytes: usize,
    /// `ipc_overhead_us.p50 / floor_us.p50`.
    pub overhead_vs_floor_p50: f64,
    /// `ipc_overhead_us.p99 / floor_us.p99`.
    pub overhead_vs_floor_p99: f64,
    /// `ipc_overhead_us.p50 / uds_us.p50`.
    pub overhead_vs_uds_p50: f64,
    /// `ipc_overhead_us.p50 / echo_us.p50`: the share of the overhead that is not the
    /// wake-up of N processes in turn.
    pub overhead_vs_echo_p50: f64,
    /// `ipc_overhead_us.p99 / echo_us.p99`.
    pub overhead_vs_echo_p99: f64,
    /// CPU time of all agents together while held idle (utime + stime), seconds.
    pub agent_idle_cpu_s: f64,
    /// The idle probe in detail.
    pub agent_idle: IdleCpu,
    /// From the first spawn to the last ready handshake, seconds.
    pub startup_s: f64,
    /// Resident set size of the agent processes at the end of the run, KiB.
    pub agent_rss_kib: Distribution,
    /// Faults during the run (missed deadlines, rejected moves...): 0 for a clean run.
    pub faults: usize,
    /// Wall time of the multi-process run, seconds.
    pub wall_s: f64,
    /// The run's iceoryx2 prefix.
    pub prefix: String,
    /// The floor measurement's iceoryx2 prefix.
    pub floor_prefix: String,
    /// Blocks the ping-pongs were split into, spread between the steps.
    pub floor_blocks: usize,
    /// The targets (reported, never asserted).
    pub targets: Targets,
}

/// The latency targets and whether this run met them.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Targets {
    /// Overhead p50 within 1.5x the floor p50.
    pub overhead_p50_within_1_5x_floor: bool,
    /// Overhead p99 within 3x the floor p99.
    pub overhead_p99_within_3x_floor: bool,
    /// Overhead p50 below the socket round trip p50.
    pub overhead_p50_below_uds_p50: bool,
    /// No agent CPU time while idle (at /proc/PID/stat resolution).
    pub idle_cpu_zero: bool,
}

impl Targets {
    /// Evaluate the targets for `r`.
    pub fn of(r: &RunReport) -> Self {
        Self {
            overhead_p50_within_1_5x_floor: r.overhead_vs_floor_p50 <= 1.5,
            overhead_p99_within_3x_floor: r.overhead_vs_floor_p99 <= 3.0,
            overhead_p50_below_uds_p50: r.ipc_overhead_us.p50 < r.uds_us.p50,
            idle_cpu_zero: r.agent_idle_cpu_s == 0.0,
        }
    }
}

fn yes(b: bool) -> &'static str {
    if b { "met" } else { "NOT met" }
}

/// The human table.
pub fn table(report: &Report) -> String {
    let mut s = String::new();
    let load = report
        .load_average_1m
        .map_or(String::new(), |l| format!(", load average {l:.2}"));
    if report.runs.is_empty() {
        let _ = writeln!(
            s,
            "coordinator bench: {} build, {} CPUs{load}",
            report.build, report.cpus
        );
    } else {
        let _ = writeln!(
            s,
            "coordinator bench: {} build, {} CPUs{load}; ping-pongs: {} round trips after {} warm-up",
            report.build, report.cpus, report.round_trips, report.warmup_round_trips
        );
    }
    for r in &report.runs {
        let _ = writeln!(
            s,
            "\nN = {} agents, {} steps: {} turns measured ({} warm-up turns dropped), {} faults",
            r.agents, r.steps, r.turn_us.count, r.warmup_turns, r.faults
        );
        let _ = writeln!(
            s,
            "  {:<34}{:>9}{:>9}{:>9}{:>9}{:>9}",
            "microseconds", "p50", "p90", "p99", "p99.9", "max"
        );
        let row = |s: &mut String, name: &str, d: &Distribution| {
            let _ = writeln!(
                s,
                "  {:<34}{:>9.1}{:>9.1}{:>9.1}{:>9.1}{:>9.1}",
                name, d.p50, d.p90, d.p99, d.p999, d.max
            );
        };
        row(&mut s, "turn latency", &r.turn_us);
        row(&mut s, "  agent compute", &r.compute_us);
        row(
            &mut s,
            "  IPC overhead (turn - compute)",
            &r.ipc_overhead_us,
        );
        let split = &r.overhead_split;
        row(&mut s, "    waking the agent", &split.to_agent_us);
        row(
            &mut s,
            "    agent reads world, writes move",
            &split.agent_io_us,
        );
        row(
            &mut s,
            "    waking the coordinator",
            &split.to_coordinator_us,
        );
        row(&mut s, "echo: same agents, empty turns", &r.echo_us);
        row(&mut s, "    waking the agent", &r.echo_split.to_agent_us);
        row(
            &mut s,
            "    waking the coordinator",
            &r.echo_split.to_coordinator_us,
        );
        row(
            &mut s,
            &format!("iceoryx2 floor (2 processes, {})", r.floor_rung_by),
            &r.floor_us,
        );
        row(
            &mut s,
            &format!(
                "Unix socket ({} B / {} B)",
                r.uds_request_bytes, r.uds_reply_bytes
            ),
            &r.uds_us,
        );
        let t = &r.targets;
        let _ = writeln!(
            s,
            "  overhead / floor: p50 {:.2}x (target <= 1.5x: {}), p99 {:.2}x (target <= 3x: {})",
            r.overhead_vs_floor_p50,
            yes(t.overhead_p50_within_1_5x_floor),
            r.overhead_vs_floor_p99,
            yes(t.overhead_p99_within_3x_floor)
        );
        let _ = writeln!(
            s,
            "  overhead / Unix socket p50: {:.2}x (target < 1: {})",
            r.overhead_vs_uds_p50,
            yes(t.overhead_p50_below_uds_p50)
        );
        let _ = writeln!(
            s,
            "  overhead / echo: p50 {:.2}x, p99 {:.2}x (1x: the overhead is the wake-up of {} processes in turn)",
            r.overhead_vs_echo_p50, r.overhead_vs_echo_p99, r.agents
        );
        let i = &r.agent_idle;
        let _ = writeln!(
            s,
            "  agents idle {:.2} s: CPU {:.2} s (/proc stat; scheduler: {:.4} s, {} wake-ups in {} processes; target 0: {})",
            i.held_s,
            r.agent_idle_cpu_s,
            i.exact_cpu_s,
            i.wakeups,
            i.processes,
            yes(t.idle_cpu_zero)
        );
        let _ = writeln!(
            s,
            "  start-up {:.3} s; agent RSS p50 {:.0} KiB, max {:.0} KiB; run wall time {:.2} s",
            r.startup_s, r.agent_rss_kib.p50, r.agent_rss_kib.max, r.wall_s
        );
    }
    if let Some(t) = &report.turns {
        s.push_str(&super::turns::table(t));
    }
    if let Some(l) = &report.log_cost {
        s.push_str(&super::log_cost::table(l));
    }
    if let Some(l) = &report.loops {
        s.push_str(&super::loops::table(l));
    }
    if let Some(r) = &report.scale {
        s.push_str(&super::scale::table(r));
        if let Some(svg) = &r.plot_svg {
            let _ = writeln!(s, "scale plot: {svg}");
        }
    }
    if let Some(svg) = &report.histogram_svg {
        let _ = writeln!(s, "\nhistogram: {svg}");
    }
    s
}
