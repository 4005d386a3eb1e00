//! The `coordinator` program as a user starts it: the binary this package builds, each
//! command reaching the crate that carries it out (`runner` for validate, plan and run,
//! `tools` for render), and the bench's ping-pong program beside it.
//!
//! The commands' behaviour is tested where it is written (the root package runs whole
//! formations; `formation-tools` renders); this binary checks that the program put
//! together from them is whole.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn coordinator(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coordinator"))
        .args(args)
        .output()
        .expect("start coordinator")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn paper_scenario() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper.toml")
}

#[test]
fn the_help_lists_every_command() {
    let out = coordinator(&["--help"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let help = text(&out.stdout);
    for command in [
        "validate", "plan", "run", "simulate", "bound", "compare", "render", "bench",
    ] {
        assert!(
            help.lines()
                .any(|l| l.trim_start().starts_with(&format!("{command} "))),
            "`coordinator --help` does not list `{command}`:\n{help}"
        );
        let sub = coordinator(&[command, "--help"]);
        assert!(
            sub.status.success(),
            "`coordinator {command} --help` failed: {}",
            text(&sub.stderr)
        );
    }
}

#[test]
fn validate_and_plan_read_the_paper_scenario() {
    let scenario = paper_scenario();
    let scenario = scenario.to_str().expect("a UTF-8 path");
    let out = coordinator(&["validate", scenario]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("valid:"),
        "{}",
        text(&out.stderr)
    );

    let out = coordinator(&["plan", scenario]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let csv = text(&out.stdout);
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("step,x_m,y_m,heading_rad"));
    let first = lines.next().expect("the path's first pose");
    assert!(first.starts_with("0,"), "{first}");
}

#[test]
fn render_of_a_missing_folder_is_a_usage_error_naming_it() {
    let missing = std::env::temp_dir().join(format!("no-run-folder-{}", std::process::id()));
    let out = coordinator(&["render", missing.to_str().expect("a UTF-8 path")]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains(&missing.display().to_string()), "{stderr}");
}

#[test]
fn the_bench_peer_is_built_beside_the_coordinator() {
    let peer = Path::new(env!("CARGO_BIN_EXE_bench-peer"));
    let coordinator = Path::new(env!("CARGO_BIN_EXE_coordinator"));
    assert_eq!(peer.parent(), coordinator.parent());
    let out = Command::new(peer)
        .arg("--help")
        .output()
        .expect("start bench-peer");
    assert!(out.status.success(), "{}", text(&out.stderr));
}
