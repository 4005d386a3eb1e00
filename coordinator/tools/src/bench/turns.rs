//! `coordinator bench --turns-scenario FILE`: sequential against parallel turns on one
//! scenario, in the same bench run. The scenario runs through the real [`run_scenario`]
//! with its `[turns] mode` forced to each mode in turn (same agents, same processes
//! count, same top speed), alternating `S P`, `P S`, `S P`, ... so a machine that gets
//! busier or quieter during the bench weighs on both modes alike.

use std::path::Path;
use std::time::Duration;

use serde::Serialize;
use shared::control::vocabulary::TurnMode;
use shared::geometry::Pose;
use shared::world::scenario::Scenario;

use crate::bench::run_options::bench_run_options;
use crate::compare::with_turn_mode;
use runner::CliError;
use runner::loaded::load_and_plan;
use runner::stats::{Distribution, median};
use runner::turns::{NetworkOptions, RunOptions, RunOutcome, WakeMode, run_scenario};

/// The comparison (`turns` in the report).
#[derive(Clone, Debug, Serialize)]
pub struct TurnsReport {
    /// The scenario's `name`.
    pub scenario: String,
    /// The scenario file as given.
    pub file: String,
    /// The scenario's own `[turns] mode`.
    pub scenario_mode: &'static str,
    /// Agents (one process each, in both modes).
    pub agents: usize,
    /// Steps of the centre path run (each run).
    pub steps: usize,
    /// The smallest and the largest top speed of the agents, metres per step.
    pub max_step_m: [f64; 2],
    /// Runs of each mode.
    pub rounds: usize,
    /// The runs in the order they were made (`sequential`, `parallel`, ...).
    pub order: Vec<&'static str>,
    /// The figures of the sequential runs.
    pub sequential: ModeReport,
    /// The figures of the parallel runs.
    pub parallel: ModeReport,
    /// `parallel.steps_per_s / sequential.steps_per_s`.
    pub parallel_vs_sequential_steps_per_s: f64,
    /// `parallel.turn_us.p50 / sequential.turn_us.p50`.
    pub parallel_vs_sequential_turn_p50: f64,
    /// The same runs with every agent over Zenoh (`--transport zenoh`): on the loopback,
    /// and across a veth pair to a network namespace (`--zenoh-netns`); each mode of each.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub over_zenoh: Vec<ModeReport>,
    /// The same runs with every agent sandboxed (`--sandboxed`, as root): sequential, then
    /// parallel.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sandboxed: Vec<ModeReport>,
    /// Sandboxed against trusted (iceoryx2) in each mode, `[sequential, parallel]`:
    /// turn latency p50, steps per second and start-up, each as sandboxed / trusted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sandboxed_vs_trusted: Option<SandboxCost>,
}

/// What the sandbox costs, each figure sandboxed / trusted in the same bench run,
/// `[sequential, parallel]`.
#[derive(Clone, Debug, Serialize)]
pub struct SandboxCost {
    /// Turn latency p50.
    pub turn_p50: [f64; 2],
    /// Steps per second (the median run).
    pub steps_per_s: [f64; 2],
    /// Start-up (the median run).
    pub startup_s: [f64; 2],
}

/// How the agents of a run talk to the coordinator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Link {
    /// iceoryx2 shared memory.
    Iceoryx2,
    /// Zenoh on the loopback: a relay per agent, the agent started by it.
    ZenohLoopback,
    /// Zenoh across a veth pair: every agent in a network namespace of its own host.
    ZenohVeth,
    /// iceoryx2 through a relay per agent, the agent sandboxed behind it (its own user and
    /// control group, a socket pair to its relay; needs root).
    Sandboxed,
}

impl Link {
    /// The name in the report.
    pub fn name(self) -> &'static str {
        match self {
            Self::Iceoryx2 => "iceoryx2",
            Self::ZenohLoopback => "zenoh loopback",
            Self::ZenohVeth => "zenoh veth",
            Self::Sandboxed => "iceoryx2 sandboxed",
        }
    }
}

/// The figures of one turn mode over its runs.
#[derive(Clone, Debug, Serialize)]
pub struct ModeReport {
    /// `sequential` or `parallel`.
    pub mode: &'static str,
    /// How the agents talked: `iceoryx2`, `zenoh loopback`, `zenoh veth` ([`Link`]).
    pub transport: &'static str,
    /// Steps per second of the step loop (start-up excluded): the median of the runs.
    pub steps_per_s: f64,
    /// Steps per second of each run, in the order they were made.
    pub steps_per_s_runs: Vec<f64>,
    /// Turn groups per step (one per live agent in sequential mode): mean over the runs.
    pub mean_groups_per_step: f64,
    /// Turn latency, every run pooled, step 1 (warm-up) left out, microseconds.
    pub turn_us: Distribution,
    /// The agents' compute time per turn, pooled the same way, microseconds.
    pub compute_us: Distribution,
    /// The longest single move of any run, metres.
    pub max_move_m: f64,
    /// The largest mean deviation of a run, metres.
    pub mean_deviation_m: f64,
    /// Collisions over every run (0 when safe).
    pub collisions: usize,
    /// Faults over every run (0 for clean runs).
    pub faults: usize,
    /// Whether every run went through the whole path it was given.
    pub completed: bool,
    /// Wall time of each run, start-up included, seconds.
    pub wall_s: Vec<f64>,
    /// Start-up (first spawn to the last ready handshake): the median of the runs, seconds.
    pub startup_s: f64,
}

/// What the bench asked for: the file, the runs of each mode, the steps.
pub struct TurnsBench<'a> {
    /// The scenario file.
    pub file: &'a Path,
    /// Runs of each mode.
    pub rounds: usize,
    /// At most this many steps of the centre path.
    pub steps: Option<usize>,
    /// Progress lines on stderr.
    pub verbose: bool,
    /// The transports each mode runs over (iceoryx2 first).
    pub links: Vec<Link>,
}

/// The scenario in both modes, with its path.
#[derive(Debug)]
pub struct Prepared {
    /// Turns forced to sequential.
    pub sequential: Scenario,
    /// Turns forced to parallel.
    pub parallel: Scenario,
    /// The centre path, cut to the steps asked for.
    pub path: Vec<Pose>,
    /// The file as given.
    pub source: String,
    /// The scenario's own mode.
    pub own: TurnMode,
}

/// The scenario in both modes with its path, checked before anything runs: a bad file,
/// a scenario without a top speed (parallel turns need one) or bad counts are refused
/// (exit code 2).
pub fn prepare(b: &TurnsBench<'_>) -> Result<Prepared, CliError> {
    if b.rounds == 0 {
        return Err(CliError::Usage("--turns-rounds: at least 1".into()));
    }
    if b.steps.is_some_and(|k| k < 2) {
        return Err(CliError::Usage(
            "--turns-steps: at least 2 (the first step is a warm-up)".into(),
        ));
    }
    let loaded = load_and_plan(Some(b.file))?;
    let seq = with_turn_mode(&loaded.scenario, &loaded.source, TurnMode::Sequential)?;
    let par = with_turn_mode(&loaded.scenario, &loaded.source, TurnMode::Parallel)?;
    let mut path = loaded.centre_path;
    if let Some(k) = b.steps {
        path.truncate(k + 1);
    }
    Ok(Prepared {
        sequential: seq,
        parallel: par,
        path,
        source: loaded.source,
        own: loaded.scenario.turns,
    })
}

/// Run the comparison `b`, prepared as `prepared` ([`prepare`]), with the agent
/// executable `bin`, rung as `wake` has it.
pub fn measure(
    b: &TurnsBench<'_>,
    prepared: Prepared,
    bin: &Path,
    wake: WakeMode,
) -> Result<TurnsReport, CliError> {
    let Prepared {
        sequential: seq,
        parallel: par,
        path,
        source,
        own,
    } = prepared;
    let options = bench_run_options(bin, wake);
    // A second host for the veth runs, made once (needs root).
    let host = if b.links.contains(&Link::ZenohVeth) {
        Some(runner::netns::NetnsHost::new().map_err(CliError::Other)?)
    } else {
        None
    };
    let mut order = Vec::with_capacity(2 * b.rounds);
    // By mode and link.
    let mut runs: Vec<(TurnMode, Link, Vec<RunOutcome>)> = Vec::new();
    for mode in [TurnMode::Sequential, TurnMode::Parallel] {
        for &link in &b.links {
            runs.push((mode, link, Vec::new()));
        }
    }
    for round in 0..b.rounds {
        let pair = if round % 2 == 0 {
            [TurnMode::Sequential, TurnMode::Parallel]
        } else {
            [TurnMode::Parallel, TurnMode::Sequential]
        };
        for mode in pair {
            let scenario = if mode == TurnMode::Parallel {
                &par
            } else {
                &seq
            };
            for &link in &b.links {
                let outcome = run_over(scenario, &path, &options, bin, link, host.as_ref())?;
                if outcome.interrupted {
                    return Err(CliError::Other(anyhow::anyhow!("interrupted")));
                }
                if b.verbose {
                    eprintln!(
                        "bench: {} turns over {}, round {} of {}: {:.2} steps/s, {:.2} groups per step, turn p50 {:.1} us",
                        mode.name(),
                        link.name(),
                        round + 1,
                        b.rounds,
                        outcome.timing.steps_per_s,
                        outcome.run.summary().mean_groups_per_step,
                        outcome.timing.turn_latency_us.p50
                    );
                }
                if link == Link::Iceoryx2 {
                    order.push(mode.name());
                }
                if let Some((_, _, list)) =
                    runs.iter_mut().find(|(m, l, _)| *m == mode && *l == link)
                {
                    list.push(outcome);
                }
            }
        }
    }
    let report_of = |mode: TurnMode, link: Link| {
        let list = runs
            .iter()
            .find(|(m, l, _)| *m == mode && *l == link)
            .map_or(&[][..], |(_, _, list)| list.as_slice());
        mode_report(mode, link, list)
    };
    let sequential = report_of(TurnMode::Sequential, Link::Iceoryx2);
    let parallel = report_of(TurnMode::Parallel, Link::Iceoryx2);
    let over_zenoh: Vec<ModeReport> = b
        .links
        .iter()
        .filter(|&&l| matches!(l, Link::ZenohLoopback | Link::ZenohVeth))
        .flat_map(|&l| [TurnMode::Sequential, TurnMode::Parallel].map(|m| report_of(m, l)))
        .collect();
    let sandboxed: Vec<ModeReport> = if b.links.contains(&Link::Sandboxed) {
        [TurnMode::Sequential, TurnMode::Parallel]
            .map(|m| report_of(m, Link::Sandboxed))
            .to_vec()
    } else {
        Vec::new()
    };
    let sandboxed_vs_trusted = match sandboxed.as_slice() {
        [s, p] => {
            let of = |f: fn(&ModeReport) -> f64| {
                [
                    runner::stats::ratio(f(s), f(&sequential)),
                    runner::stats::ratio(f(p), f(&parallel)),
                ]
            };
            Some(SandboxCost {
                turn_p50: of(|m| m.turn_us.p50),
                steps_per_s: of(|m| m.steps_per_s),
                startup_s: of(|m| m.startup_s),
            })
        }
        _ => None,
    };
    let speeds: Vec<f64> = seq.agents.iter().filter_map(|a| a.max_step_m).collect();
    Ok(TurnsReport {
        scenario: seq.name.clone(),
        file: source,
        scenario_mode: own.name(),
        agents: seq.agents.len(),
        steps: path.len().saturating_sub(1),
        max_step_m: [
            speeds.iter().copied().fold(f64::INFINITY, f64::min),
            speeds.iter().copied().fold(0.0, f64::max),
        ],
        rounds: b.rounds,
        order,
        parallel_vs_sequential_steps_per_s: runner::stats::ratio(
            parallel.steps_per_s,
            sequential.steps_per_s,
        ),
        parallel_vs_sequential_turn_p50: runner::stats::ratio(
            parallel.turn_us.p50,
            sequential.turn_us.p50,
        ),
        sequential,
        parallel,
        over_zenoh,
        sandboxed,
        sandboxed_vs_trusted,
    })
}

/// Agents a run over the veth pair has this long to leave once it ended.
const REMOTE_LEAVE: Duration = Duration::from_secs(5);

/// One run of `scenario` over `link` (`host`: the second host, for [`Link::ZenohVeth`]).
fn run_over(
    scenario: &Scenario,
    path: &[Pose],
    options: &RunOptions,
    bin: &Path,
    link: Link,
    host: Option<&runner::netns::NetnsHost>,
) -> Result<RunOutcome, CliError> {
    let free_port = |ip: std::net::Ipv4Addr| -> anyhow::Result<u16> {
        Ok(std::net::TcpListener::bind((ip, 0))?.local_addr()?.port())
    };
    let endpoint = |protocol: &str, ip: std::net::Ipv4Addr| -> anyhow::Result<net::Endpoint> {
        Ok(net::Endpoint::parse(&format!(
            "{protocol}/{ip}:{}",
            free_port(ip)?
        ))?)
    };
    let mut options = options.clone();
    let mut remote_agents = Vec::new();
    match (link, host) {
        (Link::Iceoryx2, _) => {}
        (Link::Sandboxed, _) => options.sandbox = Some(runner::turns::SandboxOptions::new()),
        (Link::ZenohLoopback, _) => {
            // What a user runs by default: TLS with the run's own authority.
            let listen = endpoint("tls", std::net::Ipv4Addr::LOCALHOST)?;
            options.network = Some(NetworkOptions::new(listen));
        }
        (Link::ZenohVeth, Some(host)) => {
            // Plain TCP: the agents started in the second host bring no certificates.
            let listen = endpoint("tcp", host.local_ip)?;
            let n = scenario.agents.len();
            for i in 0..n {
                let args = [
                    "--connect".to_string(),
                    listen.to_string(),
                    "--agent".to_string(),
                    i.to_string(),
                    "--allow-plain-tcp".to_string(),
                ];
                remote_agents.push(host.spawn(bin, &args)?);
            }
            options.network = Some(NetworkOptions {
                remote: (0..n).collect(),
                ..NetworkOptions::plain(listen)
            });
        }
        (Link::ZenohVeth, None) => {
            return Err(CliError::Other(anyhow::anyhow!("no second host")));
        }
    }
    let outcome = run_scenario(scenario, path, &options);
    // The remote agents leave when told; those that do not are killed.
    let until = std::time::Instant::now() + REMOTE_LEAVE;
    for child in &mut remote_agents {
        while std::time::Instant::now() < until && matches!(child.try_wait(), Ok(None)) {
            std::thread::sleep(Duration::from_millis(10));
        }
        let _ = child.kill();
        let _ = child.wait();
    }
    outcome.map_err(|failure| CliError::Other(failure.error))
}

/// The comparison as a table for people.
pub fn table(t: &TurnsReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let [lo, hi] = t.max_step_m;
    let speed = if lo == hi {
        format!("{lo} m/step")
    } else {
        format!("{lo} to {hi} m/step")
    };
    let _ = writeln!(
        s,
        "\nturns: {} ({}, its own mode {}), {} agents ({} processes in both modes), {} steps, top speed {speed}; {} of each mode, in the order {}",
        t.scenario,
        t.file,
        t.scenario_mode,
        t.agents,
        t.agents,
        t.steps,
        if t.rounds == 1 {
            "1 run".to_string()
        } else {
            format!("{} runs", t.rounds)
        },
        t.order
            .iter()
            .map(|m| if *m == "parallel" { "P" } else { "S" })
            .collect::<Vec<_>>()
            .join(" ")
    );
    let _ = writeln!(
        s,
        "  {:<12}{:>10}{:>14}{:>14}{:>14}{:>16}{:>8}{:>12}  transport",
        "mode",
        "steps/s",
        "groups/step",
        "turn p50 us",
        "turn p99 us",
        "compute p50 us",
        "faults",
        "collisions"
    );
    for m in [&t.sequential, &t.parallel]
        .into_iter()
        .chain(&t.over_zenoh)
        .chain(&t.sandboxed)
    {
        let _ = writeln!(
            s,
            "  {:<12}{:>10.2}{:>14.2}{:>14.1}{:>14.1}{:>16.1}{:>8}{:>12}  {}",
            m.mode,
            m.steps_per_s,
            m.mean_groups_per_step,
            m.turn_us.p50,
            m.turn_us.p99,
            m.compute_us.p50,
            m.faults,
            m.collisions,
            m.transport
        );
    }
    let _ = writeln!(
        s,
        "  parallel / sequential: {:.2}x steps/s, {:.2}x turn latency p50 (steps/s per run: sequential {}, parallel {})",
        t.parallel_vs_sequential_steps_per_s,
        t.parallel_vs_sequential_turn_p50,
        runs_list(&t.sequential.steps_per_s_runs),
        runs_list(&t.parallel.steps_per_s_runs)
    );
    if let Some(c) = &t.sandboxed_vs_trusted {
        let _ = writeln!(
            s,
            "  sandboxed / trusted (sequential, parallel): turn latency p50 {:.2}x, {:.2}x; steps/s {:.2}x, {:.2}x; start-up {:.2}x, {:.2}x",
            c.turn_p50[0],
            c.turn_p50[1],
            c.steps_per_s[0],
            c.steps_per_s[1],
            c.startup_s[0],
            c.startup_s[1]
        );
    }
    s
}

fn runs_list(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.2}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The figures of `mode` over `runs`.
fn mode_report(mode: TurnMode, link: Link, runs: &[RunOutcome]) -> ModeReport {
    let summaries: Vec<_> = runs.iter().map(|o| o.run.summary()).collect();
    let steps_per_s_runs: Vec<f64> = runs.iter().map(|o| o.timing.steps_per_s).collect();
    // Every agent's first turn is a warm-up, as in the latency bench.
    let measured = || {
        runs.iter()
            .flat_map(|o| o.turn_samples.iter())
            .filter(|t| t.step > 1)
    };
    ModeReport {
        mode: mode.name(),
        transport: link.name(),
        steps_per_s: median(&steps_per_s_runs),
        mean_groups_per_step: summaries
            .iter()
            .map(|s| s.mean_groups_per_step)
            .sum::<f64>()
            / summaries.len().max(1) as f64,
        turn_us: Distribution::of_iter(measured().map(|t| t.latency_us)),
        compute_us: Distribution::of_iter(measured().map(|t| t.compute_us)),
        max_move_m: summaries.iter().map(|s| s.max_move_m).fold(0.0, f64::max),
        mean_deviation_m: summaries
            .iter()
            .map(|s| s.mean_deviation_m)
            .fold(0.0, f64::max),
        collisions: summaries.iter().map(|s| s.collisions).sum(),
        faults: summaries.iter().map(|s| s.faults.len()).sum(),
        completed: summaries.iter().all(|s| s.completed),
        wall_s: runs.iter().map(|o| o.timing.wall_s).collect(),
        startup_s: median(&runs.iter().map(|o| o.timing.startup_s).collect::<Vec<_>>()),
        steps_per_s_runs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenarios() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
    }

    #[test]
    fn a_scenario_without_a_top_speed_is_refused_before_anything_runs() {
        let file = scenarios().join("paper.toml");
        let b = TurnsBench {
            file: &file,
            rounds: 1,
            steps: None,
            verbose: false,
            links: vec![Link::Iceoryx2],
        };
        let err = prepare(&b).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("turns.mode"), "{err}");
    }

    #[test]
    fn both_modes_share_agents_and_top_speed_and_the_path_is_cut() {
        let file = scenarios().join("paper-top-speed.toml");
        let b = TurnsBench {
            file: &file,
            rounds: 1,
            steps: Some(5),
            verbose: false,
            links: vec![Link::Iceoryx2],
        };
        let p = prepare(&b).unwrap();
        assert_eq!(p.sequential.turns, TurnMode::Sequential);
        assert_eq!(p.parallel.turns, TurnMode::Parallel);
        assert_eq!(p.sequential.agents, p.parallel.agents);
        assert!(p.sequential.agents.iter().all(|a| a.max_step_m.is_some()));
        assert_eq!(p.path.len(), 6);
    }
}
