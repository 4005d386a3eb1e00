//! `coordinator run --resume DIR`: the killed run in DIR checked and read back from its
//! log ([`load_resume`]), so that the run goes on from its last complete step.
//!
//! Everything is checked before anything is changed: a folder that is not a run, a log
//! that cannot be read (cut inside its header, or a chunk whose CRC does not match), a
//! log of another format version, of another scenario than the one named, or of a run
//! that finished, is refused (exit 2) with one line naming the file and what is wrong.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use crate::turns::FaultInjection;
use shared::control::safety;
use shared::geometry::DiskGrid;
use shared::run::record::{Recorder, Step, replay_course};
use shared::world::scenario::Scenario;

use crate::error::CliError;
use crate::run_log::{LOG_FORMAT_VERSION, LoggedRun, RUN_LOG_FILE, read_run_log};

/// A killed run, read back and checked, to go on with.
#[derive(Debug)]
pub struct Resumed {
    /// The run's folder.
    pub dir: PathBuf,
    /// The scenario as run (the log's).
    pub scenario: Scenario,
    /// The scenario file as the run was given it.
    pub source: String,
    /// The log read back.
    pub logged: Arc<LoggedRun>,
    /// The logged options that change the record.
    pub record: RecordOptions,
}

/// The options of a run that change its record, checked.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordOptions {
    /// The turn deadline.
    pub turn_deadline: Duration,
    /// The slow bound, if set.
    pub slow_turn: Option<Duration>,
    /// Whether dead agents are replaced.
    pub respawn: bool,
    /// The faults injected.
    pub faults: FaultInjection,
}

/// Read the run killed in `dir` back from its log and check that it can go on:
/// `scenario_file`, when given, must be the scenario logged.
pub fn load_resume(dir: &Path, scenario_file: Option<&Path>) -> Result<Resumed, CliError> {
    let usage = |what: String| CliError::Usage(what);
    let path = dir.join(RUN_LOG_FILE);
    let shown = path.display().to_string();
    if !dir.is_dir() {
        return Err(usage(format!("--resume {}: no such folder", dir.display())));
    }
    if !path.is_file() {
        return Err(usage(format!(
            "--resume {}: not a run folder (no {RUN_LOG_FILE} in it)",
            dir.display()
        )));
    }
    let logged = read_run_log(&path).map_err(|e| usage(e.to_string()))?;
    if logged.scenario_toml.is_empty() {
        return Err(usage(format!(
            "{shown}: no scenario in it (cut before its first chunk ended, or not a run's log)"
        )));
    }
    if logged.format_version != Some(LOG_FORMAT_VERSION) {
        return Err(usage(format!(
            "{shown}: written in log format version {}, this program resumes version {LOG_FORMAT_VERSION}",
            logged
                .format_version
                .map_or_else(|| "0 (none given)".to_string(), |v| v.to_string())
        )));
    }
    if let Some(end) = &logged.end {
        return Err(usage(format!(
            "{shown}: the run finished ({}); there is nothing to resume (`coordinator render {}` draws its outputs again)",
            if end.completed {
                "completed"
            } else {
                "stopped early"
            },
            dir.display()
        )));
    }
    let scenario = Scenario::parse(&logged.scenario_toml, &shown)
        .map_err(|e| usage(format!("{shown}: the scenario logged: {e}")))?;
    if let Some(file) = scenario_file {
        let given = crate::loaded::load_and_plan(Some(file))?;
        let same = |s: &Scenario| s.to_resolved_toml("").ok();
        if same(&given.scenario) != same(&scenario) || given.centre_path != logged.first_plan {
            return Err(usage(format!(
                "{shown}: a log of scenario `{}`, not of {}",
                scenario.name,
                file.display()
            )));
        }
    }
    let options = logged.options.clone().ok_or_else(|| {
        usage(format!(
            "{shown}: the run's options are not logged (an older format)"
        ))
    })?;
    let misbehave = options
        .misbehave
        .iter()
        .map(|m| crate::names::parse_misbehave(m))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| usage(format!("{shown}: the options logged: misbehave: {e}")))?;
    let record = RecordOptions {
        turn_deadline: Duration::from_millis(options.turn_deadline_ms.max(1)),
        slow_turn: options.slow_turn_ms.map(Duration::from_millis),
        respawn: options.respawn,
        faults: FaultInjection {
            kills: options.kills.clone(),
            deaths: options.deaths.clone(),
            misbehave,
        },
    };
    check_agents_named(scenario.agents.len(), &record)
        .map_err(|e| usage(format!("{shown}: the options logged: {e}")))?;
    if !logged.steps.is_empty() {
        let run = logged.to_run(&scenario.name, scenario.unknown.len());
        if Recorder::resume(&scenario, run).is_none() {
            return Err(usage(format!(
                "{shown}: its steps do not fit the scenario logged (another number of agents or moving obstacles)"
            )));
        }
        if let Some(last) = logged.steps.last()
            && let Err(e) = check_where_agents_stand(&scenario, last)
        {
            return Err(usage(format!(
                "{shown}: step {}: {e}: not where a run leaves its agents",
                last.step
            )));
        }
        if let Err(step) = replay_course(&scenario, &logged.first_plan, &logged.steps) {
            return Err(usage(format!(
                "{shown}: step {step}'s centre is not where the scenario's course puts it: not the log of this scenario's run"
            )));
        }
    }
    Ok(Resumed {
        dir: dir.to_path_buf(),
        source: logged.source.clone().unwrap_or_else(|| shown.clone()),
        scenario,
        logged: Arc::new(logged),
        record,
    })
}

/// Where the log leaves the agents, checked like any input before the run goes on from
/// there: every agent (dead ones too) finite, inside the field, clear of the obstacles
/// (the unknown ones too), of the polygons and of every other agent, its heading finite if
/// it has one: the safety invariant at the step the run resumes from, checked by the same
/// code as a move (a move that stays where the agent stands). The log of a real run
/// passes, its monitor having checked every move; a crafted one need not.
fn check_where_agents_stand(scenario: &Scenario, last: &Step) -> Result<(), String> {
    let bodies = last.bodies(scenario);
    let grid = safety::bodies_grid(&bodies);
    let obstacles = DiskGrid::new(scenario.static_obstacles());
    let others = safety::Others {
        bodies: &bodies,
        passing: &[],
        grid: Some(&grid),
    };
    for (agent, (body, row)) in bodies.iter().zip(&last.agents).enumerate() {
        let at = [body.position];
        safety::check_move_among(
            &scenario.field,
            &obstacles,
            &others,
            agent,
            &at[0],
            &at,
            &[],
            1,
        )
        .and_then(|()| safety::check_move_against_polygons(&scenario.polygons, body.radius_m, &at))
        .map_err(|v| format!("agent {agent} at {:?}: {v}", body.position.coords))?;
        if let Some(heading) = row.heading_rad
            && !heading.is_finite()
        {
            return Err(format!("agent {agent}'s heading is {heading}"));
        }
    }
    Ok(())
}

/// Every agent named by the options is one of the scenario's `agents`.
pub fn check_agents_named(agents: usize, record: &RecordOptions) -> Result<(), String> {
    for a in record.faults.agents_named() {
        if a >= agents {
            return Err(format!(
                "agent {a} does not exist: the scenario has {agents} agents (0 to {})",
                agents.saturating_sub(1)
            ));
        }
    }
    Ok(())
}
