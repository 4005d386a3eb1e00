//! Late agents are named and stopped: one that misses two turns of every three (never
//! three in a row) is `hung` once it has missed 3 of its last 10; one that answers every
//! turn in time but later than the slow bound (by default a fifth of the deadline; half
//! for a car) is `slow` at its third late answer. Either is killed and frozen, the others go on
//! untouched, and the fault is against the late agent alone. So one late agent costs a
//! run at most 3 turn deadlines of waiting (750 ms at the default 250 ms) before it is
//! stopped, whatever it does (a replacement with `--respawn` as much again): what it can
//! add to a run is bounded by that, not by the run's length.

use crate::support;

use std::path::Path;

use serde_json::Value;
use support::{assert_nothing_left, assert_safe, faults_of, run_to_end, summary};

/// The late agent (the paper example has agents 0 to 5).
const LATE: u64 = 3;

/// Run the paper example with agent [`LATE`] in `mode`, a turn deadline of `deadline_ms`
/// and a slow bound of `slow_ms`, both far from what an honest agent takes on a loaded
/// machine and from what the late agent does.
fn late_run(mode: &str, deadline_ms: &str, slow_ms: &str, out: &Path) -> Value {
    let rogue = format!("{LATE}={mode}");
    let args = [
        "--misbehave",
        &rogue,
        "--turn-deadline-ms",
        deadline_ms,
        "--slow-turn-ms",
        slow_ms,
    ];
    let (output, pid) = run_to_end(&args, out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{mode}: {stderr}");
    let s = summary(out);
    assert_eq!(s["completed"], true, "{mode}: {s:#}");
    assert_safe(&s);
    assert_nothing_left(pid);
    s
}

/// Every fault is against the late agent.
fn assert_only_against_late(s: &Value, mode: &str) {
    for f in s["faults"].as_array().expect("faults") {
        assert_eq!(f["agent"].as_u64(), Some(LATE), "{mode}: {f:#}");
    }
}

#[test]
fn an_agent_late_two_turns_of_three_is_hung_though_never_three_in_a_row() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Late by 1.3 s against a deadline of 1 s; no answer is slow but a missed one.
    let s = late_run("late-some", "1000", "1000", &dir.path().join("out"));
    assert_only_against_late(&s, "late-some");
    let hung = faults_of(&s, "hung");
    assert_eq!(hung.len(), 1, "{s:#}");
    // Its misses: steps 1 and 2, 4 and 5 (step 3 answered at once): the third miss, at
    // step 4, is the third of its last ten turns.
    let step = hung[0]["step"].as_u64().expect("step");
    assert!(step <= 10, "hung only at step {step}");
    let missed = faults_of(&s, "missed");
    assert!((3..=4).contains(&missed.len()), "{missed:#?}");
    assert!(
        faults_of(&s, "dead")
            .iter()
            .any(|f| f["step"].as_u64() == Some(step)),
        "{s:#}"
    );
}

#[test]
fn an_agent_that_answers_every_turn_late_but_in_time_is_slow() {
    let dir = tempfile::tempdir().expect("tempdir");
    // 200 ms against a slow bound of 100 ms, well within a deadline of 5 s.
    let s = late_run("sluggish", "5000", "100", &dir.path().join("out"));
    assert_only_against_late(&s, "sluggish");
    let slow = faults_of(&s, "slow");
    assert_eq!(slow.len(), 1, "{s:#}");
    // Late at steps 1, 2 and 3: slow at the third, never missed.
    assert_eq!(slow[0]["step"].as_u64(), Some(3), "{s:#}");
    assert!(faults_of(&s, "missed").is_empty(), "{s:#}");
    assert!(faults_of(&s, "hung").is_empty(), "{s:#}");
    let detail = slow[0]["detail"].as_str().expect("detail");
    assert!(detail.contains("3 of its last 10 turns"), "{detail}");
}
