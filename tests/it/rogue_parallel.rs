//! Red team for the newer parts of the model: a top speed, limited sensing and parallel
//! turns. Every `--misbehave` mode runs against a parallel scenario with a short sensing
//! radius (`tests/data/redteam16-parallel-sensing.toml`: 16 agents, groups of several
//! agents granted at once, each agent sent only the agents it senses) through the real
//! `coordinator run` process, as `tests/it/rogue.rs` does for sequential runs; agents are
//! killed from outside at random steps of the run, as `tests/it/faults.rs` does. Every run must end
//! with exit code 0, `completed`, no collision, the faults recorded against the attacker
//! (or the killed), and nothing left behind (processes, /dev/shm).

use crate::support;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use shared::control::vocabulary::{Body, TurnMode};
use shared::geometry::Point;
use shared::world::groups::turn_groups_ordered;
use shared::world::scenario::Scenario;
use support::progress::{self, Watched};
use support::{
    agent_rows, assert_nothing_left, assert_safe, coordinator, faults_of, run_to_end, summary,
};

/// The attacker: inside the 4 x 4 block (row 1, column 1), so it has neighbours on
/// every side and shares its groups with agents it senses.
const ROGUE: u64 = 5;
/// The agent the modes with a victim attack: the rogue's neighbour in its row.
const VICTIM: u64 = 6;
/// Agents in the scenario.
const AGENTS: usize = 16;

fn scenario_file() -> PathBuf {
    support::repo_root().join("tests/data/redteam16-parallel-sensing.toml")
}

fn scenario() -> Scenario {
    let scenario = Scenario::load(&scenario_file()).expect("the red-team scenario");
    assert_eq!(scenario.agents.len(), AGENTS);
    assert_eq!(scenario.turns, TurnMode::Parallel);
    for a in &scenario.agents {
        assert_eq!((a.max_step_m, a.sensing_radius_m), (Some(0.6), Some(2.0)));
    }
    scenario
}

/// Run the scenario with `args` (and a generous turn deadline unless `args` gives one:
/// these runs compare trajectories, and a loaded machine must not turn a late honest
/// answer into a missed turn); assert what every attacked run must show, and return its
/// summary.
fn attacked_run(args: &[&str], out: &Path) -> Value {
    let file = scenario_file();
    let mut all = vec![file.to_str().expect("utf-8 path")];
    all.extend_from_slice(args);
    if !args.contains(&"--turn-deadline-ms") {
        all.extend(["--turn-deadline-ms", "10000"]);
    }
    // Trusted agents (as every run of `support::coordinator`): the attacks are on the
    // run's channels, which a sandboxed agent cannot open (the sandbox's tests); what is
    // tested is the coordinator's own checks.
    let (output, pid) = run_to_end(&all, out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    let s = summary(out);
    assert_eq!(s["completed"], true, "{args:?}: {s:#}");
    assert_safe(&s);
    assert_eq!(
        s["mean_groups_per_step"].as_f64().map(|g| g < 8.0),
        Some(true)
    );
    assert_nothing_left(pid);
    s
}

/// `--misbehave ROGUE=mode`.
fn rogue(mode: &str) -> [String; 2] {
    ["--misbehave".to_string(), format!("{ROGUE}={mode}")]
}

fn run_mode(mode: &str, extra: &[&str], out: &Path) -> Value {
    let [flag, value] = rogue(mode);
    let mut args = vec![flag.as_str(), value.as_str()];
    args.extend_from_slice(extra);
    attacked_run(&args, out)
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
    let kinds: BTreeSet<String> = s["faults"]
        .as_array()
        .expect("faults")
        .iter()
        .map(|f| f["kind"].as_str().expect("kind").to_string())
        .collect();
    kinds.into_iter().collect()
}

fn steps(s: &Value) -> u64 {
    s["steps"].as_u64().expect("steps")
}

fn trajectory(out: &Path) -> String {
    std::fs::read_to_string(out.join("trajectory.csv")).expect("trajectory.csv")
}

/// Where every agent stands at every step, from `trajectory.csv`: `[step][agent]`.
fn positions(out: &Path) -> Vec<Vec<Point>> {
    let mut steps: Vec<Vec<Point>> = Vec::new();
    for agent in 0..AGENTS {
        for (step, x, y, _) in agent_rows(out, agent) {
            if steps.len() <= step {
                steps.resize(step + 1, Vec::new());
            }
            assert_eq!(steps[step].len(), agent, "rows in step and agent order");
            steps[step].push(Point::new(x, y));
        }
    }
    steps
}

/// The agents in `agent`'s group at step 1 (formed from where every agent stood at step 0,
/// in the scenario's turn order along the centre's heading at step 1), when every agent
/// is alive.
fn group_mates(scenario: &Scenario, before: &[Point], agent: usize) -> Vec<usize> {
    let path = shared::run::simulate::plan_centre_path(scenario).expect("centre path");
    let bodies: Vec<Body> = before
        .iter()
        .zip(&scenario.agents)
        .map(|(p, spec)| Body {
            position: *p,
            radius_m: spec.radius_m,
        })
        .collect();
    let groups = turn_groups_ordered(
        scenario.turns,
        scenario.turn_order,
        path[1].heading_rad,
        &scenario.agents,
        &bodies,
        &[true; AGENTS],
    );
    groups
        .into_iter()
        .find(|g| g.contains(&agent))
        .expect("a live agent has a group")
        .into_iter()
        .filter(|&a| a != agent)
        .collect()
}

#[test]
fn an_honest_parallel_run_with_sensing_has_no_fault_and_groups_of_several() {
    let dir = tempfile::tempdir().expect("tempdir");
    let s = attacked_run(&[], &dir.path().join("honest"));
    assert!(s["faults"].as_array().expect("faults").is_empty(), "{s:#}");
    let groups = s["mean_groups_per_step"].as_f64().expect("groups");
    assert!(groups > 1.0 && groups < 4.0, "parallel: {groups}");
    // The top speed holds.
    assert!(
        s["max_move_m"].as_f64().expect("max_move_m") <= 0.6 + 1e-9,
        "{s:#}"
    );
}

/// Every bad move (unsafe, nonsensical, too long, or unreadable) is refused at every
/// turn, in groups with others that move at once: the rogue never moves, its mates and
/// everyone else go on, nobody collides. What the refused move was changes nothing: the
/// runs are the same, byte for byte.
#[test]
fn every_bad_move_is_refused_at_every_parallel_turn_and_the_runs_agree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut first: Option<(String, String)> = None;
    for (mode, kind) in [
        ("nan", "rejected"),
        ("teleport", "rejected"),
        ("through-obstacle", "rejected"),
        ("garbage", "rejected"),
        ("overspeed", "rejected"),
        ("raw-length", "malformed"),
    ] {
        let out = dir.path().join(mode);
        let s = run_mode(mode, &[], &out);
        let found = faults_against(&s, kind, ROGUE);
        assert_eq!(found.len() as u64, steps(&s), "{mode}: one per turn");
        assert_eq!(fault_kinds(&s), [kind], "{mode}: {s:#}");
        let rows = agent_rows(&out, ROGUE as usize);
        assert!(
            rows.iter()
                .all(|r| (r.1, r.2, r.3) == (rows[0].1, rows[0].2, true)),
            "{mode}: the rogue moved"
        );
        if mode == "overspeed" {
            // Safe but too fast: refused for its length alone.
            for f in &found {
                let detail = f["detail"].as_str().expect("detail");
                assert!(
                    detail.contains("beyond the top speed of 0.6 m per step"),
                    "{f:#}"
                );
            }
        }
        if mode == "raw-length" {
            for count in ["513", "1099511627776", "18446744073709551615"] {
                assert!(
                    found
                        .iter()
                        .any(|f| f["detail"].as_str().expect("detail").contains(count)),
                    "count {count} not refused"
                );
            }
        }
        match &first {
            None => first = Some((mode.to_string(), trajectory(&out))),
            Some((m, t)) => assert_eq!(&trajectory(&out), t, "{mode} and {m} differ"),
        }
    }
}

#[test]
fn a_move_beyond_the_top_speed_is_refused_while_its_group_mates_move() {
    let scenario = scenario();
    let dir = tempfile::tempdir().expect("tempdir");
    // The overspeed move is safe but for its length: without a top speed (the paper
    // example) every one is accepted and the run is the honest run.
    let paper = dir.path().join("paper-overspeed");
    let (output, pid) = run_to_end(&["--misbehave", "3=overspeed"], &paper);
    assert!(output.status.success());
    let s = summary(&paper);
    assert!(s["faults"].as_array().expect("faults").is_empty(), "{s:#}");
    assert!(s["max_move_m"].as_f64().expect("max_move_m") > 2.0, "{s:#}");
    assert_nothing_left(pid);
    let paper_honest = dir.path().join("paper-honest");
    let (output, pid) = run_to_end(&[], &paper_honest);
    assert!(output.status.success());
    assert_nothing_left(pid);
    assert_eq!(trajectory(&paper), trajectory(&paper_honest));

    // With a top speed, every one is refused, for its length.
    let out = dir.path().join("overspeed");
    let s = run_mode("overspeed", &[], &out);
    let refused = faults_against(&s, "rejected", ROGUE);
    assert_eq!(refused.len() as u64, steps(&s));
    let mut lengths: Vec<f64> = refused
        .iter()
        .map(|f| {
            let detail = f["detail"].as_str().expect("detail");
            detail
                .strip_prefix("the move is ")
                .and_then(|d| d.split(' ').next())
                .and_then(|l| l.parse().ok())
                .unwrap_or_else(|| panic!("not a too-long refusal: {detail}"))
        })
        .collect();
    lengths.sort_by(f64::total_cmp);
    // Nine passes over honest moves: at least a little beyond the top speed at the first
    // turn (the centre moves 0.1 m a step), nine top speeds once the rogue lags behind.
    assert!(lengths[0] > 0.6, "{lengths:?}");
    assert!(
        (lengths[lengths.len() - 1] - 9.0 * 0.6).abs() < 1e-6,
        "{lengths:?}"
    );
    // The rogue shared its first turn with agents it senses, granted at once: some of
    // those mates moved at step 1 while its own move was refused.
    let at = positions(&out);
    let mates = group_mates(&scenario, &at[0], ROGUE as usize);
    let rogue_at = at[0][ROGUE as usize];
    let near: Vec<usize> = mates
        .iter()
        .copied()
        .filter(|&m| (at[0][m] - rogue_at).norm() - 0.3 <= 2.0)
        .collect();
    assert!(!near.is_empty(), "mates {mates:?}, none sensed");
    assert!(near.iter().any(|&m| at[1][m] != at[0][m]), "{near:?}");
    // Nobody else is refused or collides, and everyone else reaches the goal formation.
    assert_eq!(fault_kinds(&s), ["rejected"]);
    let last = at.last().expect("steps");
    let honest = dir.path().join("honest");
    attacked_run(&[], &honest);
    let reference = positions(&honest);
    let reference_last = reference.last().expect("steps");
    for agent in (0..AGENTS).filter(|&a| a != ROGUE as usize) {
        assert!(
            (last[agent] - reference_last[agent]).norm() < 0.05,
            "agent {agent} ends {} m from its honest end",
            (last[agent] - reference_last[agent]).norm()
        );
    }
}

/// Answers that answer no turn are refused without changing anything: the run is the
/// honest run to the bit, also when the rogue's group mates answer at the same time.
#[test]
fn replayed_early_repeated_answers_and_forks_change_nothing_in_parallel_turns() {
    let dir = tempfile::tempdir().expect("tempdir");
    let honest = dir.path().join("honest");
    attacked_run(&[], &honest);
    for mode in ["replay", "early", "flood", "fork"] {
        let out = dir.path().join(mode);
        let s = run_mode(mode, &[], &out);
        if mode == "fork" {
            assert!(fault_kinds(&s).is_empty(), "{s:#}");
        } else {
            let unsolicited = faults_against(&s, "unsolicited", ROGUE);
            assert!(
                unsolicited.len() as u64 >= steps(&s) - 2,
                "{mode}: {} of {} steps",
                unsolicited.len(),
                steps(&s)
            );
            // A flooder may pay for its flood (see tests/it/rogue.rs): a copy still on its
            // way when its next turn is granted fills its channel, its own next answer is
            // refused and it misses that turn; then the run is not the honest one.
            if mode == "flood" && !faults_against(&s, "missed", ROGUE).is_empty() {
                assert_eq!(fault_kinds(&s), ["missed", "unsolicited"], "{mode}: {s:#}");
                support::assert_faults_only_against(&s, ROGUE);
                continue;
            }
            assert_eq!(fault_kinds(&s), ["unsolicited"], "{mode}: {s:#}");
        }
        assert_eq!(trajectory(&out), trajectory(&honest), "{mode}");
    }
}

#[test]
fn a_silent_agent_in_a_parallel_group_is_declared_hung_and_frozen() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("silent");
    // The default deadline: a silent agent costs its group that long, three times.
    let s = run_mode("silent", &["--turn-deadline-ms", "250"], &out);
    let hung = faults_against(&s, "hung", ROGUE);
    assert_eq!(hung.len(), 1, "{s:#}");
    let dead = faults_against(&s, "dead", ROGUE);
    assert_eq!(dead.len(), 1, "{s:#}");
    assert_eq!(dead[0]["step"], 3);
    let missed: Vec<Value> = faults_of(&s, "missed")
        .into_iter()
        .filter(|f| f["agent"] == ROGUE)
        .collect();
    assert_eq!(missed.len(), 3, "{s:#}");
    // Frozen where it started, out of the formation from the third step on.
    let rows = agent_rows(&out, ROGUE as usize);
    assert!(rows.iter().all(|r| (r.1, r.2) == (rows[0].1, rows[0].2)));
    assert!(rows.iter().all(|r| r.3 == (r.0 < 3)));
}

#[test]
fn bad_handshakes_and_early_exits_fail_to_start_and_the_parallel_run_goes_on() {
    let dir = tempfile::tempdir().expect("tempdir");
    let victim = format!("spoof-ready={VICTIM}");
    for mode in ["raw-length-ready", victim.as_str(), "exit-before-ready"] {
        for respawn in [false, true] {
            let out = dir
                .path()
                .join(format!("{}-{respawn}", mode.replace('=', "-")));
            let extra: &[&str] = if respawn { &["--respawn"] } else { &[] };
            let s = run_mode(mode, extra, &out);
            let failed = faults_against(&s, "failed-to-start", ROGUE);
            assert_eq!(failed.len(), 1, "{mode}: {s:#}");
            assert_eq!(failed[0]["step"], 0);
            // Nobody else is touched (the victim named in a forged handshake included).
            for f in s["faults"].as_array().expect("faults") {
                assert_eq!(f["agent"].as_u64(), Some(ROGUE), "{mode}: {f:#}");
            }
            if respawn {
                assert_eq!(faults_against(&s, "respawned", ROGUE).len(), 1, "{s:#}");
                assert!(
                    s["final_mean_deviation_m"].as_f64().expect("final") < 0.05,
                    "{mode}: {s:#}"
                );
            } else {
                // Frozen where it starts (step 0 is the start itself, recorded before any
                // handshake).
                let rows = agent_rows(&out, ROGUE as usize);
                assert!(rows.iter().all(|r| (r.1, r.2) == (rows[0].1, rows[0].2)));
                assert!(rows.iter().all(|r| r.3 == (r.0 == 0)), "{mode}");
            }
        }
    }
}

#[test]
fn an_agent_on_another_agents_channel_is_named_and_killed_in_a_parallel_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let victim = format!("impersonate={VICTIM}");
    for mode in [victim.as_str(), "hoard"] {
        for respawn in [false, true] {
            let out = dir
                .path()
                .join(format!("{}-{respawn}", mode.replace('=', "-")));
            let extra: &[&str] = if respawn { &["--respawn"] } else { &[] };
            let s = run_mode(mode, extra, &out);
            let caught = faults_against(&s, "impersonation", ROGUE);
            assert!(!caught.is_empty(), "{mode}: {s:#}");
            // A victim may have lost the race for its own channel (then it failed to
            // start), but no move was ever taken in its name.
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
                assert!(
                    s["final_mean_deviation_m"].as_f64().expect("final") < 0.05,
                    "{mode}: {s:#}"
                );
            }
        }
    }
}

/// The agent index in an agent process's command line (`--agent N`).
fn agent_of(pid: u32) -> Option<usize> {
    let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).ok()?;
    let args: Vec<String> = cmdline
        .split(|&b| b == 0)
        .map(|a| String::from_utf8_lossy(a).to_string())
        .collect();
    let at = args.iter().position(|a| a == "--agent")?;
    args.get(at + 1)?.parse().ok()
}

/// Agents SIGKILLed from outside at random moments of a parallel run with sensing (one to
/// three a run, each once the run reports a step drawn at random, so they may die in one
/// group, mid-turn or between turns): the run completes, nobody collides, every death is
/// recorded against the agent killed, each dead agent stays frozen where it stood (or is
/// replaced, with `--respawn`), and nothing is left behind.
#[test]
fn agents_killed_from_outside_at_random_moments_of_a_parallel_run_are_survived() {
    let file = scenario_file();
    // Every kill lands while a step is still to come, however fast the run goes.
    let latest = progress::latest_hold_step(progress::centre_path_steps(&file));
    let mut between_turns = 0;
    for seed in 0..8u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(700 + seed);
        let respawn = seed % 2 == 1;
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("out");
        // A generous turn deadline: a death is noticed by the process check, and a
        // loaded machine must not turn an honest agent's late answer into a missed turn
        // (seen once at the default 250 ms with three test suites running at once).
        let mut args = vec![
            file.to_str().expect("utf-8 path"),
            "--turn-deadline-ms",
            "10000",
        ];
        if respawn {
            args.push("--respawn");
        }
        let count = rng.random_range(1..=3usize);
        let mut at: Vec<usize> = (0..count).map(|_| rng.random_range(1..=latest)).collect();
        at.sort_unstable();
        let mut run = Watched::spawn(coordinator(&args, &out), &at);
        let pid = run.id();
        let agents = support::wait_for_agents(pid, AGENTS);
        let mut killed: Vec<usize> = Vec::new();
        for _ in &at {
            let victims: Vec<(u32, usize)> = agents
                .iter()
                .filter_map(|&p| Some((p, agent_of(p)?)))
                .filter(|(_, a)| !killed.contains(a))
                .collect();
            let (victim, agent) = victims[rng.random_range(0..victims.len())];
            let _held = run.hold();
            kill(Pid::from_raw(victim as i32), Signal::SIGKILL).expect("kill an agent");
            killed.push(agent);
        }
        let output = run.wait_with_output();
        let context = format!("seed {seed}: killed {killed:?} at steps {at:?}, respawn {respawn}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{context}: {stderr}");
        assert!(!stderr.contains("panicked"), "{context}: {stderr}");
        let s = summary(&out);
        assert_eq!(s["completed"], true, "{context}");
        assert_safe(&s);
        // Every death recorded, once, against the agent killed; nothing else went wrong. (A
        // kill that lands before the agent's handshake is a failed start.)
        let deaths: Vec<Value> = s["faults"]
            .as_array()
            .expect("faults")
            .iter()
            .filter(|f| f["kind"] == "dead" || f["kind"] == "failed-to-start")
            .cloned()
            .collect();
        let mut dead: Vec<usize> = deaths
            .iter()
            .map(|f| f["agent"].as_u64().expect("agent") as usize)
            .collect();
        dead.sort_unstable();
        let mut want = killed.clone();
        want.sort_unstable();
        assert_eq!(dead, want, "{context}: {s:#}");
        // Each death noticed by the liveness check (no `missed` turn, asserted below with
        // the kinds allowed), its time recorded; how long it took on a loaded machine is
        // reported, not asserted.
        for f in faults_of(&s, "dead") {
            assert!(
                f["detection_ms"].as_f64().expect("detection_ms") >= 0.0,
                "{context}: {f:#}"
            );
            // A death found between turns names how the process ended: here, the kill.
            let detail = f["detail"].as_str().expect("detail");
            if detail.contains("between turns") {
                assert!(detail.contains("SIGKILL"), "{context}: {f:#}");
                between_turns += 1;
            }
        }
        let kinds = fault_kinds(&s);
        let allowed: &[&str] = if respawn {
            &["dead", "failed-to-start", "respawned"]
        } else {
            &["dead", "failed-to-start"]
        };
        assert!(
            kinds.iter().all(|k| allowed.contains(&k.as_str())),
            "{context}: {s:#}"
        );
        if respawn {
            assert_eq!(faults_of(&s, "respawned").len(), count, "{context}: {s:#}");
        } else {
            for f in &deaths {
                let agent = f["agent"].as_u64().expect("agent") as usize;
                let noticed = f["step"].as_u64().expect("step") as usize;
                let rows = agent_rows(&out, agent);
                // Frozen where it last stood: alive until the step it died at, then still.
                let frozen: Vec<_> = rows.iter().filter(|r| r.0 >= noticed).collect();
                assert!(
                    frozen
                        .iter()
                        .all(|r| !r.3 && (r.1, r.2) == (frozen[0].1, frozen[0].2)),
                    "{context}: agent {agent}"
                );
                assert!(rows.iter().filter(|r| r.0 < noticed).all(|r| r.3));
                if let Some(before) = rows.iter().rfind(|r| r.0 < noticed) {
                    assert_eq!((before.1, before.2), (frozen[0].1, frozen[0].2));
                }
            }
        }
        let how: Vec<String> = deaths
            .iter()
            .map(|f| format!("{}@{} {}", f["agent"], f["step"], f["detail"]))
            .collect();
        eprintln!("{context}: {how:?}");
        assert_nothing_left(pid);
    }
    // Some of the deaths (6 of 15 in one run here) are found between turns, so the check
    // of how they ended above was made.
    assert!(between_turns > 0, "no death was found between turns");
}
