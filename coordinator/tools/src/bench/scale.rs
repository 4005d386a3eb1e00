//! `coordinator bench --scale 100,300,1000`: the multi-process runtime against the size of
//! the formation, in one bench run. For every size N, a generated swarm
//! ([`Kind::Swarm`]: a block of N agents with a top speed, a sensing radius and parallel
//! turns) is measured three ways, one after the other, so that all three see the same
//! (shared, noisy) machine:
//! 1. the spawn floor: N processes of the agent executable that only print their help,
//!    started at once and waited for (what starting N processes costs, nothing else);
//! 2. `simulate()`: the reference simulation of the same scenario, every agent in this
//!    process, one after the other;
//! 3. the real run: N agent processes over iceoryx2, its start-up split into phases, its
//!    step loop, its turns, and each agent's CPU time and memory (PSS) at the end; then
//!    the same run rung by iceoryx2 events instead of the doorbells (`--wake event`),
//!    after it at the first, third, ... size and before it at the others;
//! 4. within the run, after each of its steps (and not counted in its step loop), the
//!    wake-up floor: the same agents rung the same way, group by group as the step
//!    took them, each answering an empty turn (no world, no planning, no move, no
//!    judging). What waking N processes once a step costs on this machine, whatever
//!    they compute;
//! 5. after the run, the operating system's own floor ([`super::futex_floor`]): N forked
//!    processes woken the same way, group sizes and all, each on a futex word of its
//!    own, with no channel at all.
//!
//! Reported per N, with the two ratios the runtime is judged by (start-up against the
//! spawn floor, step loop against `simulate()`), the wake-up floor against both, and
//! drawn against N in an SVG.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::Context;
use serde::Serialize;
use shared::run::simulate::simulate_along;

use super::plot::{BLUE, Curve, GREEN, GREY, ORANGE, PURPLE, SKY, ScaleChart, VERMILLION};
use super::run_options::bench_run_options;
use super::scenario::{Kind, generate_kind};
use runner::CliError;
use runner::output::{GroupTiming, StartupPhases};
use runner::stats::Distribution;
use runner::turns::{RunOutcome, WakeMode, run_scenario_with};
use shared::geometry::Pose;
use shared::world::scenario::Scenario;

/// Steps of the swarm's straight path when `--scale-steps` is not given (the length of
/// `scenarios/swarm1000.toml`'s path).
pub const DEFAULT_SCALE_STEPS: usize = 48;

/// The measurements of every size (`scale` in the report).
#[derive(Clone, Debug, Serialize)]
pub struct ScaleReport {
    /// One entry per size, in the order given.
    pub sizes: Vec<ScalePoint>,
    /// The plot of the figures against N, if drawn.
    pub plot_svg: Option<String>,
}

/// The figures of one size.
#[derive(Clone, Debug, Serialize)]
pub struct ScalePoint {
    /// Agents (one process each).
    pub agents: usize,
    /// Steps of the centre path.
    pub steps: usize,
    /// Starting N help-printing processes of the agent executable at once and waiting
    /// for them all, seconds.
    pub spawn_floor_s: f64,
    /// The run's start-up: from its start to the last agent's ready handshake, seconds.
    pub startup_s: f64,
    /// Where the start-up went.
    pub startup_phases_s: StartupPhases,
    /// `startup_s / spawn_floor_s`.
    pub startup_vs_floor: f64,
    /// `simulate()` on the same scenario and path, seconds.
    pub simulate_s: f64,
    /// The run's step loop (start-up excluded), seconds.
    pub loop_s: f64,
    /// `loop_s / simulate_s`: what the processes and the hand-overs cost.
    pub loop_vs_simulate: f64,
    /// The wake-up floor: after each step, every live agent rung an empty turn (an
    /// echo), group by group as the step took them (a group's rings at once, then its
    /// answers collected), summed over the steps, seconds. Not in `loop_s`.
    pub wake_floor_s: f64,
    /// `wake_floor_s / simulate_s`: the least a step loop of these processes woken this
    /// way can cost against `simulate()`, before any world, planning or judging.
    pub wake_floor_vs_simulate: f64,
    /// `loop_s / wake_floor_s`: the step loop against its wake-up floor.
    pub loop_vs_wake_floor: f64,
    /// Empty turns of the wake-up floors (of both runs, doorbells and events) not
    /// answered within the deadline (0 normally).
    pub wake_floor_unanswered: usize,
    /// The operating system's wake-up floor: N forked processes woken in the same group
    /// sizes, step by step, each on a futex word of its own and answering on a shared
    /// counter (no iceoryx2, no sample, no socket), seconds.
    pub futex_floor_s: f64,
    /// `futex_floor_s / simulate_s`.
    pub futex_floor_vs_simulate: f64,
    /// `wake_floor_s / futex_floor_s`: what the rings and an empty sample each way cost
    /// over a bare futex wake-up.
    pub wake_floor_vs_futex_floor: f64,
    /// The same run once more, rung by iceoryx2 events (`--wake event`) instead of the
    /// doorbells, right after it (right before it at every other size).
    pub event_rings: EventRings,
    /// Steps per second of the step loop.
    pub steps_per_s: f64,
    /// Turn groups per step (agents granted together), mean.
    pub mean_groups_per_step: f64,
    /// The groups' sizes and wall times, and how idle the machine was in the loop.
    pub groups: GroupTiming,
    /// Turn latency (world published to move held), microseconds.
    pub turn_us: Distribution,
    /// The agents' own compute time per turn, microseconds.
    pub compute_us: Distribution,
    /// Each agent process's CPU time over its whole life, seconds.
    pub agent_cpu_s: Distribution,
    /// Each agent process's proportional set size at the end of the run, KiB.
    pub agent_pss_kib: Distribution,
    /// Each agent process's resident set size at the end of the run, KiB.
    pub agent_rss_kib: Distribution,
    /// Collisions the run's record holds (0 when safe).
    pub collisions: usize,
    /// Faults of the run (0 when every agent answered every turn).
    pub faults: usize,
}

/// The figures of the run rung by iceoryx2 events (the others are of the run rung by
/// the doorbells, the default).
#[derive(Clone, Debug, Serialize)]
pub struct EventRings {
    /// Its start-up, seconds.
    pub startup_s: f64,
    /// Its step loop, seconds.
    pub loop_s: f64,
    /// `loop_s / simulate_s`.
    pub loop_vs_simulate: f64,
    /// Its wake-up floor (empty turns rung by events), seconds.
    pub wake_floor_s: f64,
    /// Its step loop against the doorbells' (`loop_s` of the size).
    pub loop_vs_doorbells: f64,
    /// Collisions its record holds.
    pub collisions: usize,
    /// Its faults.
    pub faults: usize,
}

/// The sizes of `--scale`, checked before anything runs (exit code 2 when bad).
pub fn check_sizes(sizes: &[usize], steps: usize) -> Result<(), CliError> {
    if let Some(&n) = sizes
        .iter()
        .find(|&&n| n == 0 || n > shared::control::vocabulary::MAX_AGENTS)
    {
        return Err(CliError::Usage(format!(
            "--scale {n}: a formation has 1 to {} agents",
            shared::control::vocabulary::MAX_AGENTS
        )));
    }
    if !(2..=super::run_options::MAX_BENCH_STEPS).contains(&steps) {
        return Err(CliError::Usage(format!(
            "--scale-steps: 2 to {}",
            super::run_options::MAX_BENCH_STEPS
        )));
    }
    Ok(())
}

/// Measure every size of `sizes` with the agent executable `bin`, `steps` steps each;
/// progress on stderr when `verbose`.
pub fn measure(
    sizes: &[usize],
    steps: usize,
    bin: &Path,
    verbose: bool,
) -> anyhow::Result<ScaleReport> {
    let mut points = Vec::with_capacity(sizes.len());
    for (k, &n) in sizes.iter().enumerate() {
        if verbose {
            eprintln!("bench: scale, {n} agents, {steps} steps: spawn floor, simulate(), run ...");
        }
        // Which wake mode runs first alternates from size to size.
        let point = measure_one(n, steps, bin, k % 2 == 1)?;
        if verbose {
            eprintln!(
                "bench: scale, {n} agents: start-up {:.2} s ({:.1}x the floor), step loop {:.3} s ({:.1}x simulate())",
                point.startup_s, point.startup_vs_floor, point.loop_s, point.loop_vs_simulate
            );
        }
        points.push(point);
    }
    Ok(ScaleReport {
        sizes: points,
        plot_svg: None,
    })
}

/// One real run of `scenario` along `path` rung by `wake`, with the wake-up floor
/// measured after each step (outside the step loop's time).
struct FlooredRun {
    outcome: RunOutcome,
    /// The step loop, seconds.
    loop_s: f64,
    /// The wake-up floor summed over the steps, seconds.
    wake_floor_s: f64,
    /// Empty turns of the floor not answered in time.
    wake_floor_unanswered: usize,
    /// The live agents of each group, step by step.
    group_sizes: Vec<Vec<usize>>,
}

fn run_with_floor(
    scenario: &Scenario,
    path: &[Pose],
    bin: &Path,
    wake: WakeMode,
) -> anyhow::Result<FlooredRun> {
    let (mut wake_floor_s, mut wake_floor_unanswered) = (0.0, 0);
    let mut group_sizes = Vec::with_capacity(path.len());
    let options = bench_run_options(bin, wake);
    let outcome = run_scenario_with(scenario, path, &options, &mut |ctx| {
        group_sizes.push(
            ctx.groups
                .iter()
                .map(|g| g.iter().filter(|&&a| ctx.alive[a]).count())
                .collect::<Vec<_>>(),
        );
        let started = Instant::now();
        for group in ctx.groups {
            let members: Vec<(usize, u32)> = group
                .iter()
                .filter(|&&a| ctx.alive[a])
                .filter_map(|&a| Some((a, ctx.pids.get(a).copied().flatten()?)))
                .collect();
            let answered = ctx
                .ipc
                .echo_group(&members, Instant::now() + super::run_options::ECHO_DEADLINE)?;
            wake_floor_unanswered += members.len() - answered;
        }
        wake_floor_s += started.elapsed().as_secs_f64();
        Ok(())
    })
    .map_err(|failure| failure.error)?;
    if outcome.interrupted {
        anyhow::bail!("interrupted");
    }
    let steps_run = outcome.run.steps.len().saturating_sub(1) as f64;
    let loop_s = if outcome.timing.steps_per_s > 0.0 {
        steps_run / outcome.timing.steps_per_s
    } else {
        0.0
    };
    Ok(FlooredRun {
        outcome,
        loop_s,
        wake_floor_s,
        wake_floor_unanswered,
        group_sizes,
    })
}

/// Measure `agents` agents over `steps` steps; the run rung by events before the one
/// rung by doorbells if `events_first`.
fn measure_one(
    agents: usize,
    steps: usize,
    bin: &Path,
    events_first: bool,
) -> anyhow::Result<ScalePoint> {
    let (_, scenario, path) = generate_kind(agents, steps, Kind::Swarm)?;
    let spawn_floor_s = spawn_floor(bin, agents)?;
    let started = Instant::now();
    simulate_along(&scenario, &path)
        .map_err(|e| anyhow::anyhow!("the reference simulation: {e}"))?;
    let simulate_s = started.elapsed().as_secs_f64();
    let (run, events) = if events_first {
        let events = run_with_floor(&scenario, &path, bin, WakeMode::Event)?;
        (
            run_with_floor(&scenario, &path, bin, WakeMode::Doorbell)?,
            events,
        )
    } else {
        let run = run_with_floor(&scenario, &path, bin, WakeMode::Doorbell)?;
        (run, run_with_floor(&scenario, &path, bin, WakeMode::Event)?)
    };
    let futex_floor_s = super::futex_floor::futex_floor(agents, &run.group_sizes)?;
    let FlooredRun {
        outcome,
        loop_s,
        wake_floor_s,
        wake_floor_unanswered,
        ..
    } = run;
    let summary = outcome.run.summary();
    let timing = &outcome.timing;
    Ok(ScalePoint {
        agents,
        steps,
        spawn_floor_s,
        startup_s: timing.startup_s,
        startup_phases_s: timing.startup_phases_s,
        startup_vs_floor: runner::stats::ratio(timing.startup_s, spawn_floor_s),
        simulate_s,
        loop_s,
        loop_vs_simulate: runner::stats::ratio(loop_s, simulate_s),
        wake_floor_s,
        wake_floor_vs_simulate: runner::stats::ratio(wake_floor_s, simulate_s),
        loop_vs_wake_floor: runner::stats::ratio(loop_s, wake_floor_s),
        wake_floor_unanswered: wake_floor_unanswered + events.wake_floor_unanswered,
        futex_floor_s,
        futex_floor_vs_simulate: runner::stats::ratio(futex_floor_s, simulate_s),
        wake_floor_vs_futex_floor: runner::stats::ratio(wake_floor_s, futex_floor_s),
        event_rings: EventRings {
            startup_s: events.outcome.timing.startup_s,
            loop_s: events.loop_s,
            loop_vs_simulate: runner::stats::ratio(events.loop_s, simulate_s),
            wake_floor_s: events.wake_floor_s,
            loop_vs_doorbells: runner::stats::ratio(events.loop_s, loop_s),
            collisions: events.outcome.run.summary().collisions,
            faults: events.outcome.run.faults.len(),
        },
        steps_per_s: timing.steps_per_s,
        mean_groups_per_step: summary.mean_groups_per_step,
        groups: timing.groups.clone(),
        turn_us: timing.turn_latency_us,
        compute_us: timing.compute_us,
        agent_cpu_s: timing.agent_cpu_s,
        agent_pss_kib: timing.agent_pss_kib,
        agent_rss_kib: timing.agent_rss_kib,
        collisions: summary.collisions,
        faults: outcome.run.faults.len(),
    })
}

/// Start `agents` processes of `bin --help` at once and wait for every one: the floor of
/// starting that many agent processes, seconds.
fn spawn_floor(bin: &Path, agents: usize) -> anyhow::Result<f64> {
    let started = Instant::now();
    let mut children = Vec::with_capacity(agents);
    for _ in 0..agents {
        let child = Command::new(bin)
            .arg("--help")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .with_context(|| format!("starting {} --help", bin.display()));
        match child {
            Ok(c) => children.push(c),
            Err(e) => {
                // Every process started so far is waited for before giving up.
                for mut c in children {
                    let _ = c.wait();
                }
                return Err(e);
            }
        }
    }
    for mut c in children {
        let status = c.wait().context("waiting for an agent --help")?;
        if !status.success() {
            anyhow::bail!("{} --help failed: {status}", bin.display());
        }
    }
    Ok(started.elapsed().as_secs_f64())
}

/// The plot of `r`: the times against N (start-up and its floor, the step loop and
/// `simulate()`), then the two ratios.
pub fn charts(r: &ScaleReport) -> Vec<ScaleChart> {
    let curve = |label: &str, color, value: &dyn Fn(&ScalePoint) -> f64| Curve {
        label: label.into(),
        points: r
            .sizes
            .iter()
            .map(|p| (p.agents as f64, value(p)))
            .collect(),
        color,
    };
    vec![
        ScaleChart {
            title: "start-up and step loop against the number of agents".into(),
            y_desc: "seconds (log scale)".into(),
            curves: vec![
                curve("start-up", BLUE, &|p| p.startup_s),
                curve("spawn floor (N agent --help)", GREY, &|p| p.spawn_floor_s),
                curve("step loop", VERMILLION, &|p| p.loop_s),
                curve("step loop rung by iceoryx2 events", PURPLE, &|p| {
                    p.event_rings.loop_s
                }),
                curve("simulate(), one process", GREEN, &|p| p.simulate_s),
                curve("wake-up floor (empty turns)", ORANGE, &|p| p.wake_floor_s),
                curve("futex floor (no channel)", SKY, &|p| p.futex_floor_s),
            ],
        },
        ScaleChart {
            title: "the ratios: start-up / spawn floor, step loop and floors / simulate()".into(),
            y_desc: "ratio (log scale)".into(),
            curves: vec![
                curve("start-up / spawn floor", BLUE, &|p| p.startup_vs_floor),
                curve("step loop / simulate()", VERMILLION, &|p| {
                    p.loop_vs_simulate
                }),
                curve("wake-up floor / simulate()", ORANGE, &|p| {
                    p.wake_floor_vs_simulate
                }),
                curve("futex floor / simulate()", SKY, &|p| {
                    p.futex_floor_vs_simulate
                }),
            ],
        },
    ]
}

/// The table of the scale figures, for people.
pub fn table(r: &ScaleReport) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "\nscale (generated swarm, parallel turns, trusted agents; ratios measured side by side):"
    );
    let _ = writeln!(
        t,
        "{:>6} {:>6} | {:>9} {:>9} {:>7} | {:>8} {:>8} {:>8} {:>8} | {:>9} {:>9} {:>7} {:>8} | {:>9} {:>7} {:>9} {:>7} | {:>9} {:>9} | {:>9} {:>8} {:>9} {:>8} {:>9} {:>9}",
        "agents",
        "steps",
        "start s",
        "floor s",
        "ratio",
        "prepare",
        "spawn",
        "handshk",
        "scan",
        "loop s",
        "simul s",
        "ratio",
        "steps/s",
        "wake s",
        "/simul",
        "futex s",
        "/simul",
        "ev loop",
        "ev wake",
        "turn p50",
        "groups",
        "size max",
        "idle",
        "cpu ms",
        "PSS KiB"
    );
    for p in &r.sizes {
        let ph = &p.startup_phases_s;
        let _ = writeln!(
            t,
            "{:>6} {:>6} | {:>9.3} {:>9.3} {:>6.1}x | {:>8.3} {:>8.3} {:>8.3} {:>8.3} | {:>9.3} {:>9.3} {:>6.1}x {:>8.1} | {:>9.3} {:>6.1}x {:>9.3} {:>6.1}x | {:>9.3} {:>9.3} | {:>9.1} {:>8.2} {:>9.0} {:>7.0}% {:>9.1} {:>9.0}",
            p.agents,
            p.steps,
            p.startup_s,
            p.spawn_floor_s,
            p.startup_vs_floor,
            ph.prepare,
            ph.spawn,
            ph.handshakes,
            ph.intruder_scan,
            p.loop_s,
            p.simulate_s,
            p.loop_vs_simulate,
            p.steps_per_s,
            p.wake_floor_s,
            p.wake_floor_vs_simulate,
            p.futex_floor_s,
            p.futex_floor_vs_simulate,
            p.event_rings.loop_s,
            p.event_rings.wake_floor_s,
            p.turn_us.p50,
            p.mean_groups_per_step,
            p.groups.size.max,
            p.groups.loop_idle_share.unwrap_or(f64::NAN) * 1e2,
            p.agent_cpu_s.p50 * 1e3,
            p.agent_pss_kib.p50
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_out_of_range_are_refused_before_anything_runs() {
        assert!(check_sizes(&[1, 300, 1000], DEFAULT_SCALE_STEPS).is_ok());
        assert!(check_sizes(&[0], DEFAULT_SCALE_STEPS).is_err());
        assert!(
            check_sizes(
                &[shared::control::vocabulary::MAX_AGENTS + 1],
                DEFAULT_SCALE_STEPS
            )
            .is_err()
        );
        assert!(check_sizes(&[10], 1).is_err());
    }
}
