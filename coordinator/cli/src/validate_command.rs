//! `coordinator validate SCENARIO`: parse, check, and make sure the centre has a path;
//! `coordinator validate MAP.yaml`: read a ROS map_server map and merge its blocked cells.

use std::path::Path;

use runner::CliError;
use runner::loaded::load_and_plan;
use shared::world::maps::{Cell, OccupancyGrid};

use crate::cli::ValidateArgs;

/// Whether `file` names a map's YAML file (by its extension) rather than a scenario.
pub fn is_map_yaml(file: &Path) -> bool {
    file.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"))
}

/// Read the map whose YAML file is `file`, and say what it holds: its size, its cells by
/// kind, and the outlines its blocked cells (occupied or unknown) merge into.
fn validate_map(file: &Path) -> Result<(), CliError> {
    let (yaml, grid) = OccupancyGrid::load(file)?;
    let rings = grid.outlines(|c| c != Cell::Free);
    eprintln!(
        "{}: valid map: {} x {} cells of {} m ({:.2} x {:.2} m from ({}, {})), {} occupied, \
         {} unknown, {} free; the blocked cells merge into {} outlines with {} corners",
        file.display(),
        grid.width,
        grid.height,
        yaml.resolution_m,
        grid.width as f64 * yaml.resolution_m,
        grid.height as f64 * yaml.resolution_m,
        yaml.origin_m[0],
        yaml.origin_m[1],
        grid.count(Cell::Occupied),
        grid.count(Cell::Unknown),
        grid.count(Cell::Free),
        rings.len(),
        rings.iter().map(Vec::len).sum::<usize>(),
    );
    Ok(())
}

/// Carry out `validate`.
pub fn execute(args: &ValidateArgs) -> Result<(), CliError> {
    if is_map_yaml(&args.scenario) {
        return validate_map(&args.scenario);
    }
    let loaded = load_and_plan(Some(&args.scenario))?;
    let s = &loaded.scenario;
    // Polygons and a map are named only when there are some.
    let first_piece = s.map.as_ref().map_or(s.polygons.len(), |m| m.first_piece);
    let mut shapes = String::new();
    if first_piece > 0 {
        shapes += &format!(", {first_piece} polygons");
    }
    if let Some(map) = &s.map {
        shapes += &format!(
            ", a map of {} x {} cells cut into {} pieces",
            map.grid.width,
            map.grid.height,
            s.polygons.len() - first_piece
        );
    }
    eprintln!(
        "{}: valid: {} agents, {} obstacles{shapes}, centre path of {} steps",
        args.scenario.display(),
        s.agents.len(),
        s.obstacles.len(),
        loaded.centre_path.len().saturating_sub(1)
    );
    Ok(())
}
