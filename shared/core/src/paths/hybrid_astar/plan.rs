//! The entry point: validate the input, try the straight shot, then search.

use std::borrow::BorrowMut;

use super::analytic::analytic_expansion;
use super::collision::Checker;
use super::error::PlanError;
use super::heuristic::{Holonomic, MAX_GRID_CELLS};
use super::primitive::dense_path;
use super::resample::path_length_m;
use super::search::{PlanStats, Search};
use super::settings::HybridAStarSettings;
use crate::geometry::{Disk, Field, Polygon, Pose};

/// Plan a path for the formation centre from `start` to `goal`.
///
/// `obstacles` are the true obstacles (not inflated): the path keeps
/// `settings.clearance_m` from every obstacle's boundary and from the field's edges. The
/// result is dense (consecutive poses at most `settings.sample_spacing_m` apart along the
/// path), begins with `start` and ends with `goal`, both exactly as given; feed it to
/// [`resample`](super::resample()) for evenly spaced steps.
///
/// ```
/// use shared::geometry::{Disk, Field, Pose};
/// use shared::paths::hybrid_astar::{HybridAStarSettings, path_length_m, plan, resample};
///
/// // A disk of radius 2 m right on the straight line from start to goal.
/// let field = Field::new(40.0, 30.0);
/// let obstacles = [Disk::new(20.0, 15.0, 2.0)];
/// let settings = HybridAStarSettings::new(2.0, 0.5, false);
/// let (start, goal) = (Pose::new(5.0, 15.0, 0.0), Pose::new(35.0, 15.0, 0.0));
/// let path = plan(&field, &obstacles, &start, &goal, &settings)?;
/// assert_eq!((path.first(), path.last()), (Some(&start), Some(&goal)));
/// // The path goes around the disk, 0.5 m clear of it, and not far out of the way.
/// let clear = |p: &Pose| (p.position() - obstacles[0].centre).norm() >= 2.0 + 0.5;
/// assert!(path.iter().all(clear));
/// let length_m = path_length_m(&path);
/// assert!(length_m > 30.0 && length_m < 33.0, "{length_m}");
/// let steps = resample(&path, 0.25);
/// assert_eq!(steps[0], start);
/// # Ok::<(), shared::paths::hybrid_astar::PlanError>(())
/// ```
pub fn plan(
    field: &Field,
    obstacles: &[Disk],
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
) -> Result<Vec<Pose>, PlanError> {
    plan_with_stats(field, obstacles, start, goal, settings).map(|(path, _)| path)
}

/// [`plan`], also returning the search's figures.
pub fn plan_with_stats(
    field: &Field,
    obstacles: &[Disk],
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
) -> Result<(Vec<Pose>, PlanStats), PlanError> {
    plan_among_polygons(field, obstacles, &[], start, goal, settings)
}

/// [`plan_with_stats`] among `polygons` too (true shapes): every piece of the path keeps
/// the clearance from them as from the disks (an arc through its chords, each kept clear
/// by the arc's bulge as well). The search's heuristic ignores the polygons, which keeps
/// it a lower bound.
pub fn plan_among_polygons(
    field: &Field,
    obstacles: &[Disk],
    polygons: &[Polygon],
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
) -> Result<(Vec<Pose>, PlanStats), PlanError> {
    validate_inputs(field, obstacles, settings)?;
    let checker = Checker::new(field, obstacles, settings).with_polygons(polygons, settings);
    plan_with_checker(field, checker, start, goal, settings, |checker| {
        Holonomic::new(field, checker, goal, settings)
    })
}

/// Everything of [`plan_with_stats`] after the inputs were validated and the obstacles
/// indexed in `checker`: check the start and the goal, try the straight shot, then search
/// with the heuristic `holonomic` gives for `checker`'s obstacles (only asked for when the
/// straight shot fails).
pub(super) fn plan_with_checker<H: BorrowMut<Holonomic>>(
    field: &Field,
    mut checker: Checker,
    start: &Pose,
    goal: &Pose,
    settings: &HybridAStarSettings,
    holonomic: impl FnOnce(&Checker) -> H,
) -> Result<(Vec<Pose>, PlanStats), PlanError> {
    let finite = |p: &Pose| p.x_m.is_finite() && p.y_m.is_finite() && p.heading_rad.is_finite();
    if !finite(start) || !checker.point_free(&start.position()) {
        return Err(PlanError::StartBlocked);
    }
    if !finite(goal) || !checker.point_free(&goal.position()) {
        return Err(PlanError::GoalBlocked);
    }
    // The straight shot first, before paying for the heuristic grid.
    if let Some(tail) = analytic_expansion(&mut checker, settings, start, goal) {
        let path = dense_path(
            start,
            goal,
            tail.iter().map(|p| (*p, p.end())),
            settings.sample_spacing_m,
        );
        let length_m = path_length_m(&path);
        let stats = PlanStats {
            expansions: 0,
            analytic_attempts: 1,
            length_m,
        };
        return Ok((path, stats));
    }
    let mut holonomic = holonomic(&checker);
    Search::new(
        field,
        checker,
        holonomic.borrow_mut(),
        start,
        goal,
        settings,
    )
    .run()
}

/// Check the settings, the field's size against the grid limit and the obstacles.
pub(super) fn validate_inputs(
    field: &Field,
    obstacles: &[Disk],
    settings: &HybridAStarSettings,
) -> Result<(), PlanError> {
    settings.validate()?;
    if !(field.width_m.is_finite()
        && field.height_m.is_finite()
        && field.width_m > 0.0
        && field.height_m > 0.0)
    {
        return Err(PlanError::InvalidSettings(
            "the field must have a positive finite size",
        ));
    }
    if obstacles.iter().any(|d| {
        !(d.centre.x.is_finite()
            && d.centre.y.is_finite()
            && d.radius_m.is_finite()
            && d.radius_m >= 0.0)
    }) {
        return Err(PlanError::InvalidSettings(
            "obstacles must be finite with a radius >= 0",
        ));
    }
    let grid_cells =
        (field.width_m / settings.cell_m).ceil() * (field.height_m / settings.cell_m).ceil();
    if grid_cells > MAX_GRID_CELLS {
        return Err(PlanError::InvalidSettings(
            "cell_m is too small for the field (over 2^24 cells)",
        ));
    }
    Ok(())
}
