//! `coordinator compare SCENARIO...`: every controller on every scenario (and, with
//! `--turns` and `--turn-order`, in every turn mode and turn order), through the same
//! processes, protocol and safety monitor, tabulated side by side; each run's own files
//! in a folder of their own.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use serde::Serialize;
use shared::control::vocabulary::{ControllerKind, TurnMode, TurnOrder};
use shared::run::record::{FaultKind, Run};
use shared::world::scenario::{Scenario, ScenarioError};

use runner::CliError;
use runner::loaded::load_and_plan;
use runner::names::{parse_controller, parse_turn_mode, parse_turn_order};
use runner::output;
use runner::turns::{RunOptions, run_scenario};

/// Arguments of `compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Scenario files (TOML); the embedded paper example when none is given.
    pub scenarios: Vec<PathBuf>,
    /// The controllers to compare (comma-separated; default: all).
    #[arg(long, alias = "planners", value_delimiter = ',', value_parser = parse_controller)]
    pub controllers: Vec<ControllerKind>,
    /// Turn modes to run every controller in (comma-separated: sequential, parallel,
    /// simultaneous, the last for orca only; default: each scenario's own `[turns] mode`,
    /// orca in its own model wherever every agent has a top speed). Parallel and
    /// simultaneous need a top speed.
    #[arg(long, value_name = "MODE", value_delimiter = ',', value_parser = parse_turn_mode)]
    pub turns: Vec<TurnMode>,
    /// Turn orders to run every controller in, for each turn mode (comma-separated:
    /// agent, front-first; default: each scenario's own `[turns] order`).
    #[arg(long, value_name = "ORDER", value_delimiter = ',', value_parser = parse_turn_order)]
    pub turn_order: Vec<TurnOrder>,
    /// Output folder for `compare.csv`, `compare.md` and one folder per run (default
    /// `runs/compare-<UTC time>`). One that exists and is not empty is refused unless
    /// `--force`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the `--out` folder whole when it exists and is not empty.
    #[arg(long)]
    pub force: bool,
    /// The agent executable (default: `agent` beside this program).
    #[arg(long)]
    pub agent_bin: Option<PathBuf>,
}

/// One row of the comparison table.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Scenario name.
    pub scenario: String,
    /// Controller name.
    pub controller: String,
    /// Whether the run went through the whole path.
    pub completed: bool,
    /// Agent records overlapping another body at the end of a step (0 when safe).
    pub collisions: usize,
    /// Moves the safety monitor refused (unsafe moves the controller tried).
    pub unsafe_moves: usize,
    /// Smallest clearance over the run, in metres.
    pub min_clearance_m: f64,
    /// Mean deviation, in metres.
    pub mean_deviation_m: f64,
    /// Largest deviation, in metres.
    pub max_deviation_m: f64,
    /// Mean deviation at the last step, in metres.
    pub final_mean_deviation_m: f64,
    /// Agent-steps in which a live agent off its slot did not move at all.
    pub deadlocked_steps: usize,
    /// Agent compute time per turn, median, in microseconds.
    pub compute_p50_us: f64,
    /// Agent compute time per turn, 99th percentile, in microseconds.
    pub compute_p99_us: f64,
    /// The turn mode run (`sequential` or `parallel`).
    pub turns: String,
    /// The longest single move of any agent, in metres (as in `summary.json`).
    pub max_move_m: f64,
    /// Steps per second of the step loop (as in `summary.json`).
    pub steps_per_s: f64,
    /// The agent whose deviation was the largest (the first such, by step then agent).
    pub worst_agent: usize,
    /// The step of that largest deviation.
    pub worst_step: usize,
    /// The turn order run (`agent` or `front-first`).
    pub turn_order: String,
}

/// Agent-steps where a live agent off its slot did not move.
pub fn deadlocked_steps(run: &Run) -> usize {
    run.steps
        .iter()
        .skip(1)
        .flat_map(|s| s.agents.iter())
        .filter(|a| a.alive && a.waypoints.len() == 1 && a.deviation_m > 1e-6)
        .count()
}

/// The live agent and step of the largest deviation of `run` (the first, by step then
/// agent; agent 0 at step 0 when nobody ever deviates).
pub fn worst_agent_step(run: &Run) -> (usize, usize) {
    let mut worst = (0, 0, 0.0);
    for (k, step) in run.steps.iter().enumerate() {
        for (i, a) in step.agents.iter().enumerate() {
            if a.alive && a.deviation_m > worst.2 {
                worst = (i, k, a.deviation_m);
            }
        }
    }
    (worst.0, worst.1)
}

/// The turn mode and turn order a run was asked for on the command line (`None`: the
/// scenario's own).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Asked {
    mode: Option<TurnMode>,
    order: Option<TurnOrder>,
}

impl Asked {
    /// The names of what was asked for, mode first.
    fn names(&self) -> impl Iterator<Item = &'static str> {
        self.mode
            .map(|m| m.name())
            .into_iter()
            .chain(self.order.map(|o| o.name()))
    }
}

/// `scenario` with its turns taken in `mode`; parallel turns need a top speed for every
/// agent, as in a scenario file (refused as `source: turns.mode: ...`, exit code 2).
pub(crate) fn with_turn_mode(
    scenario: &Scenario,
    source: &str,
    mode: TurnMode,
) -> Result<Scenario, ScenarioError> {
    if mode != TurnMode::Sequential
        && let Some(i) = scenario.agents.iter().position(|a| a.max_step_m.is_none())
    {
        return Err(ScenarioError::Invalid {
            file: source.to_string(),
            field: "turns.mode".into(),
            reason: format!(
                "{} turns need a top speed for every agent (formation.max_step_m), and agent {i} has none",
                mode.name()
            ),
        });
    }
    let mut s = scenario.clone();
    s.turns = mode;
    Ok(s)
}

fn row(run: &Run, controller: ControllerKind, scenario: &Scenario, timing: &output::Timing) -> Row {
    let s = run.summary();
    let compute = &timing.compute_us;
    let (worst_agent, worst_step) = worst_agent_step(run);
    Row {
        scenario: s.scenario.clone(),
        controller: controller.name().to_string(),
        completed: s.completed,
        collisions: s.collisions,
        unsafe_moves: s
            .faults
            .iter()
            .filter(|f| f.kind == FaultKind::Rejected)
            .count(),
        min_clearance_m: s.min_clearance_m,
        mean_deviation_m: s.mean_deviation_m,
        max_deviation_m: s.max_deviation_m,
        final_mean_deviation_m: s.final_mean_deviation_m,
        deadlocked_steps: deadlocked_steps(run),
        compute_p50_us: compute.p50,
        compute_p99_us: compute.p99,
        turns: scenario.turns.name().to_string(),
        max_move_m: s.max_move_m,
        steps_per_s: timing.steps_per_s,
        worst_agent,
        worst_step,
        turn_order: scenario.turn_order.name().to_string(),
    }
}

/// The table as Markdown.
pub fn markdown(rows: &[Row]) -> String {
    let mut md = String::from(
        "| scenario | controller | completed | collisions | unsafe moves refused | min clearance (m) | mean dev. (m) | max dev. (m) | final dev. (m) | stuck agent-steps | compute p50 (us) | compute p99 (us) | turns | max move (m) | steps/s | worst agent @ step | turn order |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {} | {:.1} | {:.1} | {} | {:.4} | {:.1} | {} @ {} | {} |\n",
            r.scenario,
            r.controller,
            r.completed,
            r.collisions,
            r.unsafe_moves,
            r.min_clearance_m,
            r.mean_deviation_m,
            r.max_deviation_m,
            r.final_mean_deviation_m,
            r.deadlocked_steps,
            r.compute_p50_us,
            r.compute_p99_us,
            r.turns,
            r.max_move_m,
            r.steps_per_s,
            r.worst_agent,
            r.worst_step,
            r.turn_order
        ));
    }
    md
}

fn csv_bytes(rows: &[Row]) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    Ok(w.into_inner()?)
}

/// The folder name of one run of the comparison: `<scenario>-<controller>`, followed by
/// the turn mode and the turn order where they were asked for (`asked`: `-parallel`,
/// `-front-first`), made of letters, digits, `-` and `_` only, with `-2`, `-3`, ... when
/// two scenarios share a name.
fn run_folder_name(
    scenario: &str,
    controller: ControllerKind,
    asked: &Asked,
    taken: &mut Vec<String>,
) -> String {
    let clean = output::file_name_part(scenario);
    let mut base = format!("{clean}-{}", controller.name());
    for name in asked.names() {
        base.push('-');
        base.push_str(name);
    }
    let name = (1..)
        .map(|k| {
            if k == 1 {
                base.clone()
            } else {
                format!("{base}-{k}")
            }
        })
        .find(|n| !taken.contains(n))
        .unwrap_or(base);
    taken.push(name.clone());
    name
}

/// Carry out `compare`: every scenario is validated and the output folder checked before any
/// agent starts. One line per run on stderr, then the table; each run's files (its
/// `summary.json` with the refused moves in `faults`, its resolved `scenario.toml`, ...)
/// go to a folder of their own inside the output folder.
pub fn execute(args: &CompareArgs) -> Result<(), CliError> {
    let controllers = if args.controllers.is_empty() {
        ControllerKind::ALL.to_vec()
    } else {
        args.controllers.clone()
    };
    // Validate every scenario, in every turn mode asked for, before running anything.
    let loaded = if args.scenarios.is_empty() {
        vec![load_and_plan(None)?]
    } else {
        args.scenarios
            .iter()
            .map(|f| load_and_plan(Some(f)))
            .collect::<Result<Vec<_>, _>>()?
    };
    // Each mode and each order once, in the order given (none: the scenario's own).
    let modes = each_once(&args.turns);
    let orders = each_once(&args.turn_order);
    let runs = loaded
        .iter()
        .map(|l| {
            let mut scenarios = Vec::new();
            for &mode in &modes {
                let in_mode = match mode {
                    None => l.scenario.clone(),
                    Some(m) => with_turn_mode(&l.scenario, &l.source, m)?,
                };
                for &order in &orders {
                    let mut s = in_mode.clone();
                    if let Some(o) = order {
                        s.turn_order = o;
                    }
                    scenarios.push((s, Asked { mode, order }));
                }
            }
            Ok((l, scenarios))
        })
        .collect::<Result<Vec<_>, ScenarioError>>()?;
    // A controller asked for by name must be able to run every scenario; by default the
    // ones a scenario refuses (beside polygons) are left out of it, said on stderr.
    if !args.controllers.is_empty()
        && let Some(why) = loaded
            .iter()
            .flat_map(|l| {
                controllers
                    .iter()
                    .map(|&k| l.scenario.refuses_controller(k))
            })
            .flatten()
            .next()
    {
        return Err(CliError::Usage(why));
    }
    let out = output::OutDir::check(
        args.out
            .clone()
            .unwrap_or_else(|| output::default_run_dir("compare")),
        args.force,
    )?;
    let options = RunOptions {
        agent_bin: args.agent_bin.clone(),
        progress: false,
        ..RunOptions::default()
    };
    // Dropped on an error or an interruption: nothing half-written is left.
    let staging = out.begin()?;
    let mut rows = Vec::new();
    let mut taken = Vec::new();
    for (l, scenarios) in &runs {
        for (in_mode, asked) in scenarios {
            for &controller in &controllers {
                if let Some(why) = in_mode.refuses_controller(controller) {
                    eprintln!("left out: {why}");
                    continue;
                }
                let mut scenario = in_mode.with_controller(controller);
                // Without a mode asked for, ORCA runs in its own model (every agent at
                // once) wherever every agent has a top speed.
                if asked.mode.is_none()
                    && controller == ControllerKind::Orca
                    && scenario.agents.iter().all(|a| a.max_step_m.is_some())
                {
                    scenario.turns = TurnMode::Simultaneous;
                }
                let folder = run_folder_name(&scenario.name, controller, asked, &mut taken);
                // The turn mode and order are named wherever they were asked for.
                let mut label = format!("{} with {}", scenario.name, controller.name());
                if let Some(m) = asked.mode {
                    label.push_str(&format!(", {} turns", m.name()));
                }
                if let Some(o) = asked.order {
                    label.push_str(&format!(", {} order", o.name()));
                }
                let outcome = run_scenario(&scenario, &l.centre_path, &options)
                    .map_err(|failure| CliError::Other(failure.error))?;
                if outcome.interrupted {
                    return Err(CliError::Other(anyhow::anyhow!(
                        "interrupted during {label}: nothing written"
                    )));
                }
                output::write_run(
                    &staging.path().join(&folder),
                    &scenario,
                    &l.source,
                    &outcome.run,
                    &l.centre_path,
                    &outcome.timing,
                )?;
                let r = row(&outcome.run, controller, &scenario, &outcome.timing);
                // One line per run, when it is done.
                eprintln!(
                    "{label}: {}, {} collisions, {} unsafe moves refused, {} faults, {:.1} steps/s -> {folder}/",
                    if r.completed {
                        "completed"
                    } else {
                        "not completed"
                    },
                    r.collisions,
                    r.unsafe_moves,
                    outcome.run.faults.len(),
                    r.steps_per_s
                );
                rows.push(r);
            }
        }
    }
    write(staging.path(), &rows)?;
    let dir = staging.commit()?;
    eprint!("{}", markdown(&rows));
    eprintln!("-> {}", dir.display());
    Ok(())
}

/// Each value of `asked` once, in the order given, as `Some`; `[None]` when none was.
fn each_once<T: Copy + PartialEq>(asked: &[T]) -> Vec<Option<T>> {
    let mut once: Vec<Option<T>> = Vec::new();
    for &v in asked {
        if !once.contains(&Some(v)) {
            once.push(Some(v));
        }
    }
    if once.is_empty() {
        once.push(None);
    }
    once
}

fn write(dir: &Path, rows: &[Row]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    output::write_atomically(&dir.join("compare.csv"), &csv_bytes(rows)?)?;
    output::write_atomically(&dir.join("compare.md"), markdown(rows).as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_folders_are_plain_names_and_never_shared() {
        let mut taken = Vec::new();
        let own = Asked::default();
        let name = "paper example/1";
        let a = run_folder_name(name, ControllerKind::Cbf, &own, &mut taken);
        let b = run_folder_name(name, ControllerKind::Cbf, &own, &mut taken);
        let c = run_folder_name(name, ControllerKind::BestPoint, &own, &mut taken);
        let parallel = Asked {
            mode: Some(TurnMode::Parallel),
            order: None,
        };
        let d = run_folder_name(name, ControllerKind::Orca, &parallel, &mut taken);
        let front = Asked {
            mode: Some(TurnMode::Parallel),
            order: Some(TurnOrder::FrontFirst),
        };
        let e = run_folder_name(name, ControllerKind::Orca, &front, &mut taken);
        assert_eq!(a, "paper_example_1-cbf");
        assert_eq!(b, "paper_example_1-cbf-2");
        assert_eq!(c, "paper_example_1-best-point");
        assert_eq!(d, "paper_example_1-orca-parallel");
        assert_eq!(e, "paper_example_1-orca-parallel-front-first");
    }

    #[test]
    fn parallel_turns_need_a_top_speed_and_sequential_never_does() {
        let paper = Scenario::paper();
        let err = with_turn_mode(&paper, "paper.toml", TurnMode::Parallel).unwrap_err();
        assert_eq!(err.field(), "turns.mode");
        assert!(
            err.to_string().starts_with("paper.toml: turns.mode: "),
            "{err}"
        );
        let seq = with_turn_mode(&paper, "paper.toml", TurnMode::Sequential).unwrap();
        assert_eq!(seq.turns, TurnMode::Sequential);
        let mut fast = paper.clone();
        for a in &mut fast.agents {
            a.max_step_m = Some(0.5);
        }
        let par = with_turn_mode(&fast, "x.toml", TurnMode::Parallel).unwrap();
        assert_eq!(par.turns, TurnMode::Parallel);
        assert_eq!(par.agents, fast.agents);
    }
}
