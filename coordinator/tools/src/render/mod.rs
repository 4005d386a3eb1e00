//! `coordinator render RUN_DIR`: the figures and the animation of a run, re-created from
//! the files `coordinator run` wrote (nothing is re-planned), into `RUN_DIR/plots/`:
//!
//! - `field.png`/`.svg`: obstacles with their safety margins, start and goal poses, and
//!   the centre's Hybrid A* path with heading arrows (the paper's Figs. 2, 3, 6); in a
//!   changing world also the moving obstacles' routes and first and last places, the
//!   obstacles unknown at the start (hatched, with the step they were found at) and every
//!   plan of the centre under the path it followed (`plans.csv`, `obstacles.csv`);
//! - `formation.png`/`.svg`: the formation at its start pose, each agent's safety circle
//!   and its slot (Fig. 7), and where an agent with a heading faces (a tick to its rim);
//! - `deviation.png`/`.svg`: each agent's deviation from its slot over the steps and the
//!   formation's mean (Fig. 9), faults marked;
//! - `clearance.png`/`.svg`: the smallest agent-agent and agent-obstacle clearance at
//!   every step against the zero line, faults marked;
//! - `animation.gif`: the whole run (the paper's video; Fig. 8 at every frame), with each
//!   agent's sensing radius as a faint circle on request ([`RenderOptions`]), each moving
//!   obstacle where it stands at the frame's step and each unknown obstacle outlined until
//!   it became known, filled after; an agent with a heading shows it as a line from its
//!   centre to its rim.
//!
//! Titles name what the run's model adds to the paper's: the top speed, the sensing
//! radius and parallel turns, when the scenario has them (`scene::model_note`).
//!
//! Colours come from the Okabe-Ito palette (`palette.rs`); text uses an embedded font
//! (`font.rs`), so no system font library is needed.

pub mod animation;
pub mod canvas;
mod data;
pub mod field;
pub(crate) mod font;
pub mod formation;
mod geom;
mod gif_writer;
mod header;
pub mod layout;
mod map_figure;
pub mod metrics;
mod palette;
mod scene;
pub mod series;
mod text;

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use runner::CliError;
use runner::output::write_atomically;

/// Arguments of `render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A run directory written by `run` (scenario.toml, path.csv, trajectory.csv,
    /// moves.csv, summary.json; plans.csv and obstacles.csv when present).
    pub run_dir: PathBuf,
    /// In the animation, draw each live agent's sensing radius as a faint circle (when
    /// the scenario has `formation.sensing_radius_m`).
    #[arg(long, visible_alias = "sensing")]
    pub sensing_circles: bool,
}

pub use data::{RunData, RunDirError};

pub use runner::output::PLOTS_DIR;

/// What to draw beyond the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// In the animation, each live agent's sensing radius as a faint circle (when the
    /// scenario has one).
    pub sensing_circles: bool,
}

/// Render every figure and the animation of the run in `dir` into `dir/plots/`; returns
/// the files written.
pub fn render_run_dir(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    render_run_dir_with(dir, RenderOptions::default())
}

/// [`render_run_dir`] with `options`.
pub fn render_run_dir_with(dir: &Path, options: RenderOptions) -> anyhow::Result<Vec<PathBuf>> {
    let data = RunData::load(dir)?;
    render_data_with(&data, &dir.join(PLOTS_DIR), options)
}

/// Render every figure and the animation of `data` into `out` (created if needed);
/// returns the files written.
pub fn render_data(data: &RunData, out: &Path) -> anyhow::Result<Vec<PathBuf>> {
    render_data_with(data, out, RenderOptions::default())
}

/// [`render_data`] with `options`.
pub fn render_data_with(
    data: &RunData,
    out: &Path,
    options: RenderOptions,
) -> anyhow::Result<Vec<PathBuf>> {
    font::ensure_registered()?;
    // The folder may be someone else's (a run folder handed over, its `plots`): created
    // if missing, never followed if it is a link.
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("creating {}", parent.display()))?;
    }
    shared::output_file::real_folder(out).with_context(|| format!("creating {}", out.display()))?;
    let metrics = metrics::per_step(data);
    let mut written = Vec::new();
    written.extend(canvas::write_figure(
        out,
        "field",
        &field::FieldFigure::new(data),
    )?);
    written.extend(canvas::write_figure(
        out,
        "formation",
        &formation::FormationFigure::new(data),
    )?);
    written.extend(canvas::write_figure(
        out,
        "deviation",
        &series::SeriesFigure::deviation(data, &metrics),
    )?);
    written.extend(canvas::write_figure(
        out,
        "clearance",
        &series::SeriesFigure::clearance(data, &metrics),
    )?);
    let gif = animation::Animation::with_sensing_circles(data, &metrics, options.sensing_circles)
        .write_gif(Vec::new())
        .context("drawing animation.gif")?;
    let gif_path = out.join("animation.gif");
    write_atomically(&gif_path, &gif)?;
    written.push(gif_path);
    Ok(written)
}

/// `coordinator render`: a bad run directory is a usage error (exit code 2) naming the
/// file; a failure to draw or write is exit code 1.
pub fn execute(args: &RenderArgs) -> Result<(), CliError> {
    // A killed run: its outputs made from its log first.
    if let Some((last, completed)) = runner::output::recover_run_dir(&args.run_dir)
        .map_err(|e| CliError::Usage(format!("{e:#}")))?
    {
        let how = if completed {
            "the run ended complete; its other outputs were missing"
        } else {
            "the run did not end: marked not completed"
        };
        eprintln!(
            "recovered steps 0 to {last} from {} ({how})",
            args.run_dir.join(runner::run_log::RUN_LOG_FILE).display()
        );
    }
    let data = RunData::load(&args.run_dir).map_err(|e| CliError::Usage(e.to_string()))?;
    let out = args.run_dir.join(PLOTS_DIR);
    // The folder handed in is input: a `plots` that is a link or no folder is refused
    // (exit code 2) before anything is drawn.
    shared::output_file::real_folder(&out).map_err(|e| CliError::Usage(e.to_string()))?;
    let options = RenderOptions {
        sensing_circles: args.sensing_circles,
    };
    let written = render_data_with(&data, &out, options)?;
    eprintln!("rendered {} files -> {}", written.len(), out.display());
    Ok(())
}
