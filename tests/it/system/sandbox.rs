//! Sandboxed agents (`coordinator run --sandbox`, needs root, as CI has): each agent runs
//! as a user of its own, in a control group of its own, behind a relay that alone opens
//! the run's shared memory. A sandboxed run equals the reference to the bit; attacks from
//! inside the sandbox on the run's files, processes and limits reach nothing: the run
//! completes with exit 0, no fault is recorded against anyone, every agent's moves equal
//! the honest run's, and nothing is left behind.

use crate::support;

use std::path::Path;
use std::time::Duration;

use runner::turns::{BetweenSteps, RunOptions, SandboxOptions, run_scenario_with};
use shared::run::simulate::{plan_centre_path, simulate_along};
use shared::world::scenario::Scenario;
use support::{assert_nothing_left, assert_safe, run_to_end, summary};

/// The first agent's user id in these tests.
const FIRST_UID: u32 = SandboxOptions::DEFAULT_FIRST_UID;
/// The first agent's user in `attacks_from_inside_the_sandbox_reach_nothing`, apart from
/// the default users the other tests' runs take at the same time.
const ATTACK_FIRST_UID: u32 = FIRST_UID + 10_000;

/// What /proc says of process `pid`: its real, effective, saved and file-system user
/// ids, whether it may gain privileges, and its open descriptors.
fn credentials(pid: u32) -> Option<(Vec<u32>, bool, Vec<u32>)> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .map(str::trim)
            .map(str::to_string)
    };
    let uids = field("Uid:")?
        .split_whitespace()
        .filter_map(|v| v.parse().ok())
        .collect();
    let no_new_privs = field("NoNewPrivs:")? == "1";
    let mut fds: Vec<u32> = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .ok()?
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse().ok())
        .collect();
    fds.sort_unstable();
    Some((uids, no_new_privs, fds))
}

/// The sandboxed agents of run `prefix`, as (agent index, pid).
fn sandboxed_agents(prefix: &str) -> Vec<(usize, u32)> {
    let mut found = Vec::new();
    for pid in std::fs::read_dir("/proc")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
    {
        let Ok(cmdline) = std::fs::read(format!("/proc/{pid}/cmdline")) else {
            continue;
        };
        let args: Vec<String> = cmdline
            .split(|&b| b == 0)
            .map(|a| String::from_utf8_lossy(a).into_owned())
            .collect();
        let has = |flag: &str| args.iter().position(|a| a == flag);
        if has("--socket-fd").is_none() {
            continue;
        }
        let Some(p) = has("--prefix") else { continue };
        if args.get(p + 1).map(String::as_str) != Some(prefix) {
            continue;
        }
        if let Some(agent) = has("--agent").and_then(|i| args.get(i + 1)?.parse().ok()) {
            found.push((agent, pid));
        }
    }
    found.sort_unstable();
    found
}

/// The run's control groups: none may be left once it ended.
fn run_cgroups(prefix: &str) -> Vec<std::path::PathBuf> {
    let name = format!("formation-{prefix}");
    let mut found = Vec::new();
    for hierarchy in std::fs::read_dir("/sys/fs/cgroup")
        .into_iter()
        .flatten()
        .flatten()
    {
        for dir in [
            hierarchy.path().join(&name),
            Path::new("/sys/fs/cgroup").join(&name),
        ] {
            if dir.exists() && !found.contains(&dir) {
                found.push(dir);
            }
        }
    }
    found
}

/// What a run's stderr may hold with one attacker: the relay's cut of its agent's log and
/// a few lines more.
fn sandbox_log_bound() -> usize {
    agent::sandbox::MAX_AGENT_LOG_BYTES as usize + (16 << 10)
}

/// A sandboxed run of the paper example equals the reference to the bit; while it
/// goes, every agent is its own user (the agent's index above the first id) that may not
/// gain privileges and holds no descriptor but its three standard ones and its socket;
/// once it ended, no process, file or control group of the run is left.
#[test]
fn a_sandboxed_run_equals_the_reference_and_each_agent_is_a_user_of_its_own() {
    support::system::require_root();
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("centre path");
    let reference = simulate_along(&scenario, &path).expect("reference");
    let options = RunOptions {
        agent_bin: Some(support::agent_bin()),
        turn_deadline: Duration::from_secs(10),
        progress: false,
        sandbox: Some(SandboxOptions::new()),
        ..RunOptions::default()
    };
    let mut seen = Vec::new();
    let mut groups_seen = Vec::new();
    let outcome = run_scenario_with(&scenario, &path, &options, &mut |at: BetweenSteps<'_>| {
        if at.step == 1 {
            seen = sandboxed_agents(at.prefix)
                .into_iter()
                .map(|(agent, pid)| (agent, credentials(pid)))
                .collect();
            groups_seen = run_cgroups(at.prefix);
        }
        Ok(())
    })
    .expect("sandboxed run");
    assert_eq!(
        outcome.run.steps, reference.steps,
        "the sandboxed run differs"
    );
    assert!(outcome.run.faults.is_empty(), "{:?}", outcome.run.faults);
    assert_eq!(
        seen.iter().map(|(a, _)| *a).collect::<Vec<_>>(),
        (0..scenario.agents.len()).collect::<Vec<_>>(),
        "one sandboxed process per agent"
    );
    // Agent i is user first + i: the default first id, or the next free block of ids if
    // another run (another test's, at the same time) holds it.
    let first = seen
        .first()
        .and_then(|(_, creds)| creds.as_ref()?.0.first().copied())
        .expect("agent 0's user");
    assert!(first >= FIRST_UID, "agent 0 runs as user {first}");
    for (agent, creds) in &seen {
        let (uids, no_new_privs, fds) = creds.clone().expect("the agent's /proc entry");
        let uid = first + *agent as u32;
        assert_eq!(uids, [uid; 4], "agent {agent}");
        assert!(no_new_privs, "agent {agent} may gain privileges");
        assert_eq!(fds, [0, 1, 2, 3], "agent {agent}'s descriptors");
    }
    assert!(!groups_seen.is_empty(), "the run had no control group");
    assert!(
        run_cgroups(&outcome.prefix).is_empty(),
        "control groups left"
    );
    assert!(support::leftovers(&outcome.prefix).is_empty(), "files left");
    assert!(sandboxed_agents(&outcome.prefix).is_empty(), "agents left");
}

/// Agent 3 of a sandboxed paper example attacks before it serves honestly: it writes
/// random bytes over every file of the run it can open, sends SIGSTOP to every process
/// of the run, rewrites the mission without its obstacles, forks until it can fork no
/// more, hoards ports or opens another agent's channel, floods its log. Each run completes with exit 0
/// and no fault at all, its trajectory equals the honest sandboxed run's byte for byte,
/// the attacker's own report shows what it reached (nothing, or its own limit), and no
/// process of its user is left.
#[test]
fn attacks_from_inside_the_sandbox_reach_nothing() {
    support::system::require_root();
    let temp = tempfile::tempdir().expect("tempdir");
    let honest_out = temp.path().join("honest");
    // Users of its own, so that no other test's sandboxed agent (the default users,
    // concurrently) is taken for a process this test's attacker left behind.
    let uids = ATTACK_FIRST_UID.to_string();
    let (output, pid) = run_to_end(
        &[
            "--sandbox",
            "--agent-uids",
            &uids,
            "--turn-deadline-ms",
            "10000",
        ],
        &honest_out,
    );
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_nothing_left(pid);
    let honest = std::fs::read(honest_out.join("trajectory.csv")).expect("trajectory");
    let limits = wire::cgroup::Limits::default();
    // Each attack's report of what it reached, any one of them: an attack on the run's
    // shared memory finds either none it may open, or (its `/tmp` and `/dev/shm` its
    // own) none at all.
    let attacks: [(&str, &[&str]); 8] = [
        ("scribble", &["wrote into 0 of 0 files"]),
        ("stop-others", &["stopped 0 of"]),
        ("rewrite-mission", &["cannot read it"]),
        ("fork-bomb", &["children before fork failed"]),
        (
            "hoard",
            &["attack (hoard) stopped", "hoarding 0 ports on other agents"],
        ),
        ("impersonate=0", &["attack (impersonate=0) stopped"]),
        ("log-flood", &["bytes of its output dropped"]),
        ("fill-tmp", &["(fill-tmp): wrote"]),
    ];
    for (mode, reports) in attacks {
        let out = temp.path().join(mode);
        let rogue = format!("3={mode}");
        let (output, pid) = run_to_end(
            &[
                "--sandbox",
                "--agent-uids",
                &uids,
                "--misbehave",
                &rogue,
                "--turn-deadline-ms",
                "10000",
            ],
            &out,
        );
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{mode}: {stderr}");
        assert!(
            reports.iter().any(|report| stderr.contains(report)),
            "{mode}: none of the reports {reports:?} in {stderr}"
        );
        if mode == "fork-bomb" {
            // Its own limit, and only its own: the others started and moved.
            let forked: usize = stderr
                .split("(fork-bomb): forked ")
                .nth(1)
                .and_then(|s| s.split_whitespace().next()?.parse().ok())
                .expect("the fork bomb's count");
            assert!(
                forked < limits.pids_max as usize,
                "{mode}: {forked} children"
            );
        }
        // The log stays bounded: a flood is cut at what the relay passes on, and nothing
        // of the agent's reaches the coordinator's stdout.
        let bound = sandbox_log_bound();
        assert!(
            stderr.len() < bound,
            "{mode}: stderr of {} bytes",
            stderr.len()
        );
        assert!(
            output.stdout.len() < 4096,
            "{mode}: stdout of {} bytes",
            output.stdout.len()
        );
        if mode == "fill-tmp" {
            // Its private temporary file systems only, each bounded, and gone with it.
            let line = stderr
                .lines()
                .find(|l| l.contains("(fill-tmp): wrote"))
                .expect("the report");
            let written: Vec<u64> = line
                .split(" MiB into ")
                .filter_map(|part| part.rsplit(' ').next()?.parse().ok())
                .collect();
            let most = agent::sandbox::PRIVATE_TMP_BYTES >> 20;
            assert_eq!(written.len(), 3, "{line}");
            assert!(written.iter().all(|&w| w <= most), "{line}");
            for dir in ["/dev/shm", "/tmp", "/var/tmp"] {
                let left: Vec<_> = std::fs::read_dir(dir)
                    .into_iter()
                    .flatten()
                    .flatten()
                    .filter(|e| {
                        e.file_name()
                            .to_string_lossy()
                            .starts_with("formation-fill-tmp-")
                    })
                    .map(|e| e.path())
                    .collect();
                assert!(left.is_empty(), "{mode}: left in {dir}: {left:?}");
            }
        }
        let s = summary(&out);
        assert_eq!(s["completed"], true, "{mode}");
        assert_safe(&s);
        assert_eq!(
            s["faults"].as_array().map(Vec::len),
            Some(0),
            "{mode}: {s:#}"
        );
        let trajectory = std::fs::read(out.join("trajectory.csv")).expect("trajectory");
        assert!(
            trajectory == honest,
            "{mode}: the trajectory differs from the honest run"
        );
        assert_nothing_left(pid);
        let uid = ATTACK_FIRST_UID + 3;
        let left: Vec<u32> = std::fs::read_dir("/proc")
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
            .filter(|&p| credentials(p).is_some_and(|(uids, _, _)| uids.first() == Some(&uid)))
            .collect();
        assert!(
            left.is_empty(),
            "{mode}: processes of user {uid} left: {left:?}"
        );
    }
}

/// `--sandbox` is refused, before anything runs, with user ids that do not fit and when
/// every agent is remote.
#[test]
fn bad_sandbox_flags_are_refused_before_anything_runs() {
    let temp = tempfile::tempdir().expect("tempdir");
    for (args, says) in [
        (vec!["--sandbox", "--agent-uids", "0"], "--agent-uids 0"),
        (
            vec!["--sandbox", "--agent-uids", "4294967294"],
            "--agent-uids 4294967294",
        ),
        (
            vec!["--sandbox", "--agent-pids-max", "1"],
            "--agent-pids-max",
        ),
        (
            vec![
                "--sandbox",
                "--transport",
                "zenoh",
                "--remote",
                "0,1,2,3,4,5",
                "--allow-plain-tcp",
                "--listen",
                "tcp/127.0.0.1:7447",
            ],
            "every agent is remote",
        ),
    ] {
        let out = temp.path().join("never");
        let (output, _) = run_to_end(&args, &out);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(!out.exists(), "{args:?}: an output folder was made");
    }
}

/// The control groups of a sandboxed run whose coordinator was killed (it could not
/// remove them) are removed by the next coordinator's clean-up of stale runs.
#[test]
fn a_dead_coordinators_control_groups_are_cleaned_by_the_next_run() {
    support::system::require_root();
    // A pid that no process has any more.
    let mut gone = std::process::Command::new("true").spawn().expect("true");
    let pid = gone.id();
    gone.wait().expect("reaped");
    let prefix = format!("fc{pid}x5ca1ab1e_");
    let group = wire::cgroup::CgroupDirs::for_run(&prefix).expect("cgroups");
    group.create().expect("the run's group");
    group.child("agent-0-0").create().expect("an agent's group");
    assert!(!run_cgroups(&prefix).is_empty());
    let cleaned = runner::stale_runs::clean_stale_runs();
    assert!(cleaned.contains(&prefix), "{cleaned:?}");
    assert!(
        run_cgroups(&prefix).is_empty(),
        "{:?}",
        run_cgroups(&prefix)
    );
}

/// The first agent's user in `a_sandboxed_agent_has_no_terminal_to_push_input_into`.
const TTY_FIRST_UID: u32 = FIRST_UID + 20_000;
/// The first agent's user of both runs in `agents_of_two_runs_are_different_users`.
const TWIN_FIRST_UID: u32 = FIRST_UID + 30_000;

/// A run started from a terminal (a pseudo-terminal, the coordinator's controlling
/// terminal and stdin, as an interactive shell's): a sandboxed agent that opens
/// `/dev/tty` and pushes a line into it (`TIOCSTI`), and into its standard descriptors,
/// finds no terminal; nothing waits in the terminal's input afterwards, and the run
/// completes with no fault.
#[test]
fn a_sandboxed_agent_has_no_terminal_to_push_input_into() {
    use std::os::fd::AsRawFd;
    use std::os::unix::process::CommandExt;
    support::system::require_root();
    let temp = tempfile::tempdir().expect("tempdir");
    let out = temp.path().join("out");
    let (mut master, mut slave) = (-1, -1);
    // SAFETY: openpty(3) writes two descriptors; the name and settings are not asked for.
    let opened = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(opened, 0, "openpty: {}", std::io::Error::last_os_error());
    // SAFETY: both descriptors were just opened and are owned here alone.
    let (_master, slave) = unsafe {
        use std::os::fd::FromRawFd;
        (
            std::os::fd::OwnedFd::from_raw_fd(master),
            std::os::fd::OwnedFd::from_raw_fd(slave),
        )
    };
    let uids = TTY_FIRST_UID.to_string();
    let mut command = support::coordinator(
        &[
            "--sandbox",
            "--agent-uids",
            &uids,
            "--misbehave",
            "3=tty-push",
            "--turn-deadline-ms",
            "10000",
        ],
        &out,
    );
    command.stdin(std::process::Stdio::from(
        slave.try_clone().expect("the terminal"),
    ));
    // SAFETY: setsid(2) and ioctl(2) on descriptor 0, between fork and exec.
    unsafe {
        command.pre_exec(|| {
            if libc::setsid() < 0 || libc::ioctl(0, libc::TIOCSCTTY, 0) < 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let child = command.spawn().expect("coordinator");
    let pid = child.id();
    let output = child.wait_with_output().expect("coordinator");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("cannot open /dev/tty")
            && stderr.contains("pushed a line into 0 terminals"),
        "{stderr}"
    );
    let mut waiting: libc::c_int = 0;
    // SAFETY: FIONREAD writes one int.
    let asked = unsafe { libc::ioctl(slave.as_raw_fd(), libc::FIONREAD, &mut waiting) };
    assert_eq!(asked, 0, "FIONREAD");
    assert_eq!(waiting, 0, "bytes pushed into the terminal's input");
    let s = summary(&out);
    assert_eq!(s["completed"], true);
    assert_eq!(s["faults"].as_array().map(Vec::len), Some(0), "{s:#}");
    assert_nothing_left(pid);
}

/// Two sandboxed runs at once, asked for the same user ids: the second's agents get
/// other ids, so its agent 3, which SIGKILLs every other process of its own user, finds
/// none of the first run's; the first run, stopped by SIGTERM once the second ended,
/// records no fault.
#[test]
fn agents_of_two_runs_are_different_users() {
    support::system::require_root();
    let temp = tempfile::tempdir().expect("tempdir");
    let uids = TWIN_FIRST_UID.to_string();
    // The first run lasts (34 s, stopped long before): agent 0 answers every turn 200 ms
    // late, well within the deadline and the slow bound even on a loaded machine.
    let first_out = temp.path().join("first");
    let first = support::coordinator(
        &[
            "--sandbox",
            "--agent-uids",
            &uids,
            "--misbehave",
            "0=sluggish",
            "--slow-turn-ms",
            "2000",
            "--turn-deadline-ms",
            "10000",
        ],
        &first_out,
    )
    .spawn()
    .expect("the first run");
    let first_pid = first.id();
    let agents = Scenario::paper().agents.len();
    support::wait_for_agents(first_pid, agents);
    let second_out = temp.path().join("second");
    let (output, second_pid) = run_to_end(
        &[
            "--sandbox",
            "--agent-uids",
            &uids,
            "--misbehave",
            "3=kill-twin",
            "--turn-deadline-ms",
            "10000",
        ],
        &second_out,
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("(kill-twin): killed 0 of 0"), "{stderr}");
    let first_ran_on = nix::sys::wait::waitpid(
        nix::unistd::Pid::from_raw(first_pid as i32),
        Some(nix::sys::wait::WaitPidFlag::WNOHANG),
    )
    .expect("waitpid");
    assert_eq!(
        first_ran_on,
        nix::sys::wait::WaitStatus::StillAlive,
        "the first run ended before the second did: nothing was shown"
    );
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(first_pid as i32),
        nix::sys::signal::Signal::SIGTERM,
    )
    .expect("SIGTERM");
    let first_output = first.wait_with_output().expect("the first run");
    let s = summary(&first_out);
    assert_eq!(
        s["faults"].as_array().map(Vec::len),
        Some(0),
        "the first run: {s:#}\n{}",
        String::from_utf8_lossy(&first_output.stderr)
    );
    assert_eq!(summary(&second_out)["completed"], true);
    for pid in [first_pid, second_pid] {
        assert_nothing_left(pid);
    }
}

/// As root, `run --transport zenoh` sandboxes the agents it starts as over iceoryx2:
/// each behind the sandbox's socket relay, as a user of its own, with no key and no link
/// of its own. Agent 3, which writes over every file of the run it can open (the run's
/// TLS folder with the relays' key among them), opens none: the run completes with no
/// fault and moves every agent as the honest sandboxed run does over iceoryx2.
#[test]
fn agents_started_over_zenoh_as_root_are_sandboxed_and_hold_no_key() {
    support::system::require_root();
    let temp = tempfile::tempdir().expect("tempdir");
    let honest_out = temp.path().join("honest");
    let (output, pid) = run_to_end(&["--sandbox", "--turn-deadline-ms", "10000"], &honest_out);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_nothing_left(pid);
    let out = temp.path().join("zenoh");
    let (output, pid) = run_to_end(
        &[
            "--sandbox",
            "--transport",
            "zenoh",
            "--misbehave",
            "3=scribble",
            "--turn-deadline-ms",
            "10000",
        ],
        &out,
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("wrote into 0 of 0 files"), "{stderr}");
    let s = summary(&out);
    assert_eq!(s["completed"], true);
    assert_eq!(s["faults"].as_array().map(Vec::len), Some(0), "{s:#}");
    let trajectory = |dir: &Path| std::fs::read(dir.join("trajectory.csv")).expect("trajectory");
    assert!(
        trajectory(&out) == trajectory(&honest_out),
        "the run over Zenoh differs from the honest sandboxed run"
    );
    assert_nothing_left(pid);
}
