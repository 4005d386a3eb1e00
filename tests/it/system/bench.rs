//! `coordinator bench --sandboxed`: what the sandbox costs a turn, measured beside the
//! trusted agents (the bench's other reports are in the fast tier's `bench`).

use serde_json::Value;

use crate::bench::{number, turns_report};
use crate::support;

/// The same runs as `bench_compares_sequential_and_parallel_turns_on_one_scenario`, with
/// sandboxed agents beside (`--sandboxed`, root).
#[test]
fn bench_compares_the_turns_of_sandboxed_agents_with_trusted_ones() {
    support::system::require_root();
    let report = turns_report(&["--sandboxed"]);
    let t = &report["turns"];
    // The sandboxed runs: the same figures, clean, and their cost against the trusted.
    let sandboxed = t["sandboxed"].as_array().expect("sandboxed");
    assert_eq!(sandboxed.len(), 2, "{t}");
    for (m, (mode, trusted)) in sandboxed.iter().zip([
        ("sequential", &t["sequential"]),
        ("parallel", &t["parallel"]),
    ]) {
        assert_eq!(
            (&m["mode"], &m["transport"]),
            (&mode.into(), &"iceoryx2 sandboxed".into())
        );
        assert_eq!(
            (&m["faults"], &m["collisions"], &m["completed"]),
            (&0.into(), &0.into(), &true.into()),
            "{m}"
        );
        assert_eq!(
            m["mean_groups_per_step"], trusted["mean_groups_per_step"],
            "{m}"
        );
        assert!(number(m, "startup_s") > 0.0, "{m}");
    }
    let cost = &t["sandboxed_vs_trusted"];
    for (i, trusted) in [&t["sequential"], &t["parallel"]].into_iter().enumerate() {
        let p50 = |m: &Value| m["turn_us"]["p50"].as_f64().expect("p50");
        let expected = p50(&sandboxed[i]) / p50(trusted);
        let got = cost["turn_p50"][i].as_f64().expect("turn_p50");
        assert!(
            (got - expected).abs() <= 1e-9 * expected,
            "{got} vs {expected}"
        );
    }
}
