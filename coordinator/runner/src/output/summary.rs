//! `summary.json`: the run's figures ([`Summary`]), its timing ([`Timing`]) and the last
//! step, written as [`SummaryFile`]; the part `coordinator render` reads back is
//! [`SummaryRead`].
//!
//! Two types, not one: [`Summary`] (in `shared::run::record`) is written from a run and cannot
//! be read back whole (its replans and waits hold `&'static str` names, and a figure
//! that is infinite, such as `min_clearance_m` with nothing ever near, is written as
//! `null`). [`SummaryRead`] holds the keys render needs under the names [`Summary`]
//! gives them, each optional so that older and hand-written files load; the tests write
//! a [`SummaryFile`] and read it back as a [`SummaryRead`].

use serde::{Deserialize, Serialize};
use shared::run::record::{FaultKind, HeadingSummary, Summary};

use crate::stats::Distribution;

/// Timing figures of a multi-process run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timing {
    /// Turn latency (world published to move received), microseconds.
    pub turn_latency_us: Distribution,
    /// Agent compute time per turn, microseconds.
    pub compute_us: Distribution,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// From the start of the run to the last ready handshake, seconds.
    pub startup_s: f64,
    /// Where `startup_s` went, phase by phase.
    pub startup_phases_s: StartupPhases,
    /// Steps per second of the step loop (start-up excluded).
    pub steps_per_s: f64,
    /// Resident set size of the agent processes at the end of the run, KiB.
    pub agent_rss_kib: Distribution,
    /// Proportional set size of the agent processes at the end of the run (shared pages
    /// counted as their share), KiB.
    pub agent_pss_kib: Distribution,
    /// CPU time of each agent process over its whole life (start-up, every turn, every
    /// wait), seconds.
    pub agent_cpu_s: Distribution,
    /// The groups of turns (one agent each with sequential turns).
    pub groups: GroupTiming,
}

/// How the groups of turns used the machine: a group's agents are granted at once and
/// compute in parallel, so its wall time is at best its agents' compute spread over the
/// cores.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GroupTiming {
    /// Agents granted a turn per group.
    pub size: Distribution,
    /// Wall time of a group, from its first grant to its last answer judged, microseconds.
    pub wall_us: Distribution,
    /// The cores of this machine.
    pub cores: usize,
    /// The share of the machine's CPU time that was idle during the step loop (from
    /// `/proc/stat`: another program's work counts as busy); `None` when it could not be
    /// read or the loop was shorter than a clock tick.
    pub loop_idle_share: Option<f64>,
}

/// The phases of a run's start-up, in seconds; they add up to `startup_s`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StartupPhases {
    /// The run's private folder, the mission file, every agent's shared-memory
    /// services, the log (`spawn` not included).
    pub prepare: f64,
    /// Starting the agent processes (`posix_spawn`, one after the other). They start
    /// once the mission file exists and wait behind a gate until their services do
    /// (over a network, after the router: once the services exist).
    pub spawn: f64,
    /// Waiting for the agents' ready handshakes (each reads and checks the mission and
    /// opens its ports meanwhile).
    pub handshakes: f64,
    /// Checking the agents' services for processes that have no business there.
    pub intruder_scan: f64,
}

/// `summary.json` as written: the run's figures and its timing, side by side.
#[derive(Serialize)]
pub struct SummaryFile<'a> {
    /// The run's figures.
    #[serde(flatten)]
    pub summary: &'a Summary,
    /// Its timing.
    #[serde(flatten)]
    pub timing: &'a Timing,
    /// Its heading figures, when its agents have a heading (no keys for a holonomic run).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub headings: Option<HeadingSummary>,
    /// The step the run stopped after (the last one when it completed).
    pub last_step: usize,
    /// Log lines of other crates (Zenoh's, say, under a flood of junk connections) this
    /// process dropped beyond their budget ([`wire::logging`]).
    pub log_lines_suppressed: u64,
}

/// The keys of `summary.json` that `coordinator render` reads (named as [`Summary`]
/// names them); every other key is ignored.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub struct SummaryRead {
    /// Every fault, in the order the run recorded them.
    #[serde(default)]
    pub faults: Vec<FaultRecord>,
    /// Whether the run went through the whole centre path (`None`: not recorded).
    #[serde(default)]
    pub completed: Option<bool>,
    /// For each unknown obstacle, the step it became known (`None`: never).
    #[serde(default)]
    pub unknown_found_at_step: Vec<Option<usize>>,
}

/// A fault as `summary.json` lists it (the keys of [`shared::run::record::Fault`] render
/// reads).
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct FaultRecord {
    /// The agent.
    pub agent: usize,
    /// The step it happened in.
    pub step: usize,
    /// What happened.
    pub kind: FaultKind,
    /// Details for people.
    #[serde(default)]
    pub detail: String,
}

#[cfg(test)]
mod tests {
    use shared::run::record::Fault;
    use shared::world::scenario::Scenario;

    use super::*;

    #[test]
    fn what_is_written_reads_back_as_the_run_recorded_it() {
        let scenario = Scenario::paper();
        let mut run = shared::run::simulate::simulate(&scenario).expect("the paper runs");
        run.faults = FaultKind::ALL
            .iter()
            .enumerate()
            .map(|(i, &kind)| Fault {
                agent: i % scenario.agents.len(),
                step: 3 * i,
                kind,
                detail: format!("fault {i} \"quoted\""),
                detection_ms: (kind == FaultKind::Dead).then_some(1.5),
            })
            .collect();
        run.completed = false;
        run.course.found_at = vec![Some(4), None, Some(0)];
        let summary = run.summary();
        let file = SummaryFile {
            summary: &summary,
            timing: &Timing::default(),
            headings: None,
            last_step: 17,
            log_lines_suppressed: 3,
        };
        let json = serde_json::to_string_pretty(&file).expect("json");
        let read: SummaryRead = serde_json::from_str(&json).expect("read back");
        assert_eq!(read.completed, Some(summary.completed));
        assert_eq!(read.unknown_found_at_step, summary.unknown_found_at_step);
        assert_eq!(read.faults.len(), summary.faults.len());
        for (r, f) in read.faults.iter().zip(&summary.faults) {
            assert_eq!(
                (r.agent, r.step, r.kind, &r.detail),
                (f.agent, f.step, f.kind, &f.detail)
            );
        }
        let value: serde_json::Value = serde_json::from_str(&json).expect("json");
        assert_eq!(value["last_step"], 17);
        assert_eq!(value["faults"][4]["kind"], "dead");
    }

    #[test]
    fn a_file_with_none_of_the_keys_reads_as_empty() {
        let read: SummaryRead = serde_json::from_str(r#"{"scenario": "x"}"#).expect("read");
        assert_eq!(read, SummaryRead::default());
        let e = serde_json::from_str::<SummaryRead>(
            r#"{"faults": [{"agent": 0, "step": 1, "kind": "asleep"}]}"#,
        )
        .expect_err("an unknown fault kind");
        assert!(e.to_string().contains("asleep"), "{e}");
    }
}
