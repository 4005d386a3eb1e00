//! The agent executable on its own: its command line, and a clear failure when there is no
//! run to join. (Having an integration test also makes `cargo test --workspace` build the
//! `agent` executable, which the workspace's process tests start.)

use std::process::Command;

fn agent() -> Command {
    Command::new(env!("CARGO_BIN_EXE_agent"))
}

#[test]
fn the_help_names_every_option() {
    let out = agent().arg("--help").output().expect("agent --help");
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for option in ["--prefix", "--agent", "--liveness-ms"] {
        assert!(help.contains(option), "{option} missing from:\n{help}");
    }
    // The test modes are listed only by an agent built with them.
    assert_eq!(
        help.contains("--misbehave"),
        cfg!(feature = "misbehave"),
        "{help}"
    );
    // The bench's ping-pong is a program of the bench's own.
    for gone in ["--pingpong", "--uds"] {
        assert!(!help.contains(gone), "{gone} in:\n{help}");
    }
}

/// An agent built without its test modes refuses one in a single line that says how to
/// build one with them, before it looks for the run.
#[cfg(not(feature = "misbehave"))]
#[test]
fn a_shipping_agent_refuses_a_test_mode_and_says_how_to_build_one() {
    let prefix = format!("refusedmode{}_", std::process::id());
    for mode in ["nan", "raw-length", "impersonate=1", "deaf-to-prepare"] {
        let out = agent()
            .args(["--prefix", &prefix, "--agent", "0", "--misbehave", mode])
            .env("RUST_LOG", "error")
            .output()
            .expect("agent");
        assert_eq!(out.status.code(), Some(1), "{mode}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(&format!("--misbehave {mode}")), "{err}");
        assert!(
            err.contains("cargo build --release --features misbehave -p agent"),
            "{err}"
        );
        assert!(!err.contains("opening run"), "{err}");
    }
    assert_eq!(
        remove_files_of(&prefix),
        0,
        "nothing of the prefix was made"
    );
}

/// An agent built with its test modes takes one and goes on to join the run.
#[cfg(feature = "misbehave")]
#[test]
fn an_agent_built_with_its_test_modes_takes_one() {
    let prefix = format!("takenmode{}_", std::process::id());
    let out = agent()
        .args(["--prefix", &prefix, "--agent", "0", "--misbehave", "nan"])
        .env("RUST_LOG", "error")
        .output()
        .expect("agent");
    remove_files_of(&prefix);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("opening run {prefix}")), "{err}");
    assert!(!err.contains("--features misbehave"), "{err}");
}

/// Remove the files iceoryx2 made for `prefix` (a node that found no run leaves its
/// prefix's management segment; only a coordinator may remove it during a run).
fn remove_files_of(prefix: &str) -> usize {
    let mut removed = 0;
    for dir in [
        "/dev/shm",
        "/tmp/iceoryx2",
        "/tmp/iceoryx2/nodes",
        "/tmp/iceoryx2/services",
    ] {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with(prefix)
                && std::fs::remove_file(e.path()).is_ok()
            {
                removed += 1;
            }
        }
    }
    removed
}

/// Also under `--run`, the flag's older name.
#[test]
fn joining_a_run_that_does_not_exist_fails_with_one_clear_error() {
    for flag in ["--prefix", "--run"] {
        joining_a_run_that_does_not_exist_fails(flag);
    }
}

fn joining_a_run_that_does_not_exist_fails(flag: &str) {
    let prefix = format!("nosuchrun{}_", std::process::id());
    let out = agent()
        .args([flag, &prefix, "--agent", "0"])
        .env("RUST_LOG", "error")
        .output()
        .expect("agent");
    remove_files_of(&prefix);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("opening run {prefix}")), "{err}");
    assert_eq!(remove_files_of(&prefix), 0, "nothing of the prefix is left");
    let dirs: Vec<_> = std::fs::read_dir("/dev/shm")
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .collect();
    assert!(dirs.is_empty(), "left in /dev/shm: {dirs:?}");
}

#[test]
fn an_invalid_run_prefix_is_refused() {
    let out = agent()
        .args(["--prefix", "../escape", "--agent", "0"])
        .output()
        .expect("agent");
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("run prefix"));
}

#[test]
fn a_run_folder_other_users_could_reach_is_refused_before_anything_is_opened() {
    use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
    let prefix = format!("openrun{}_", std::process::id());
    let Some(root) = wire::run_root(&prefix) else {
        return; // no /dev/shm: no run folder to check
    };
    std::fs::DirBuilder::new()
        .mode(0o700)
        .create(&root)
        .expect("run folder");
    std::fs::set_permissions(&root, std::fs::Permissions::from_mode(0o777)).expect("chmod");
    let out = agent()
        .args(["--prefix", &prefix, "--agent", "0"])
        .env("RUST_LOG", "error")
        .output()
        .expect("agent");
    let inside: Vec<_> = std::fs::read_dir(&root)
        .expect("still there")
        .flatten()
        .map(|e| e.path())
        .collect();
    std::fs::remove_dir_all(&root).expect("clean up");
    let left = remove_files_of(&prefix);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&root.display().to_string()), "{err}");
    assert!(err.contains("0777"), "{err}");
    assert!(inside.is_empty(), "the agent made {inside:?}");
    assert_eq!(left, 0, "the agent made files of {prefix} in /dev/shm");
}
