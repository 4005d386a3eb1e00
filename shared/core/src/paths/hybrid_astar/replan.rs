//! Online replanning: one goal, many starts, a growing obstacle map. [`Replanner`] keeps
//! the goal-side heuristic between calls; [`first_blocked_pose`] tells when the current
//! path needs replanning.

use super::collision::Checker;
use super::error::PlanError;
use super::heuristic::Holonomic;
use super::plan::{plan_with_checker, validate_inputs};
use super::settings::HybridAStarSettings;
use crate::geometry::{Disk, Field, Point, Polygon, Pose};

/// A planner for one field, goal and settings, asked again and again from new start poses
/// as the known obstacles change (the formation centre replanning online).
///
/// Each call gives exactly the path [`plan`](super::plan()) would give for the same start
/// and obstacles, faster. What is kept between calls is everything of the search that does
/// not depend on the start: the obstacle-aware heuristic (the fine grid's blocked cells,
/// the flood fill of the cells that reach the goal, and the coarse grid's distances from
/// the goal, as far as earlier searches settled them), together with the obstacle list it
/// was built for.
///
/// - Same obstacles as the last time the heuristic was needed: all of it is reused as is.
/// - Obstacles only added (the previous list is a prefix of the new one): it is updated in
///   place. Only the fine cells the added obstacles touch are tested again; the flood fill
///   is redone only if a reachable cell became blocked; the coarse distances are repaired,
///   not restarted: settled cells whose shortest-path branch to the goal avoids the newly
///   blocked cells keep their distance, the others are settled again on demand. The state
///   is the one a rebuild would reach, so the paths are the same.
/// - Anything else (an obstacle removed, moved or reordered): it is rebuilt.
///
/// The search itself (its open list and cells) starts afresh from each start pose, and the
/// obstacles are indexed again on each call (cheap next to the search). When the straight
/// Reeds-Shepp (or Dubins) shot to the goal is free, no heuristic is needed and none is
/// built or updated.
///
/// ```
/// use shared::geometry::{Disk, Field, Pose};
/// use shared::paths::hybrid_astar::{HybridAStarSettings, Replanner, first_blocked_pose};
///
/// let field = Field::new(60.0, 30.0);
/// let settings = HybridAStarSettings::new(2.0, 0.5, false);
/// let goal = Pose::new(55.0, 15.0, 0.0);
/// let mut replanner = Replanner::new(field, goal, settings)?;
/// let mut obstacles = vec![Disk::new(20.0, 10.0, 2.0)];
/// let path = replanner.plan_from(&Pose::new(5.0, 15.0, 0.0), &obstacles)?;
/// assert_eq!(first_blocked_pose(&field, &path, &obstacles, 0.5), None);
///
/// // An obstacle shows up on the way: replan from where the centre is now.
/// obstacles.push(Disk::new(40.0, 15.0, 2.0));
/// let blocked = first_blocked_pose(&field, &path, &obstacles, 0.5).expect("in the way");
/// let here = path[blocked / 2];
/// let new_path = replanner.plan_from(&here, &obstacles)?;
/// assert_eq!((new_path[0], new_path[new_path.len() - 1]), (here, goal));
/// assert_eq!(first_blocked_pose(&field, &new_path, &obstacles, 0.5), None);
/// # Ok::<(), shared::paths::hybrid_astar::PlanError>(())
/// ```
///
/// Cloning copies the kept heuristic with it.
#[derive(Clone)]
pub struct Replanner {
    field: Field,
    goal: Pose,
    settings: HybridAStarSettings,
    /// The heuristic and the obstacles (true radii, in the order given) it was built for.
    heuristic: Option<(Vec<Disk>, Holonomic)>,
    /// Static polygon obstacles every path keeps clear of.
    polygons: Vec<Polygon>,
}

impl Replanner {
    /// A replanner to `goal` in `field`. Fails with [`PlanError::InvalidSettings`] when the
    /// settings or the field are out of range (as [`plan`](super::plan()) would), and with
    /// [`PlanError::GoalBlocked`] when the goal is not finite.
    pub fn new(field: Field, goal: Pose, settings: HybridAStarSettings) -> Result<Self, PlanError> {
        validate_inputs(&field, &[], &settings)?;
        if !(goal.x_m.is_finite() && goal.y_m.is_finite() && goal.heading_rad.is_finite()) {
            return Err(PlanError::GoalBlocked);
        }
        Ok(Self {
            field,
            goal,
            settings,
            heuristic: None,
            polygons: Vec::new(),
        })
    }

    /// The same replanner keeping every path clear of the static `polygons` too.
    pub fn with_polygons(mut self, polygons: &[Polygon]) -> Self {
        self.polygons = polygons.to_vec();
        self.heuristic = None;
        self
    }

    /// The goal every path ends at.
    pub fn goal(&self) -> &Pose {
        &self.goal
    }

    /// Plan from `start` to the goal among `obstacles` (true radii, the whole known map
    /// every time): the path [`plan`](super::plan()) gives, with the same guarantees (it
    /// keeps `settings.clearance_m` from every obstacle and the field's edges, begins with
    /// `start` and ends with the goal, both exactly), and the same errors.
    ///
    /// Reuses the heuristic of the previous calls when `obstacles` extends (or equals) the
    /// list it was built for, updating it for the added obstacles; rebuilds it otherwise
    /// (see [`Replanner`]). Deterministic: the result depends on the start and the
    /// obstacles only, not on the earlier calls.
    pub fn plan_from(&mut self, start: &Pose, obstacles: &[Disk]) -> Result<Vec<Pose>, PlanError> {
        validate_inputs(&self.field, obstacles, &self.settings)?;
        let checker = Checker::new(&self.field, obstacles, &self.settings)
            .with_polygons(&self.polygons, &self.settings);
        let (field, goal, settings) = (&self.field, &self.goal, &self.settings);
        let cache = &mut self.heuristic;
        plan_with_checker(field, checker, start, goal, settings, |checker| {
            let reusable = matches!(cache, Some((known, _)) if obstacles.starts_with(known));
            if !reusable {
                *cache = None;
            }
            let (known, holonomic) = cache.get_or_insert_with(|| {
                (
                    obstacles.to_vec(),
                    Holonomic::new(field, checker, goal, settings),
                )
            });
            if obstacles.len() > known.len() {
                // The checker holds the obstacles inflated, in the order given.
                holonomic.add_obstacles(field, checker, &checker.grid.disks()[known.len()..]);
                known.extend_from_slice(&obstacles[known.len()..]);
            }
            holonomic
        })
        .map(|(path, _)| path)
    }
}

impl std::fmt::Debug for Replanner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Replanner")
            .field("field", &self.field)
            .field("goal", &self.goal)
            .field("settings", &self.settings)
            .field(
                "heuristic_obstacles",
                &self.heuristic.as_ref().map(|(known, _)| known.len()),
            )
            .finish()
    }
}

/// Poses per bounding box in [`first_blocked_pose`].
const CHUNK: usize = 32;

/// Index of the first pose of `path` whose position is closer than `clearance_m` to the
/// boundary of any of `obstacles` (distance to the centre `< radius_m + clearance_m`), or
/// outside `field` inset by `clearance_m` (a pose on the inset edge is inside; a pose that
/// is not finite is outside), or `None` when the path is clear.
///
/// Only positions are checked, not the chords between them (the dense paths of
/// [`plan`](super::plan()) and [`resample`](super::resample()) poses a step apart are what
/// it is meant for). The path is taken in chunks of 32 poses, and only the obstacles whose
/// grown bounding box meets a chunk's bounding box are tested against its poses: a long
/// path with a few obstacles costs little more than one pass over the poses.
pub fn first_blocked_pose(
    field: &Field,
    path: &[Pose],
    obstacles: &[Disk],
    clearance_m: f64,
) -> Option<usize> {
    let c = clearance_m;
    let in_field =
        |p: &Point| p.x >= c && p.y >= c && p.x <= field.width_m - c && p.y <= field.height_m - c;
    let hits = |p: &Point, d: &Disk| (p - d.centre).norm() < d.radius_m + c;
    let mut near: Vec<&Disk> = Vec::with_capacity(obstacles.len());
    for (k, chunk) in path.chunks(CHUNK).enumerate() {
        let (mut min, mut max) = (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in chunk {
            min = Point::new(min.x.min(p.x_m), min.y.min(p.y_m));
            max = Point::new(max.x.max(p.x_m), max.y.max(p.y_m));
        }
        near.clear();
        near.extend(obstacles.iter().filter(|d| {
            let r = d.radius_m + c;
            d.centre.x + r > min.x
                && d.centre.x - r < max.x
                && d.centre.y + r > min.y
                && d.centre.y - r < max.y
        }));
        let blocked = chunk.iter().position(|pose| {
            let p = pose.position();
            !in_field(&p) || near.iter().any(|d| hits(&p, d))
        });
        if let Some(i) = blocked {
            return Some(k * CHUNK + i);
        }
    }
    None
}
