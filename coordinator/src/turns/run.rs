//! A run from end to end: set-up (the agent binary, the run's prefix and private
//! folder, the mission file, the channels, the Zenoh router), the driven steps, and the
//! clean-up that happens whatever went wrong.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::{Duration, Instant};

use indicatif::ProgressBar;

use shared::geometry::Pose;
use shared::record::Recorder;
use shared::scenario::Scenario;
use wire::{RunPrefix, RunRoot};

use super::driver::{BetweenSteps, BetweenStepsFn, Driver, EarlyStart, agent_args, tell_step_done};
use super::hand_over::HandOver;
use super::lateness::TurnHistory;
use super::options::{RunOptions, SandboxOptions};
use super::outcome::{Progress, RunFailure, RunOutcome, outcome};
use crate::agent_uids::AgentUids;
use crate::agents::{self, AgentProcesses, StartGate};
use crate::ipc::CoordinatorIpc;
use crate::network::Router;

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

/// [`run_scenario`], with `between_steps` called after every step if given.
fn run_scenario_between(
    scenario: &Scenario,
    centre_path: &[Pose],
    options: &RunOptions,
    between_steps: Option<&mut BetweenStepsFn<'_>>,
) -> Result<RunOutcome, RunFailure> {
    let started = Instant::now();
    let n = scenario.agents.len();
    let start = centre_path.first().copied().unwrap_or(scenario.path.start);
    // A resumed run goes on from its log's last step (checked by `run --resume`).
    let resumed = options.resume.as_deref().map(|logged| {
        Recorder::resume(
            scenario,
            logged.to_run(&scenario.name, scenario.unknown.len()),
        )
    });
    let mut progress = Progress::default();
    let mut recorder = match resumed {
        None => Recorder::new(scenario, start),
        Some(Some(recorder)) => recorder,
        Some(None) => {
            return Err(RunFailure {
                error: anyhow::anyhow!("the log's last step does not fit the scenario"),
                partial: Box::new(outcome(
                    Recorder::new(scenario, start).snapshot(),
                    progress,
                    String::new(),
                    started,
                )),
            });
        }
    };
    let fail = |error: anyhow::Error, recorder: &Recorder, progress: Progress| RunFailure {
        error,
        partial: Box::new(outcome(
            recorder.snapshot(),
            progress,
            String::new(),
            started,
        )),
    };
    let bin = match agents::locate_agent_binary(options.agent_bin.as_deref()) {
        Ok(bin) => bin,
        Err(e) => return Err(fail(e, &recorder, progress)),
    };
    if let Err(e) = agents::raise_fd_limit(n) {
        return Err(fail(e, &recorder, progress));
    }
    crate::stale_runs::clean_stale_runs();
    // No other run on this machine uses it, and no one can predict it.
    let prefix = match RunPrefix::new_random() {
        Ok(prefix) => prefix.to_string(),
        Err(e) => return Err(fail(e.into(), &recorder, progress)),
    };
    // The run's private folder, made before anything else of the run (a folder already
    // there is refused); dropped last: after the agents and the node.
    let root = match RunRoot::create(&prefix) {
        Ok(root) => root,
        Err(e) => return Err(fail(e.into(), &recorder, progress)),
    };
    // Agents of different runs are different users: this run's ids, claimed until it ends.
    let uids = match options.sandbox.map(|s| AgentUids::claim(s.first_uid, n)) {
        None => None,
        Some(Ok(uids)) => Some(uids),
        Some(Err(e)) => return Err(fail(e.into(), &recorder, progress)),
    };
    let with_claimed_uids;
    let options = match (&options.sandbox, &uids) {
        (Some(sandbox), Some(uids)) if uids.first() != sandbox.first_uid => {
            tracing::info!(
                "agents' user ids {} to {} (from {}: taken by another run or a live process)",
                uids.first(),
                u64::from(uids.first()) + n as u64 - 1,
                sandbox.first_uid
            );
            with_claimed_uids = RunOptions {
                sandbox: Some(SandboxOptions {
                    first_uid: uids.first(),
                    ..*sandbox
                }),
                ..options.clone()
            };
            &with_claimed_uids
        }
        _ => options,
    };
    // The scenario as run, for the agents to read at start-up.
    let mission_digest = match wire::write_mission(&prefix, scenario) {
        Ok(digest) => digest,
        Err(e) => return Err(fail(e.into(), &recorder, progress)),
    };
    let run_cgroup = options
        .sandbox
        .as_ref()
        .and_then(|_| sandbox_cgroup(&prefix));
    let mut procs = AgentProcesses::new(bin, &prefix, n).with_cgroup(run_cgroup.clone());
    // The agents start now, while this process has few open files for each start to
    // copy, and wait behind a gate until their channels exist ([`StartGate`]). Over a
    // network their relays need the router's settings first: they start later.
    let mut early = match options.network {
        Some(_) => None,
        None => start_early(options, &mut procs, &recorder, &mission_digest, &run_cgroup),
    };
    // Whatever fails from here on stops the agents started and removes their group.
    let abort = |procs: &mut AgentProcesses| {
        procs.stop_all(Duration::from_secs(2));
        if let Some(group) = &run_cgroup
            && let Err(e) = group.remove(Duration::from_secs(2))
        {
            tracing::warn!("the run's control group: {e}");
        }
    };
    let mut ipc = match CoordinatorIpc::create(&prefix, scenario, options.wake) {
        Ok(ipc) => ipc,
        Err(e) => {
            abort(&mut procs);
            crate::stale_runs::remove_run_files(&prefix);
            return Err(fail(e, &recorder, progress));
        }
    };
    // Until this run is cleaned up, a second interrupt removes what it holds and leaves.
    let _forced_exit_cleans = crate::force_quit::RunGuard::new(&prefix, run_cgroup.clone());
    let router = match options
        .network
        .as_ref()
        .map(|network| Router::open(network, n, root.path()))
        .transpose()
    {
        Ok(router) => router,
        Err(e) => {
            abort(&mut procs);
            drop(ipc);
            crate::stale_runs::remove_run_files(&prefix);
            return Err(fail(e, &recorder, progress));
        }
    };
    // The log, from step 0 on: a run killed from here leaves every step before the one
    // under way.
    let mut log = match options
        .log
        .as_ref()
        .map(|log| match options.resume.as_deref() {
            Some(logged) => crate::run_log::RunLogWriter::create_resumed(log, scenario, logged),
            None => {
                crate::run_log::RunLogWriter::create(log, scenario, centre_path, &options.logged())
            }
        })
        .map(|created| {
            created.and_then(|writer| crate::run_log::LogThread::start(writer, tell_step_done))
        })
        .transpose()
    {
        Ok(log) => log,
        Err(e) => {
            abort(&mut procs);
            if let Some(router) = router {
                router.close();
            }
            drop(ipc);
            crate::stale_runs::remove_run_files(&prefix);
            return Err(fail(e.into(), &recorder, progress));
        }
    };
    let spawn_s = early.as_ref().map_or(0.0, |e| e.spawn_s);
    progress.startup_phases.prepare = started.elapsed().as_secs_f64() - spawn_s;

    let driven = catch_unwind(AssertUnwindSafe(|| {
        Driver {
            scenario,
            options,
            ipc: &mut ipc,
            procs: &mut procs,
            progress: &mut progress,
            history: TurnHistory::new(
                n,
                options.max_missed_turns as usize,
                options.late_window_turns as usize,
            ),
            hand_over: HandOver::new(options.wait.spins(), n),
            senses: scenario.agents.iter().any(|a| a.sensing_radius_m.is_some()),
            run_cgroup: run_cgroup.is_some(),
            network: router.as_ref().map(Router::options),
            log: log.as_mut(),
            turns_logged: 0,
            mission_digest,
            early: early.take(),
            // Reborrowed for the driver's lifetime (a trait object's bound shortens only
            // through a coercion, which an `Option` does not make by itself).
            between_steps: between_steps.map(|f| f as &mut BetweenStepsFn<'_>),
            between_s: 0.0,
            between_ticks: (0, 0),
            bar: ProgressBar::hidden(),
        }
        .drive(&mut recorder, centre_path, started)
    }));

    // Whatever happened, stop the agents and clean up before reporting.
    for i in procs.running() {
        let _ = ipc.notify_quit(i);
    }
    procs.stop_all(Duration::from_secs(2));
    // Its sweep kills and reaps whatever the sandboxed agents left in their groups.
    drop(procs);
    if let Some(group) = &run_cgroup
        && let Err(e) = group.remove(Duration::from_secs(2))
    {
        tracing::warn!("the run's control group: {e}");
    }
    if let Some(router) = router {
        router.close();
    }
    let cleaned = ipc.shut_down();
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

/// Start every agent alive in `recorder` behind a new gate. Each fails alone: its failure
/// is handed to the driver, which freezes or replaces it. Without a gate (no pipe to be
/// had), none: the driver starts them once the channels exist.
fn start_early(
    options: &RunOptions,
    procs: &mut AgentProcesses,
    recorder: &Recorder<'_>,
    mission_digest: &wire::MissionDigest,
    run_cgroup: &Option<wire::cgroup::CgroupDirs>,
) -> Option<EarlyStart> {
    let spawning = Instant::now();
    let gate = match StartGate::new() {
        Ok(gate) => gate,
        Err(e) => {
            tracing::warn!("{e:#}: the agents start once their channels exist");
            return None;
        }
    };
    let mut failed = Vec::new();
    for (agent, _) in recorder.alive().iter().enumerate().filter(|(_, a)| **a) {
        // A fresh run's channels start at generation 0, and so do a resumed run's.
        let args = agent_args(
            options,
            agent,
            false,
            0,
            mission_digest,
            None,
            run_cgroup.is_some(),
        );
        if let Err(e) = procs.spawn_behind(agent, &args, &gate) {
            failed.push((agent, format!("its process could not be started: {e:#}")));
        }
    }
    Some(EarlyStart {
        gate,
        failed,
        spawn_s: spawning.elapsed().as_secs_f64(),
    })
}

/// The run's control group for its sandboxed agents, made; `None` (with a warning) where
/// the machine's cgroups cannot be used: the agents are then bounded by their users'
/// process limits only.
fn sandbox_cgroup(prefix: &str) -> Option<wire::cgroup::CgroupDirs> {
    let made = wire::cgroup::CgroupDirs::for_run(prefix).and_then(|group| {
        group.create()?;
        Ok(group)
    });
    match made {
        Ok(group) => Some(group),
        Err(e) => {
            tracing::warn!(
                "no control groups for the sandboxed agents ({e}): only their process limits hold"
            );
            None
        }
    }
}
