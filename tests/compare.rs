//! `coordinator compare`: every planner through the same processes and the same safety
//! monitor. The paper's LogSumExp barrier tries unsafe moves (the monitor refuses them,
//! so nobody collides); the barrier-function QP never does.

mod support;

use std::process::Command;

#[test]
fn the_comparison_table_shows_the_papers_failure_and_the_fix() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("cmp");
    let output = Command::new(support::coordinator_bin())
        .args(["compare", "--out"])
        .arg(&out)
        .env("FORMATION_AGENT_BIN", support::agent_bin())
        .output()
        .expect("coordinator compare");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    assert!(md.starts_with("| scenario | planner |"));
    let mut reader = csv::Reader::from_path(out.join("compare.csv")).expect("compare.csv");
    let headers = reader.headers().expect("headers").clone();
    let col = |name: &str| headers.iter().position(|h| h == name).expect(name);
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    assert_eq!(rows.len(), 3, "three planners on the paper example");
    for r in &rows {
        assert_eq!(
            &r[col("collisions")],
            "0",
            "the monitor keeps every planner safe"
        );
        assert_eq!(&r[col("completed")], "true");
    }
    let by = |planner: &str| {
        rows.iter()
            .find(|r| &r[col("planner")] == planner)
            .expect(planner)
    };
    let unsafe_moves = |planner: &str| {
        by(planner)[col("unsafe_moves")]
            .parse::<usize>()
            .expect("count")
    };
    assert_eq!(unsafe_moves("best-point"), 0);
    assert_eq!(unsafe_moves("cbf"), 0);
    assert!(
        unsafe_moves("zcbf-logsumexp") > 0,
        "the smoothed max overshoots (paper, IV.C.1)"
    );
    let final_dev = |planner: &str| {
        by(planner)[col("final_mean_deviation_m")]
            .parse::<f64>()
            .expect("dev")
    };
    assert!(final_dev("best-point") < 0.05);
}
