//! The `run` subcommand, `coordinator run [SCENARIO] [--out DIR [--force]]`: its
//! arguments checked, the run taken by [`runner::turns`], its outputs written.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use shared::geometry::Pose;
use shared::world::scenario::Scenario;

use crate::cli::RunArgs;
use runner::CliError;
use runner::loaded::load_and_plan;
use runner::output;
use runner::resume::{RecordOptions, check_agents_named, load_resume};
use runner::run_log::LoggedRun;
use runner::turns::{FaultInjection, RunOptions, run_scenario};

/// Carry out `run`: validate and plan (bad input exits 2 before anything is created),
/// take the run over agent processes ([`run_scenario`]), write the outputs. An interrupted run still writes its outputs, marked not
/// completed, and exits 1.
pub fn execute(args: &RunArgs) -> Result<(), CliError> {
    let prepared = match &args.resume {
        Some(dir) => prepare_resume(args, dir)?,
        None => prepare_new(args)?,
    };
    let Prepared {
        scenario,
        source,
        centre_path,
        dir,
        record,
        resume,
    } = prepared;
    let scenario = &scenario;
    let centre_path = &centre_path;
    let network = args.network.options().map_err(CliError::Usage)?;
    if let Some(n) = &network {
        n.check(scenario.agents.len()).map_err(CliError::Usage)?;
    }
    let sandbox = args
        .sandbox
        .options(
            scenario.agents.len(),
            network
                .as_ref()
                .map(|n| n.agents_started_here(scenario.agents.len()).count()),
        )
        .map_err(CliError::Usage)?;
    let dir = match dir {
        Some(dir) => dir,
        // Before any agent is spawned or anything created: a folder holding something is
        // refused unless --force. The folder is made now: the run writes its log into it
        // as it goes.
        None => output::OutDir::check(
            args.out
                .clone()
                .unwrap_or_else(|| output::default_run_dir(&scenario.name)),
            args.force,
        )?
        .create_in_place()?,
    };
    let log_path = dir.join(runner::run_log::RUN_LOG_FILE);
    let options = RunOptions {
        agent_bin: args.agent_bin.clone(),
        turn_deadline: record.turn_deadline,
        slow_turn: record.slow_turn,
        respawn: record.respawn,
        faults: record.faults,
        progress: !args.quiet,
        wait: args.wait,
        wake: args.wake,
        network,
        sandbox,
        log: Some(runner::run_log::LogOptions {
            path: log_path.clone(),
            source: source.clone(),
            sync: args.sync_every_steps.map_or(
                runner::run_log::SyncPolicy::EverySecond,
                runner::run_log::SyncPolicy::EverySteps,
            ),
        }),
        resume,
        ..RunOptions::default()
    };
    // A failed run still writes what it recorded, marked not completed.
    let (outcome, failure) = match run_scenario(scenario, centre_path, &options) {
        Ok(outcome) => (outcome, None),
        Err(failure) => (*failure.partial, Some(failure.error)),
    };
    // Every other output is made from the log, read back.
    let run = match runner::output::run_from_log(&log_path, scenario) {
        Ok(run) => {
            if run != outcome.run {
                tracing::error!(
                    "{}: the log read back differs from the run's own record; the outputs follow the log",
                    log_path.display()
                );
            }
            run
        }
        // A run that failed before its log was made.
        Err(e) => {
            tracing::warn!("{e:#}: the outputs follow the run's own record");
            outcome.run.clone()
        }
    };
    output::write_run(&dir, scenario, &source, &run, centre_path, &outcome.timing)?;
    let plots = if args.no_plots {
        None
    } else {
        // The data files are complete already; a failed drawing costs only the pictures.
        Some(tools::render::render_run_dir_with(
            &dir,
            tools::render::RenderOptions {
                sensing_circles: args.sensing_circles,
            },
        ))
    };
    match plots {
        Some(Ok(files)) => tracing::info!(
            "{} plot files in {}",
            files.len(),
            dir.join(tools::render::PLOTS_DIR).display()
        ),
        Some(Err(e)) => tracing::warn!("plots not drawn: {e:#}"),
        None => {}
    }
    let s = outcome.run.summary();
    // Agents with a heading: how far they face from the centre, and the longest turn.
    let headings = outcome
        .run
        .heading_summary(scenario)
        .map_or_else(String::new, |h| {
            format!(
                ", mean heading error {:.4} rad, longest turn {:.4} rad",
                h.mean_heading_error_rad, h.max_turn_rad
            )
        });
    eprintln!(
        "{}: {} agents, {} steps, {} collisions, min clearance {:.4} m, mean deviation {:.4} m{headings}, {} faults, turn latency p50 {:.0} us p99 {:.0} us, {:.2} s -> {}",
        s.scenario,
        s.agents,
        s.steps,
        s.collisions,
        s.min_clearance_m,
        s.mean_deviation_m,
        s.faults.len(),
        outcome.timing.turn_latency_us.p50,
        outcome.timing.turn_latency_us.p99,
        outcome.timing.wall_s,
        dir.display()
    );
    if let Some(error) = failure {
        return Err(CliError::Other(error.context(format!(
            "the run failed; outputs written up to step {}, marked not completed",
            outcome.run.steps.last().map_or(0, |st| st.step)
        ))));
    }
    if outcome.interrupted {
        return Err(CliError::Other(anyhow::anyhow!(
            "interrupted: outputs written up to step {}, marked not completed",
            outcome.run.steps.last().map_or(0, |st| st.step)
        )));
    }
    Ok(())
}

/// What a run starts from: a new one's scenario and options, or a killed run's.
struct Prepared {
    scenario: Scenario,
    source: String,
    centre_path: Vec<Pose>,
    /// The folder to write into, when it is there already (`--resume`).
    dir: Option<PathBuf>,
    record: RecordOptions,
    resume: Option<Arc<LoggedRun>>,
}

/// A new run: the scenario loaded and planned (bad input exits 2 before anything is
/// created), the options from the command line.
fn prepare_new(args: &RunArgs) -> Result<Prepared, CliError> {
    let loaded = load_and_plan(args.scenario.as_deref())?;
    let scenario = match args.controller {
        Some(kind) => {
            if let Some(why) = loaded.scenario.refuses_controller(kind) {
                return Err(CliError::Usage(why));
            }
            loaded.scenario.with_controller(kind)
        }
        None => loaded.scenario.clone(),
    };
    let record = RecordOptions {
        turn_deadline: Duration::from_millis(args.turn_deadline_ms.max(1)),
        slow_turn: args.slow_turn_ms.map(Duration::from_millis),
        respawn: args.respawn,
        faults: FaultInjection {
            kills: args.kill_agent.clone(),
            deaths: args.die_agent.clone(),
            misbehave: args.misbehave.clone(),
        },
    };
    check_agents_named(scenario.agents.len(), &record).map_err(CliError::Usage)?;
    Ok(Prepared {
        scenario,
        source: loaded.source,
        centre_path: loaded.centre_path,
        dir: None,
        record,
        resume: None,
    })
}

/// A killed run, from its log ([`load_resume`]).
fn prepare_resume(args: &RunArgs, dir: &std::path::Path) -> Result<Prepared, CliError> {
    let resumed = load_resume(dir, args.scenario.as_deref())?;
    tracing::info!(
        "resuming {} after step {}",
        resumed.dir.display(),
        resumed.logged.steps.last().map_or(0, |s| s.step)
    );
    Ok(Prepared {
        centre_path: resumed.logged.first_plan.clone(),
        // A log without a step: the run starts again from the start.
        resume: (!resumed.logged.steps.is_empty()).then_some(resumed.logged),
        scenario: resumed.scenario,
        source: resumed.source,
        dir: Some(resumed.dir),
        record: resumed.record,
    })
}
