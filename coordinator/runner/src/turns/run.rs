//! A run from end to end: the world it starts from, its resources opened (the agent
//! binary, the run's prefix and private folder, the mission file, the agents, the
//! channels, the Zenoh router: `run_handle.rs`) and its log, the driven steps, and the
//! release of the resources that happens whatever went wrong.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use shared::geometry::Pose;
use shared::run::record::Recorder;
use shared::world::scenario::Scenario;

use super::driver::Driver;
use super::options::RunOptions;
use super::outcome::{Progress, RunFailure, RunOutcome, outcome};
use super::run_handle::RunBuilder;
use super::step_report::{BetweenSteps, BetweenStepsFn, tell_step_done};
use crate::run_log::{LogThread, RunLogWriter};

/// Run `scenario` along `centre_path` with one agent process per agent.
pub fn run_scenario(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
) -> Result<RunOutcome, RunFailure> {
    run_scenario_between(scenario, centre_path, options, None)
}

/// [`run_scenario`] calling `between_steps` after every step (benchmarks measure their
/// references there, in the same run; an error ends the run).
pub fn run_scenario_with(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
    between_steps: &mut dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()>,
) -> Result<RunOutcome, RunFailure> {
    run_scenario_between(scenario, centre_path, options, Some(between_steps))
}

/// [`run_scenario`], with `between_steps` called after every step if given: the world
/// to start from, the run's resources opened, its steps driven, the resources released
/// whatever happened, the outcome.
fn run_scenario_between(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
    between_steps: Option<&mut BetweenStepsFn<'_>>,
) -> Result<RunOutcome, RunFailure> {
    let started = Instant::now();
    let start = centre_path.first().copied().unwrap_or(scenario.path.start);
    let mut progress = Progress::default();
    let fail = |error: anyhow::Error, recorder: &Recorder, progress: Progress| RunFailure {
        error,
        partial: Box::new(outcome(
            recorder.snapshot(),
            progress,
            String::new(),
            started,
        )),
    };
    // A resumed run goes on from its log's last step (checked by `run --resume`).
    let mut recorder = match options.resume.as_deref() {
        None => Recorder::new(scenario, start),
        Some(logged) => {
            let run = logged.to_run(&scenario.name, scenario.unknown.len());
            match Recorder::resume(scenario, run) {
                Some(recorder) => recorder,
                None => {
                    let error = anyhow::anyhow!("the log's last step does not fit the scenario");
                    return Err(fail(error, &Recorder::new(scenario, start), progress));
                }
            }
        }
    };
    let opened = RunBuilder { scenario, options }
        .open(recorder.world().alive())
        .and_then(|handle| Ok((open_log(options, scenario, centre_path)?, handle)));
    let (mut log, mut handle) = match opened {
        Ok(opened) => opened,
        Err(e) => return Err(fail(e, &recorder, progress)),
    };
    let spawn_s = handle.early.as_ref().map_or(0.0, |e| e.spawn_s);
    progress.startup_phases.prepare = started.elapsed().as_secs_f64() - spawn_s;

    let driven = catch_unwind(AssertUnwindSafe(|| {
        Driver::new(
            scenario,
            options,
            &mut handle,
            &mut progress,
            log.as_mut(),
            between_steps,
        )
        .drive(&mut recorder, centre_path, started)
    }));

    // Whatever happened, stop the agents and clean up before reporting.
    let prefix = handle.prefix().to_string();
    let cleaned = handle.release();
    let error = match driven {
        Ok(Ok(())) => cleaned.err(),
        Ok(Err(e)) => Some(e),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            Some(anyhow::anyhow!("the coordinator panicked: {what}"))
        }
    };
    let completed = progress.completed && !progress.gave_up && error.is_none();
    let error = match log.map(|log| log.finish(completed, progress.gave_up)) {
        Some(Err(e)) if error.is_none() => Some(e.into()),
        _ => error,
    };
    let run = if completed {
        recorder.finish(true)
    } else {
        recorder.snapshot()
    };
    let result = outcome(run, progress, prefix, started);
    match error {
        None => Ok(result),
        Some(error) => Err(RunFailure {
            error,
            partial: Box::new(result),
        }),
    }
}

/// The run's log, from step 0 on, if asked for (a run killed from here leaves every step
/// before the one under way), written by a thread of its own.
fn open_log(
    options: &RunOptions,
    scenario: &Scenario,
    centre_path: &[Pose],
) -> anyhow::Result<Option<LogThread>> {
    let Some(log) = options.log.as_ref() else {
        return Ok(None);
    };
    let writer = match options.resume.as_deref() {
        Some(logged) => RunLogWriter::create_resumed(log, scenario, logged)?,
        None => RunLogWriter::create(log, scenario, centre_path, &options.logged())?,
    };
    Ok(Some(LogThread::start(writer, tell_step_done)?))
}
