//! Agents over Zenoh: on the loopback, and on a second test host (a network namespace
//! with a mount namespace of its own, joined by a veth pair). The run equals the
//! reference to the bit; a killed remote agent and a link taken down are survived; the
//! agents leave when the coordinator dies. Who may join a run is in
//! `tests/it/system/network_security.rs`. In the system tier (it needs root for the
//! second host, and Zenoh).

use crate::support;
use crate::support::network as network_support;

use std::net::Ipv4Addr;
use std::process::Child;
use std::time::{Duration, Instant};

use net::Endpoint;
use net::zenoh::handlers::FifoChannelHandler;
use net::zenoh::pubsub::Subscriber;
use net::zenoh::sample::{Sample, SampleKind};
use runner::netns::NetnsHost;
use runner::turns::{NetworkOptions, run_scenario, run_scenario_with};
use shared::run::record::FaultKind;
use shared::run::simulate::{plan_centre_path, simulate_along, simulate_along_with_deaths};
use shared::world::scenario::Scenario;

use network_support::*;

/// In sequential and in parallel turns, every agent over Zenoh on the loopback: the run
/// equals the reference to the bit.
#[test]
fn agents_over_zenoh_on_the_loopback_match_the_reference_to_the_bit() {
    let parallel = Scenario::load(&support::repo_root().join("tests/data/swarm16-parallel.toml"))
        .expect("swarm16-parallel.toml");
    for scenario in [Scenario::paper(), parallel] {
        let path = plan_centre_path(&scenario).expect("centre path");
        let reference = simulate_along(&scenario, &path).expect("reference");
        let network = loopback();
        let outcome = run_scenario(&scenario, &path, &options(network.clone())).expect("zenoh run");
        assert!(outcome.run.completed);
        assert_equal_runs(&outcome.run, &reference, &scenario.name);
        assert_clean(&outcome.prefix, &network.listen);
    }
}

/// An agent (its relay and the agent behind it) killed before its turn is frozen and
/// the run equals the reference with that death.
#[test]
fn an_agent_killed_over_zenoh_is_frozen_as_in_the_reference() {
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let deaths = [(2, 40)];
    let reference = simulate_along_with_deaths(&scenario, &path, &deaths).expect("reference");
    let network = loopback();
    let mut opts = options(network.clone());
    opts.faults.deaths = deaths.to_vec();
    let outcome = run_scenario(&scenario, &path, &opts).expect("zenoh run");
    assert_equal_runs(&outcome.run, &reference, "paper with a death");
    assert_eq!(outcome.run.summary().collisions, 0);
    assert_clean(&outcome.prefix, &network.listen);
}

/// Half the paper example's agents on another host: they connect from their own network
/// and mount namespaces over the veth link. The run equals the reference to the bit,
/// and the remote agents leave when it ends.
#[test]
fn half_the_agents_on_another_host_match_the_reference_to_the_bit() {
    support::system::require_root();
    let host = NetnsHost::new().expect("a test host in a network namespace");
    let port = free_port(host.local_ip);
    let listen = Endpoint::parse(&format!("tcp/{}:{port}", host.local_ip)).expect("endpoint");
    let remote = vec![3, 4, 5];
    let mut agents: Vec<Child> = remote
        .iter()
        .map(|i| {
            host.spawn(
                &support::agent_bin(),
                &[
                    "--connect".into(),
                    listen.to_string(),
                    "--agent".into(),
                    i.to_string(),
                    "--allow-plain-tcp".into(),
                ],
            )
            .expect("an agent on the test host")
        })
        .collect();
    let network = NetworkOptions {
        remote,
        allow_plain_tcp: true,
        ..NetworkOptions::plain(listen.clone())
    };
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let reference = simulate_along(&scenario, &path).expect("reference");
    let outcome = run_scenario(&scenario, &path, &options(network));
    let left: Vec<bool> = agents
        .iter_mut()
        .map(|a| reap(a, Duration::from_secs(5)))
        .collect();
    let outcome = outcome.expect("run across hosts");
    assert_equal_runs(&outcome.run, &reference, "paper across hosts");
    assert!(outcome.run.completed);
    assert_eq!(left, [true; 3], "remote agents did not leave after the run");
    assert_clean(&outcome.prefix, &listen);
}

/// What goes wrong with the remote agent at step 40.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Trouble {
    /// Its process is killed with SIGKILL on its host.
    Kill,
    /// Its host's link goes down (and stays down).
    LinkDown,
    /// Its host's link goes down, and up again at step 60: the agent is not re-admitted
    /// (no `--respawn`).
    Partition,
    /// Its process is killed and the user starts it again at once; with `--respawn` the
    /// coordinator's new relay re-admits it.
    KillAndRestart,
}

fn survive(trouble: Trouble) {
    support::system::require_root();
    let host = NetnsHost::new().expect("a test host in a network namespace");
    let port = free_port(host.local_ip);
    let listen = Endpoint::parse(&format!("tcp/{}:{port}", host.local_ip)).expect("endpoint");
    let mut agent = host
        .spawn(
            &support::agent_bin(),
            &[
                "--connect".into(),
                listen.to_string(),
                "--agent".into(),
                "4".into(),
                "--allow-plain-tcp".into(),
            ],
        )
        .expect("an agent on the test host");
    let agent_args: Vec<String> = vec![
        "--connect".into(),
        listen.to_string(),
        "--agent".into(),
        "4".into(),
        "--allow-plain-tcp".into(),
    ];
    let network = NetworkOptions {
        remote: vec![4],
        allow_plain_tcp: true,
        ..NetworkOptions::plain(listen.clone())
    };
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let mut opts = options(network);
    // A silent agent is declared hung after a few missed turns of this length.
    opts.turn_deadline = Duration::from_secs(1);
    opts.respawn = trouble == Trouble::KillAndRestart;
    let agent_pid = agent.id();
    let mut restarted: Option<Child> = None;
    let outcome = run_scenario_with(&scenario, &path, &opts, &mut |between| {
        let kill = || {
            let pid = nix::unistd::Pid::from_raw(agent_pid as i32);
            nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGKILL)
        };
        match (trouble, between.step) {
            (Trouble::Kill, 40) => kill()?,
            (Trouble::LinkDown | Trouble::Partition, 40) => host.set_link(false)?,
            (Trouble::Partition, 60) => host.set_link(true)?,
            (Trouble::KillAndRestart, 40) => {
                kill()?;
                restarted = Some(host.spawn(&support::agent_bin(), &agent_args)?);
            }
            _ => {}
        }
        Ok(())
    });
    reap(&mut agent, Duration::from_secs(5));
    if let Some(mut again) = restarted {
        assert!(
            reap(&mut again, Duration::from_secs(5)),
            "the restarted agent did not leave after the run"
        );
    }
    let outcome = outcome.unwrap_or_else(|f| panic!("{trouble:?}: {:#}", f.error));
    let run = &outcome.run;
    assert!(run.completed, "{trouble:?}");
    let s = run.summary();
    assert_eq!(s.collisions, 0, "{trouble:?}");
    assert!(s.min_clearance_m >= -shared::control::safety::SAFETY_TOLERANCE_M);
    let last = run.steps.last().expect("steps");
    if trouble == Trouble::KillAndRestart {
        assert!(
            last.agents[4].alive,
            "the restarted agent was not re-admitted"
        );
        assert!(
            run.faults
                .iter()
                .any(|f| f.agent == 4 && f.kind == FaultKind::Respawned),
            "{:?}",
            run.faults
        );
        assert_clean(&outcome.prefix, &listen);
        return;
    }
    assert!(
        !last.agents[4].alive,
        "{trouble:?}: agent 4 is still alive at the end"
    );
    assert!(
        run.faults.iter().any(|f| f.agent == 4 && f.step >= 40),
        "{trouble:?}: no fault recorded for agent 4: {:?}",
        run.faults
    );
    // Everyone else kept moving to the end.
    assert!(
        last.agents
            .iter()
            .enumerate()
            .all(|(i, a)| a.alive || i == 4)
    );
    assert_clean(&outcome.prefix, &listen);
}

#[test]
fn a_remote_agent_killed_on_its_host_is_survived() {
    survive(Trouble::Kill);
}

#[test]
fn a_remote_agent_whose_link_goes_down_is_survived() {
    survive(Trouble::LinkDown);
}

#[test]
fn a_remote_agent_back_after_a_partition_is_not_readmitted_without_respawn() {
    survive(Trouble::Partition);
}

#[test]
fn a_remote_agent_restarted_by_its_user_is_readmitted_with_respawn() {
    survive(Trouble::KillAndRestart);
}

/// Bad network flags are refused with exit code 2 and one line naming the flag, before
/// anything runs: no output folder, no process.
#[test]
fn bad_network_flags_are_refused_before_anything_runs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cases: [(&[&str], &str); 8] = [
        (
            &["--transport", "zenoh", "--listen", "udp/127.0.0.1:7447"],
            "tcp/HOST:PORT",
        ),
        (
            &["--transport", "zenoh", "--listen", "tcp/127.0.0.1:0"],
            "port",
        ),
        (
            &["--transport", "zenoh", "--listen", "tcp/10.1.2.3:7447"],
            "--allow-plain-tcp",
        ),
        // Plain TCP on the loopback too: another user of this machine could join.
        (
            &["--transport", "zenoh", "--listen", "tcp/127.0.0.1:7447"],
            "any other user of this machine",
        ),
        // The run's own authority cannot reach agents started elsewhere.
        (
            &[
                "--transport",
                "zenoh",
                "--listen",
                "tls/127.0.0.1:7447",
                "--remote",
                "3",
            ],
            "--tls-dir",
        ),
        (
            &[
                "--transport",
                "zenoh",
                "--listen",
                "tls/127.0.0.1:7447",
                "--tls-dir",
                "/nonexistent",
            ],
            "ca.pem is missing",
        ),
        (&["--remote", "3"], "need --transport zenoh"),
        (&["--transport", "zenoh", "--remote", "9"], "--remote 9"),
    ];
    for (i, (args, says)) in cases.iter().enumerate() {
        let out = dir.path().join(format!("out{i}"));
        let (output, pid) = support::run_to_end(args, &out);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(!out.exists(), "{args:?}: the output folder was made");
        support::assert_nothing_left(pid);
    }
}

/// A client of a run's router that sees what the tests wait for: one agent's answers to
/// its relay, and which agents are connected (their liveliness tokens).
struct Watcher {
    /// Keeps the session open.
    _session: net::zenoh::Session,
    up: Subscriber<FifoChannelHandler<Sample>>,
    tokens: Subscriber<FifoChannelHandler<Sample>>,
    agent: usize,
}

/// How long a watcher waits for what it waits for before it fails the test (only so that
/// a broken run cannot hang the suite).
const WATCH_DEADLINE: Duration = Duration::from_secs(60);

impl Watcher {
    /// Connect to the router at `endpoint` (as soon as it listens) and listen to `agent`'s
    /// answers and to every agent's token (those already there included).
    fn open(endpoint: &Endpoint, agent: usize) -> Self {
        use net::zenoh::Wait;
        let deadline = Instant::now() + WATCH_DEADLINE;
        let session = loop {
            // Each attempt tries for `net::CONNECT_TIMEOUT`.
            match net::open_client(endpoint, &net::Security::Plain) {
                Ok(session) => break session,
                Err(e) => assert!(Instant::now() < deadline, "no router at {endpoint}: {e}"),
            }
        };
        let up = session
            .declare_subscriber(net::agent_up_key(agent))
            .wait()
            .expect("a subscriber to the agent's answers");
        let tokens = session
            .liveliness()
            .declare_subscriber("formation/agent/*/alive")
            .history(true)
            .wait()
            .expect("a subscriber to the agents' tokens");
        Self {
            _session: session,
            up,
            tokens,
            agent,
        }
    }

    /// Wait until the agent watched answers a mission ([`net::Up::Ready`]: its handshake
    /// is done) and every agent of `connected` has its token on the router.
    fn wait_until_ready_and_connected(&self, connected: &[usize]) {
        let deadline = Instant::now() + WATCH_DEADLINE;
        let left = || deadline.saturating_duration_since(Instant::now());
        loop {
            match net::receive::<net::Up>(&self.up, left()).expect("the watcher's session") {
                Some(Ok(net::Up::Ready { agent, .. })) if agent as usize == self.agent => break,
                Some(_) => {}
                None => panic!("agent {} never took its mission", self.agent),
            }
        }
        let mut present = std::collections::BTreeSet::new();
        while !connected.iter().all(|a| present.contains(a)) {
            let sample = self
                .tokens
                .recv_timeout(left())
                .expect("the watcher's session")
                .unwrap_or_else(|| panic!("agents {connected:?} not all connected: {present:?}"));
            let agent: Option<usize> = sample
                .key_expr()
                .as_str()
                .strip_prefix("formation/agent/")
                .and_then(|k| k.strip_suffix("/alive"))
                .and_then(|i| i.parse().ok());
            if let Some(agent) = agent {
                match sample.kind() {
                    SampleKind::Put => present.insert(agent),
                    SampleKind::Delete => present.remove(&agent),
                };
            }
        }
    }
}

/// When the coordinator is killed (SIGKILL) mid-run, an agent on another machine sees
/// its liveliness token go and leaves, and the relays and the agents they started go
/// with the coordinator.
#[test]
fn agents_leave_when_the_coordinator_is_killed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let listen = format!("tcp/127.0.0.1:{}", free_port(Ipv4Addr::LOCALHOST));
    // Agent 4 never comes: the coordinator waits for it, with agent 5 ready and waiting.
    let args = [
        "--transport",
        "zenoh",
        "--listen",
        &listen,
        "--remote",
        "4,5",
        "--allow-plain-tcp",
    ];
    let mut coordinator = support::coordinator(&args, &out)
        .spawn()
        .expect("start the coordinator");
    // A watcher on the coordinator's router (plain TCP on the loopback: no access
    // control), listening before agent 5 starts.
    let endpoint = Endpoint::parse(&listen).expect("endpoint");
    let watcher = Watcher::open(&endpoint, 5);
    let mut agent = std::process::Command::new(support::agent_bin())
        // Its default settings: it looks at the coordinator's token more often than its
        // `--liveness-ms` (10 s) while it waits.
        .args(["--connect", &listen, "--agent", "5"])
        .arg("--allow-plain-tcp")
        .stdin(std::process::Stdio::null())
        .spawn()
        .expect("start agent 5");
    // Until agent 5 has shaken hands with its relay (its answer to the mission crosses
    // the router) and the agents the relays start here are connected.
    watcher.wait_until_ready_and_connected(&[0, 1, 2, 3]);
    drop(watcher);
    assert!(
        matches!(agent.try_wait(), Ok(None)),
        "agent 5 left before the coordinator was killed"
    );
    coordinator.kill().expect("SIGKILL the coordinator");
    let _ = coordinator.wait();
    // The rejoin grace (a lease), a look at the token and room for a loaded machine: less
    // than the default liveness period.
    assert!(
        reap(&mut agent, net::LINK_LEASE * 2 + Duration::from_secs(3)),
        "agent 5 did not leave after the coordinator was killed"
    );
    // The relays and their agents die with the coordinator (the kernel kills them).
    support::wait_for_no_process_mentioning(&listen, support::EXIT_ROOM);
    // The dead coordinator's files are cleaned by the next run.
    let (output, next) = support::run_to_end(&[], &dir.path().join("next"));
    assert!(output.status.success());
    support::assert_nothing_left(coordinator.id());
    support::assert_nothing_left(next);
}
