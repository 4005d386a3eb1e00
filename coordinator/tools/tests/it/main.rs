//! The coordinator's integration tests, in one binary: `coordinator render` writes every
//! file, at its stated size, with agents drawn where they are (`render`); a changing world
//! renders its obstacles and plans, and `docs/outputs.md` names every summary key and CSV
//! column (`render_changing_world`); a run folder written by
//! `runner::output::write_run` reads back to the run that was written (`run_folder`).

mod render;
mod render_changing_world;
mod run_folder;
mod support;
