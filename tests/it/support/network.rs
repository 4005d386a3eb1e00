//! Helpers of the Zenoh tests (`tests/network*.rs`): free ports, run options, the
//! comparison with the reference and the clean-up checks.
#![allow(dead_code)]

use std::net::{Ipv4Addr, TcpListener};
use std::process::Child;
use std::time::{Duration, Instant};

use net::Endpoint;
use runner::turns::{NetworkOptions, RunOptions};
use shared::run::record::{FaultKind, Run};

use crate::support;

/// A port free on `ip` now.
pub fn free_port(ip: Ipv4Addr) -> u16 {
    TcpListener::bind((ip, 0))
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// The default on the loopback: TLS with the run's own authority.
pub fn loopback() -> NetworkOptions {
    let port = free_port(Ipv4Addr::LOCALHOST);
    NetworkOptions::new(Endpoint::parse(&format!("tls/127.0.0.1:{port}")).expect("endpoint"))
}

/// Plain TCP on the loopback, consented to (`--allow-plain-tcp`).
pub fn loopback_plain() -> NetworkOptions {
    let port = free_port(Ipv4Addr::LOCALHOST);
    NetworkOptions::plain(Endpoint::parse(&format!("tcp/127.0.0.1:{port}")).expect("endpoint"))
}

pub fn options(network: NetworkOptions) -> RunOptions {
    RunOptions {
        agent_bin: Some(support::agent_bin()),
        turn_deadline: Duration::from_secs(10),
        progress: false,
        network: Some(network),
        ..RunOptions::default()
    }
}

/// The faults as both sides must agree on them: agent, step and kind (the detail and
/// the detection time are the coordinator's own).
pub fn fault_keys(run: &Run) -> Vec<(usize, usize, FaultKind)> {
    run.faults
        .iter()
        .map(|f| (f.agent, f.step, f.kind))
        .collect()
}

/// Step by step and field by field (f64 equality is bit equality here: no NaN in a
/// record).
pub fn assert_equal_runs(got: &Run, want: &Run, name: &str) {
    assert_eq!(got.steps.len(), want.steps.len(), "{name}");
    for (g, w) in got.steps.iter().zip(&want.steps) {
        assert_eq!(g, w, "{name}: step {} differs from the reference", w.step);
    }
    assert_eq!(fault_keys(got), fault_keys(want), "{name}");
}

/// Nothing of the run is left: no file, no relay, and no agent the relays started (they
/// name the run's endpoint).
pub fn assert_clean(prefix: &str, listen: &Endpoint) {
    assert!(support::leftovers(prefix).is_empty(), "files left");
    assert!(
        support::processes_mentioning(prefix).is_empty(),
        "relays left running"
    );
    let endpoint = listen.local_connect().to_string();
    support::wait_for_no_process_mentioning(&endpoint, support::EXIT_ROOM);
}

/// Wait for a process the test started, killing it if it has not left in `timeout`.
pub fn reap(child: &mut Child, timeout: Duration) -> bool {
    let until = Instant::now() + timeout;
    while Instant::now() < until {
        if let Ok(Some(_)) = child.try_wait() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    false
}

/// `scripts/make-tls-dir --agents 6 DIR 127.0.0.1`: the TLS folder a user makes.
pub fn tls_dir(parent: &std::path::Path, name: &str) -> std::path::PathBuf {
    let dir = parent.join(name);
    let out = std::process::Command::new(support::repo_root().join("scripts/make-tls-dir"))
        .args(["--agents", "6"])
        .arg(&dir)
        .arg("127.0.0.1")
        .output()
        .expect("scripts/make-tls-dir (needs openssl)");
    assert!(
        out.status.success(),
        "make-tls-dir: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir
}
