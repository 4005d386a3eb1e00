//! Rogue agents: real agent processes that attack the protocol (`--misbehave MODE`),
//! against the real coordinator process. Every attack must end with exit code 0, a
//! complete `summary.json`, no collision, the fault recorded against the attacker, the
//! honest agents untouched where the attack can have no effect, and nothing left behind.

use crate::support;

use std::path::Path;

use serde_json::Value;
use support::{assert_nothing_left, assert_safe, faults_of, run_to_end, summary};

/// The attacking agent in every test (the paper example has agents 0 to 5).
const ROGUE: u64 = 3;

/// Run the paper example with `args`; assert what every attacked run must show, and
/// return its summary.
fn attacked_run(args: &[&str], out: &Path) -> Value {
    // A generous deadline: these tests compare trajectories, and a loaded machine must
    // not turn a late honest answer into a missed turn.
    // Trusted agents (as every run of `support::coordinator`): these attacks are on the
    // run's channels, which only a trusted agent can reach (a sandboxed one cannot even
    // open them: the sandbox's tests); what is tested here is what the coordinator's own
    // checks make of them.
    let args = [args, &["--turn-deadline-ms", "10000"]].concat();
    let (output, pid) = run_to_end(&args, out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    let s = summary(out);
    assert_eq!(s["completed"], true, "{args:?}: {s:#}");
    assert_safe(&s);
    assert_nothing_left(pid);
    s
}

/// Faults of `kind`, all of which must be against `agent`.
fn faults_against(s: &Value, kind: &str, agent: u64) -> Vec<Value> {
    let found = faults_of(s, kind);
    for f in &found {
        assert_eq!(f["agent"].as_u64(), Some(agent), "{kind}: {f:#}");
    }
    found
}

/// The faults' kinds, sorted and without repeats.
fn fault_kinds(s: &Value) -> Vec<String> {
    let mut kinds: Vec<String> = s["faults"]
        .as_array()
        .expect("faults")
        .iter()
        .map(|f| f["kind"].as_str().expect("kind").to_string())
        .collect();
    kinds.sort();
    kinds.dedup();
    kinds
}

fn trajectory(out: &Path) -> String {
    std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory.csv")
}

#[test]
fn replayed_early_and_repeated_answers_change_nothing_and_are_recorded() {
    let dir = tempfile::tempdir().expect("tempdir");
    let honest = dir.path().join("honest");
    let baseline = attacked_run(&[], &honest);
    assert!(faults_of(&baseline, "unsolicited").is_empty());
    let steps = baseline["steps"].as_u64().expect("steps");
    for mode in ["replay", "early", "flood"] {
        let out = dir.path().join(mode);
        let s = attacked_run(&["--misbehave", &format!("{ROGUE}={mode}")], &out);
        // Every answer that answers no turn is refused and recorded...
        let unsolicited = faults_against(&s, "unsolicited", ROGUE);
        assert!(
            unsolicited.len() as u64 >= steps - 2,
            "{mode}: {} of {steps} steps",
            unsolicited.len()
        );
        // ...against the attacker alone...
        support::assert_faults_only_against(&s, ROGUE);
        // ...and the first answer carrying the turn's token is the one taken: the run is
        // the honest run to the bit, every agent, every step. A flooder may pay: a copy
        // still on its way when its next turn is granted fills its channel (which refuses
        // samples once full), its own next answer is refused and it misses that turn.
        let missed_own = mode == "flood" && !faults_against(&s, "missed", ROGUE).is_empty();
        if missed_own {
            assert_eq!(fault_kinds(&s), ["missed", "unsolicited"], "{mode}: {s:#}");
        } else {
            assert_eq!(fault_kinds(&s), ["unsolicited"], "{mode}: {s:#}");
            assert_eq!(trajectory(&out), trajectory(&honest), "{mode}");
        }
    }
}

#[test]
fn hostile_lengths_are_refused_as_malformed_without_a_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("moves");
    let s = attacked_run(&["--misbehave", &format!("{ROGUE}=raw-length")], &out);
    let steps = s["steps"].as_u64().expect("steps");
    let malformed = faults_against(&s, "malformed", ROGUE);
    assert_eq!(malformed.len() as u64, steps, "one per turn");
    for count in ["513", "1099511627776", "18446744073709551615"] {
        assert!(
            malformed
                .iter()
                .any(|f| f["detail"].as_str().expect("detail").contains(count)),
            "count {count} not refused"
        );
    }
    assert_eq!(fault_kinds(&s), ["malformed"], "{s:#}");

    // The same in the handshake: the agent never starts, the run goes on without it.
    let out = dir.path().join("ready");
    let s = attacked_run(&["--misbehave", &format!("{ROGUE}=raw-length-ready")], &out);
    assert_eq!(faults_against(&s, "malformed", ROGUE).len(), 1);
    assert_eq!(faults_against(&s, "failed-to-start", ROGUE).len(), 1);
}

#[test]
fn agents_that_fail_to_start_are_frozen_or_replaced_and_the_run_goes_on() {
    let dir = tempfile::tempdir().expect("tempdir");
    for mode in ["exit-before-ready", "spoof-ready=1", "killed-connecting"] {
        let out = dir.path().join(mode.replace('=', "-"));
        let s = attacked_run(&["--misbehave", &format!("{ROGUE}={mode}")], &out);
        let failed = faults_against(&s, "failed-to-start", ROGUE);
        assert_eq!(failed.len(), 1, "{mode}: {s:#}");
        assert_eq!(failed[0]["step"], 0);
        // Agent 1, named in the forged handshake, is untouched.
        assert!(faults_of(&s, "dead").is_empty(), "{mode}: {s:#}");
        assert!(
            s["faults"]
                .as_array()
                .expect("faults")
                .iter()
                .all(|f| f["agent"].as_u64() == Some(ROGUE)),
            "{mode}: {s:#}"
        );

        // With --respawn, an honest replacement takes the slot.
        let out = dir
            .path()
            .join(format!("{}-respawn", mode.replace('=', "-")));
        let s = attacked_run(
            &["--misbehave", &format!("{ROGUE}={mode}"), "--respawn"],
            &out,
        );
        assert_eq!(faults_against(&s, "respawned", ROGUE).len(), 1, "{s:#}");
        assert!(
            s["final_mean_deviation_m"].as_f64().expect("final") < 0.05,
            "{mode}: {s:#}"
        );
    }
}

#[test]
fn an_agent_on_another_agents_channel_is_named_killed_and_cannot_speak_for_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    for mode in ["impersonate=1", "hoard"] {
        for respawn in [false, true] {
            let out = dir
                .path()
                .join(format!("{}-{respawn}", mode.replace('=', "-")));
            let mut args = vec!["--misbehave".to_string(), format!("{ROGUE}={mode}")];
            if respawn {
                args.push("--respawn".to_string());
            }
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let s = attacked_run(&args, &out);
            // Whichever process reached the victim's channel first, the intruder is named.
            let caught = faults_against(&s, "impersonation", ROGUE);
            assert!(!caught.is_empty(), "{mode}: {s:#}");
            // A victim may have lost the race for its own channel (then it failed to start),
            // but no move was ever accepted in its name: every fault is the rogue's or a
            // victim's failed start (and, with --respawn, the replacements').
            for f in s["faults"].as_array().expect("faults") {
                let kind = f["kind"].as_str().expect("kind");
                if f["agent"].as_u64() != Some(ROGUE) {
                    assert!(
                        matches!(kind, "failed-to-start" | "respawned"),
                        "{mode}: {f:#}"
                    );
                }
            }
            if respawn {
                // Every slot ends with an honest process at its place.
                assert!(
                    s["final_mean_deviation_m"].as_f64().expect("final") < 0.05,
                    "{mode}: {s:#}"
                );
            }
        }
    }
}

/// A trusted agent rewrites the mission file without its obstacles before it starts (a
/// sandboxed one cannot even read it: tests/it/system/sandbox.rs). Every process the coordinator
/// starts checks the file against the digest it was handed: no agent ever moves by the
/// forged mission (no move is refused, nobody collides), the attacker refuses its own
/// forgery and fails to start, and so does any agent that read the file after it was
/// changed, each saying why on stderr, rather than running on it.
#[test]
fn a_rewritten_mission_is_refused_by_every_agent_that_reads_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let args = [
        "--misbehave",
        "3=rewrite-mission",
        "--turn-deadline-ms",
        "10000",
    ];
    let (output, pid) = run_to_end(&args, &out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let s = summary(&out);
    assert_eq!(s["completed"], true, "{s:#}");
    assert_safe(&s);
    assert_nothing_left(pid);
    assert!(stderr.contains("(rewrite-mission): rewritten"), "{stderr}");
    assert!(faults_of(&s, "rejected").is_empty(), "{s:#}");
    let failed = faults_of(&s, "failed-to-start");
    assert!(
        failed.iter().any(|f| f["agent"].as_u64() == Some(ROGUE)),
        "the forger started: {s:#}"
    );
    let refusals = stderr
        .matches("changed since the coordinator wrote it")
        .count();
    assert_eq!(refusals, failed.len(), "{stderr}\n{s:#}");
}
