//! What follows each step of a run ([`StepReport`]): the step written to the run's log,
//! the progress bar moved on, `step N done` told (tests time their kills by it), and the
//! caller's hook called (benchmarks measure their references there).

use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use shared::run::record::Recorder;
use shared::world::course::Course;

use super::outcome::TurnSample;
use crate::ipc::CoordinatorIpc;
use crate::procfs;
use crate::run_log::{CourseSoFar, LogThread, TurnMessage};

/// The `tracing` target of the line logged when a step is done (`step N done`):
/// `RUST_LOG=coordinator::progress=info` shows one such line per step on stderr.
pub const PROGRESS_TARGET: &str = "coordinator::progress";

/// What the hook of [`super::run_scenario_with`] sees between two steps.
pub struct BetweenSteps<'a> {
    /// The step just finished.
    pub step: usize,
    /// The run's prefix (every resource of the run starts with it).
    pub prefix: &'a str,
    /// The run's ports (benchmarks ring the agents' echo through them).
    pub ipc: &'a CoordinatorIpc,
    /// Which agents are alive.
    pub alive: &'a [bool],
    /// The step's groups of turns (agents granted together), in the order taken.
    pub groups: &'a [Vec<usize>],
    /// Each agent's process id, if it has a process.
    pub pids: &'a [Option<u32>],
}

/// What a caller does after every step ([`super::run_scenario_with`]).
pub type BetweenStepsFn<'a> = dyn FnMut(BetweenSteps<'_>) -> anyhow::Result<()> + 'a;

/// A step just recorded, as its report tells it.
pub(super) struct StepSeen<'a> {
    /// The step.
    pub(super) step: usize,
    /// Which agents are alive.
    pub(super) alive: &'a [bool],
    /// The step's groups of turns, in the order taken.
    pub(super) groups: &'a [Vec<usize>],
    /// Each agent's process id, if it has a process (only asked for with a hook).
    pub(super) pids: Option<&'a [Option<u32>]>,
}

/// What follows each step: the log, the progress bar, the caller's hook.
pub(super) struct StepReport<'a> {
    /// The run's log, handed every step as it ends (written by a thread of its own,
    /// which also tells each step done once it is in the file).
    log: Option<&'a mut LogThread>,
    /// How many of the turn samples are in the log.
    turns_logged: usize,
    /// What the caller does after every step (benchmarks), if anything.
    between_steps: Option<&'a mut BetweenStepsFn<'a>>,
    /// How long the caller's hook took, seconds: not the step loop's time.
    between_s: f64,
    /// The machine's CPU ticks (idle, all) during the caller's hook.
    between_ticks: (u64, u64),
    /// The progress bar of the steps (hidden unless shown).
    bar: ProgressBar,
}

impl<'a> StepReport<'a> {
    /// Each step handed to `log`, then to `between_steps`, if given; no bar shown.
    pub(super) fn new(
        log: Option<&'a mut LogThread>,
        between_steps: Option<&'a mut BetweenStepsFn<'_>>,
    ) -> Self {
        Self {
            log,
            turns_logged: 0,
            // Reborrowed for the report's lifetime (a trait object's bound shortens only
            // through a coercion, which an `Option` does not make by itself).
            between_steps: between_steps.map(|f| f as &mut BetweenStepsFn<'_>),
            between_s: 0.0,
            between_ticks: (0, 0),
            bar: ProgressBar::hidden(),
        }
    }

    /// Show a progress bar of `steps` steps of scenario `name` (if `enabled`), at `step`.
    pub(super) fn show_progress(&mut self, steps: usize, name: &str, enabled: bool, step: usize) {
        self.bar = progress_bar(steps, name, enabled);
        self.bar.set_position(step as u64);
    }

    /// A step is open: the bar grows if the course waited or was replanned.
    pub(super) fn step_opened(&mut self) {
        if self.bar.position() + 1 >= self.bar.length().unwrap_or(0) {
            // The course waited or was replanned: the path ahead is longer.
            self.bar.inc_length(1);
        }
    }

    /// Whether a caller's hook runs after every step.
    pub(super) fn has_hook(&self) -> bool {
        self.between_steps.is_some()
    }

    /// Log the step just recorded in `recorder`, with the turns of `samples` not logged
    /// yet and the centre's `course` (none at step 0).
    pub(super) fn log_step(
        &mut self,
        recorder: &Recorder<'_>,
        course: Option<&Course<'_>>,
        samples: &[TurnSample],
    ) -> anyhow::Result<()> {
        let course = course.map(CourseSoFar::of);
        let Some(log) = self.log.as_deref_mut() else {
            return Ok(());
        };
        let Some(step) = recorder.steps().last() else {
            return Ok(());
        };
        let turns = samples[self.turns_logged..]
            .iter()
            .map(|t| TurnMessage {
                step: t.step,
                agent: t.agent,
                latency_us: t.latency_us,
                compute_us: t.compute_us,
            })
            .collect();
        log.log_step(step, recorder.faults(), course, turns)?;
        self.turns_logged = samples.len();
        Ok(())
    }

    /// The step `seen` is done (and logged): move the bar on, tell it done, and call the
    /// caller's hook with the run's ports `ipc`.
    pub(super) fn step_done(
        &mut self,
        seen: &StepSeen<'_>,
        ipc: &CoordinatorIpc,
    ) -> anyhow::Result<()> {
        self.bar.inc(1);
        // For whoever follows the run from outside (tests time their kills by it); with
        // a log, its thread tells each step once it is in the file.
        if self.log.is_none() {
            tell_step_done(seen.step);
        }
        let (Some(between_steps), Some(pids)) = (self.between_steps.as_mut(), seen.pids) else {
            return Ok(());
        };
        let ticks_before = procfs::machine_cpu_ticks();
        let between = Instant::now();
        between_steps(BetweenSteps {
            step: seen.step,
            prefix: ipc.prefix(),
            ipc,
            alive: seen.alive,
            groups: seen.groups,
            pids,
        })?;
        let ticks_after = procfs::machine_cpu_ticks();
        self.between_s += between.elapsed().as_secs_f64();
        if let Some((from, to)) = ticks_before.zip(ticks_after) {
            self.between_ticks.0 += to.0.saturating_sub(from.0);
            self.between_ticks.1 += to.1.saturating_sub(from.1);
        }
        Ok(())
    }

    /// The steps are over: the bar cleared; how long the caller's hook took in all
    /// (seconds) and the machine's CPU ticks (idle, all) meanwhile.
    pub(super) fn finish(&mut self) -> (f64, (u64, u64)) {
        self.bar.finish_and_clear();
        (self.between_s, self.between_ticks)
    }
}

/// Tell that `step` is done: the `step N done` line of [`PROGRESS_TARGET`] (not for step
/// 0, the start).
pub(super) fn tell_step_done(step: usize) {
    if step > 0 {
        tracing::info!(target: PROGRESS_TARGET, "step {step} done");
    }
}

/// The progress bar of a run of `steps` steps of scenario `name` (hidden unless
/// `enabled`; drawn only on a terminal).
fn progress_bar(steps: usize, name: &str, enabled: bool) -> ProgressBar {
    if !enabled {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(steps as u64), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} steps, {elapsed} (eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(name.to_string());
    bar
}
