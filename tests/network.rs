//! Agents over Zenoh: on the loopback, and on a second test host (a network namespace
//! with a mount namespace of its own, joined by a veth pair). The run equals the
//! reference to the bit; a killed remote agent and a link taken down are survived.
//! Built with the feature `zenoh` (the README's test command turns it on).
#![cfg(feature = "zenoh")]

mod support;

use std::net::{Ipv4Addr, TcpListener};
use std::process::Child;
use std::time::{Duration, Instant};

use coordinator::netns::NetnsHost;
use coordinator::turns::{NetworkOptions, RunOptions, run_scenario, run_scenario_with};
use net::Endpoint;
use net::zenoh::handlers::FifoChannelHandler;
use net::zenoh::pubsub::Subscriber;
use net::zenoh::sample::{Sample, SampleKind};
use shared::record::{FaultKind, Run};
use shared::scenario::Scenario;
use shared::simulate::{plan_centre_path, simulate_along, simulate_along_with_deaths};

/// A port free on `ip` now.
fn free_port(ip: Ipv4Addr) -> u16 {
    TcpListener::bind((ip, 0))
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

fn loopback() -> NetworkOptions {
    let port = free_port(Ipv4Addr::LOCALHOST);
    NetworkOptions::plain(Endpoint::parse(&format!("tcp/127.0.0.1:{port}")).expect("endpoint"))
}

fn options(network: NetworkOptions) -> RunOptions {
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
fn fault_keys(run: &Run) -> Vec<(usize, usize, FaultKind)> {
    run.faults
        .iter()
        .map(|f| (f.agent, f.step, f.kind))
        .collect()
}

/// Step by step and field by field (f64 equality is bit equality here: no NaN in a
/// record).
fn assert_equal_runs(got: &Run, want: &Run, name: &str) {
    assert_eq!(got.steps.len(), want.steps.len(), "{name}");
    for (g, w) in got.steps.iter().zip(&want.steps) {
        assert_eq!(g, w, "{name}: step {} differs from the reference", w.step);
    }
    assert_eq!(fault_keys(got), fault_keys(want), "{name}");
}

/// Nothing of the run is left: no file, no relay, and no agent the relays started (they
/// name the run's endpoint).
fn assert_clean(prefix: &str, listen: &Endpoint) {
    assert!(support::leftovers(prefix).is_empty(), "files left");
    assert!(
        support::processes_mentioning(prefix).is_empty(),
        "relays left running"
    );
    let endpoint = listen.local_connect().to_string();
    let until = Instant::now() + Duration::from_secs(2);
    while !support::processes_mentioning(&endpoint).is_empty() {
        assert!(Instant::now() < until, "agents of {endpoint} left running");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Wait for a process the test started, killing it if it has not left in `timeout`.
fn reap(child: &mut Child, timeout: Duration) -> bool {
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
    opts.deaths = deaths.to_vec();
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
    let host = NetnsHost::new().expect("a test host (network namespaces need root)");
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
    let host = NetnsHost::new().expect("a test host (network namespaces need root)");
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
    assert!(s.min_clearance_m >= -shared::safety::SAFETY_TOLERANCE_M);
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

/// `scripts/make-tls-dir --agents 6 DIR 127.0.0.1`: the TLS folder a user makes.
fn tls_dir(parent: &std::path::Path, name: &str) -> std::path::PathBuf {
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

/// Over TLS with client certificates: agents with a certificate of the run's authority
/// take their turns; one with no certificate and one with a certificate of another
/// authority are refused, recorded as failed to start, and the run goes on safely.
#[test]
fn no_stranger_joins_a_run_over_tls() {
    let temp = tempfile::tempdir().expect("tempdir");
    let ours = tls_dir(temp.path(), "ours");
    let theirs = tls_dir(temp.path(), "theirs");
    let port = free_port(Ipv4Addr::LOCALHOST);
    let listen = Endpoint::parse(&format!("tls/127.0.0.1:{port}")).expect("endpoint");
    let stranger = |agent: usize, extra: &[String]| {
        let mut args = vec!["--agent".to_string(), agent.to_string()];
        args.extend_from_slice(extra);
        std::process::Command::new(support::agent_bin())
            .args(&args)
            .stdin(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("start a stranger")
    };
    // No certificate at all: plain TCP to the TLS port.
    let mut plain = stranger(4, &["--connect".into(), format!("tcp/127.0.0.1:{port}")]);
    // A certificate of another authority.
    let mut forged = stranger(
        5,
        &[
            "--connect".into(),
            listen.to_string(),
            "--tls-dir".into(),
            theirs.display().to_string(),
        ],
    );
    let network = NetworkOptions {
        remote: vec![4, 5],
        tls_dir: Some(ours),
        ..NetworkOptions::plain(listen.clone())
    };
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let mut opts = options(network);
    opts.startup_timeout = Duration::from_secs(4);
    let outcome = run_scenario(&scenario, &path, &opts);
    let (plain_left, forged_left) = (
        reap(&mut plain, Duration::from_secs(15)),
        reap(&mut forged, Duration::from_secs(15)),
    );
    let outcome = outcome.unwrap_or_else(|f| panic!("{:#}", f.error));
    let run = &outcome.run;
    assert!(run.completed);
    assert_eq!(run.summary().collisions, 0);
    for agent in [4, 5] {
        let fault = run
            .faults
            .iter()
            .find(|f| f.agent == agent)
            .unwrap_or_else(|| panic!("agent {agent} not recorded: {:?}", run.faults));
        assert_eq!((fault.step, fault.kind), (0, FaultKind::FailedToStart));
        assert!(fault.detail.contains("refused"), "{fault:?}");
        // Frozen where it stood from the first move on.
        assert!(run.steps.iter().skip(1).all(|s| !s.agents[agent].alive));
        let start = run.steps[0].agents[agent].position;
        assert!(run.steps.iter().all(|s| s.agents[agent].position == start));
    }
    // The certified agents took every turn.
    let last = run.steps.last().expect("steps");
    assert!((0..4).all(|i| last.agents[i].alive));
    assert!(!run.faults.iter().any(|f| f.agent < 4), "{:?}", run.faults);
    // The strangers never got a session: each gave up and exited with an error.
    assert!(plain_left && forged_left, "a stranger was still running");
    assert_clean(&outcome.prefix, &listen);
}

/// A misbehaving agent over Zenoh, as a user runs it (`coordinator run --transport
/// zenoh --misbehave 3=MODE`): what it sends crosses the network and its relay, and is
/// refused like a local agent's; extra and stale moves never reach the coordinator.
#[test]
fn misbehaving_agents_over_zenoh_are_refused_and_nobody_collides() {
    for (mode, kind) in [
        ("nan", Some("rejected")),
        ("teleport", Some("rejected")),
        ("through-obstacle", Some("rejected")),
        ("garbage", Some("rejected")),
        ("silent", Some("hung")),
        ("replay", None),
        ("early", None),
        ("flood", None),
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        let listen = format!("tcp/127.0.0.1:{}", free_port(Ipv4Addr::LOCALHOST));
        let misbehave = format!("3={mode}");
        let args = [
            "--transport",
            "zenoh",
            "--listen",
            &listen,
            "--misbehave",
            &misbehave,
        ];
        let (output, pid) = support::run_to_end(&args, &out);
        assert!(
            output.status.success(),
            "{mode}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let s = support::summary(&out);
        support::assert_safe(&s);
        assert_eq!(s["completed"], true, "{mode}");
        match kind {
            Some(kind) => {
                let found = support::faults_of(&s, kind);
                assert!(!found.is_empty(), "{mode}: no {kind} fault: {s:#}");
                assert!(found.iter().all(|f| f["agent"] == 3), "{mode}");
            }
            // The relay passes on only the move that answers the turn.
            None => assert_eq!(
                s["faults"].as_array().map(Vec::len),
                Some(0),
                "{mode}: {s:#}"
            ),
        }
        support::assert_nothing_left(pid);
        let endpoint = Endpoint::parse(&listen).expect("endpoint");
        let until = Instant::now() + Duration::from_secs(2);
        while !support::processes_mentioning(&endpoint.to_string()).is_empty() {
            assert!(Instant::now() < until, "{mode}: agents left running");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// Bad network flags are refused with exit code 2 and one line naming the flag, before
/// anything runs: no output folder, no process.
#[test]
fn bad_network_flags_are_refused_before_anything_runs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cases: [(&[&str], &str); 7] = [
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
            "plain TCP beyond the loopback",
        ),
        (
            &["--transport", "zenoh", "--listen", "tls/127.0.0.1:7447"],
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
    ];
    let mut coordinator = support::coordinator(&args, &out)
        .spawn()
        .expect("start the coordinator");
    // A watcher on the coordinator's router (plain TCP on the loopback: no access
    // control), listening before agent 5 starts.
    let endpoint = Endpoint::parse(&listen).expect("endpoint");
    let watcher = Watcher::open(&endpoint, 5);
    let mut agent = std::process::Command::new(support::agent_bin())
        .args(["--connect", &listen, "--agent", "5", "--liveness-ms", "100"])
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
    // The liveness period, the rejoin grace (a lease) and room for a loaded machine.
    assert!(
        reap(&mut agent, net::LINK_LEASE * 2 + Duration::from_secs(3)),
        "agent 5 did not leave after the coordinator was killed"
    );
    let until = Instant::now() + Duration::from_secs(3);
    while !support::processes_mentioning(&listen).is_empty() {
        assert!(
            Instant::now() < until,
            "relays or their agents left running"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // The dead coordinator's files are cleaned by the next run.
    let (output, next) = support::run_to_end(&[], &dir.path().join("next"));
    assert!(output.status.success());
    support::assert_nothing_left(coordinator.id());
    support::assert_nothing_left(next);
}

/// A spy joins the run at step 1 with agent 5's identity (over TLS, agent 5's
/// certificate), listens on every agent's keys and sends a forged move for agent 2 every
/// step. Returns how many samples of other agents it heard, and checks that the run still
/// equals the reference to the bit (a forged move never carries the turn's token).
fn spy_on_a_run(tls: bool) -> usize {
    use net::zenoh::Wait;
    let temp = tempfile::tempdir().expect("tempdir");
    let port = free_port(Ipv4Addr::LOCALHOST);
    let (listen, network, spy_security) = if tls {
        let ours = tls_dir(temp.path(), "ours");
        let listen = Endpoint::parse(&format!("tls/127.0.0.1:{port}")).expect("endpoint");
        let network = NetworkOptions {
            tls_dir: Some(ours.clone()),
            ..NetworkOptions::plain(listen.clone())
        };
        let files = net::TlsFiles::in_dir(&ours, net::Role::Agent(5));
        (listen, network, net::Security::Tls(files))
    } else {
        let network = loopback();
        (network.listen.clone(), network, net::Security::Plain)
    };
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let reference = simulate_along(&scenario, &path).expect("reference");
    let heard = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let mut spy: Option<(net::zenoh::Session, _, _)> = None;
    let outcome = run_scenario_with(&scenario, &path, &options(network), &mut |between| {
        if between.step == 1 {
            // The router is up: the spy joins.
            let session = net::open_client(&listen, &spy_security)?;
            let counter = heard.clone();
            let z = |e: net::zenoh::Error| anyhow::anyhow!("zenoh: {e}");
            let all = session
                .declare_subscriber("formation/agent/**")
                // What crosses the router, not the spy's own forgeries.
                .allowed_origin(net::zenoh::sample::Locality::Remote)
                .callback(move |sample| {
                    if !sample.key_expr().as_str().starts_with("formation/agent/5/") {
                        counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    }
                })
                .wait()
                .map_err(z)?;
            let forger = session
                .declare_publisher(net::agent_up_key(2))
                .wait()
                .map_err(z)?;
            spy = Some((session, all, forger));
        }
        if let Some((_, _, forger)) = &spy {
            let step = between.step as u64;
            let forged = net::Up::Move(net::NetMove {
                agent: 2,
                seq: step,
                step,
                token: step,
                status: 0,
                compute_ns: 0,
                slot: [0.0, 0.0],
                best: [0.0, 0.0],
                waypoints: vec![[0.0, 0.0]],
            });
            net::send(forger, &forged)?;
        }
        Ok(())
    });
    let outcome = outcome.unwrap_or_else(|f| panic!("{:#}", f.error));
    assert!(spy.is_some(), "the spy never joined");
    assert_equal_runs(&outcome.run, &reference, "paper with a spy");
    assert_clean(&outcome.prefix, &listen);
    heard.load(std::sync::atomic::Ordering::Relaxed)
}

/// Over TLS each agent may use only its own keys: a certified agent that listens on every
/// key of the run hears nothing of the others, and its forged moves for another agent
/// change nothing. Over plain TCP (loopback only, for this reason) the same spy hears
/// the others' turns: the check can fail.
#[test]
fn a_certified_agent_can_neither_read_nor_answer_another_agents_turns() {
    assert_eq!(
        spy_on_a_run(true),
        0,
        "over TLS the spy heard others' traffic"
    );
    assert!(
        spy_on_a_run(false) > 0,
        "over plain TCP the spy heard nothing"
    );
}
