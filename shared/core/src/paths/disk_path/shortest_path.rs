//! The entry point: the shortest free path between two points, by rounds of growing
//! ellipse bound over the tangent graph, with the barrier test to give up early.

use std::cmp::Ordering;
use std::ops::ControlFlow;

use super::barrier::separated;
use super::error::PathError;
use super::path::DiskPath;
use super::tangent_graph::Planner;
use super::tolerance::FREE_TOLERANCE_M;
use crate::geometry::{Disk, FreeSpace, Point};

/// Shortest free path from `from` to `to` in `space`.
///
/// `space`'s disks are the already inflated obstacles; the path keeps a signed clearance of
/// at least `-`[`FREE_TOLERANCE_M`] from each of them and stays inside the field. Start and
/// goal may lie on disk boundaries. `from == to` gives a single zero-length segment.
///
/// ```
/// use std::f64::consts::PI;
///
/// use shared::paths::disk_path::{PathError, PathPiece, shortest_path};
/// use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};
///
/// // One disk of radius 1 m between start and goal.
/// let grid = DiskGrid::new(vec![Disk::new(5.0, 5.0, 1.0)]);
/// let layers = [&grid];
/// let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
/// let (from, to) = (Point::new(2.0, 5.0), Point::new(8.0, 5.0));
/// let path = shortest_path(&space, &from, &to)?;
/// // Tangent, arc around the disk, tangent: two tangents of length sqrt(3^2 - 1^2) and
/// // the arc between the tangent points.
/// assert!(matches!(
///     path.pieces[..],
///     [PathPiece::Segment { .. }, PathPiece::Arc { .. }, PathPiece::Segment { .. }]
/// ));
/// let expected_m = 2.0 * 8f64.sqrt() + (PI - 2.0 * (1.0f64 / 3.0).acos());
/// assert!((path.length_m() - expected_m).abs() < 1e-9);
/// assert_eq!((path.start(), path.end()), (from, to));
/// // A goal inside the disk has no path.
/// let inside = Point::new(5.5, 5.0);
/// assert_eq!(shortest_path(&space, &from, &inside), Err(PathError::GoalNotFree));
/// # Ok::<(), PathError>(())
/// ```
pub fn shortest_path(space: &FreeSpace, from: &Point, to: &Point) -> Result<DiskPath, PathError> {
    if !space.is_free(from, FREE_TOLERANCE_M) {
        return Err(PathError::StartNotFree);
    }
    if !space.is_free(to, FREE_TOLERANCE_M) {
        return Err(PathError::GoalNotFree);
    }
    if from == to || space.is_segment_free(from, to, FREE_TOLERANCE_M) {
        return Ok(DiskPath::straight(*from, *to));
    }
    search_path(space, from, to)
}

/// The search part of [`shortest_path`], for free end points whose straight segment is
/// blocked.
pub(super) fn search_path(
    space: &FreeSpace,
    from: &Point,
    to: &Point,
) -> Result<DiskPath, PathError> {
    if space.surely_apart(from, to) {
        return Err(PathError::Unreachable);
    }
    let direct_m = (to - from).norm();
    // The ellipse covers the field once it holds the four corners (the field is convex).
    let cover_m = space
        .field
        .corners()
        .iter()
        .map(|c| (c - from).norm() + (c - to).norm())
        .fold(0.0, f64::max);
    let mut bound_m = direct_m + direct_m.max(3.0 * space.max_radius_m()).max(1.0);
    loop {
        let last_round = bound_m.partial_cmp(&cover_m) != Some(Ordering::Less);
        let limit_m = if last_round { f64::INFINITY } else { bound_m };
        let circles = candidate_disks(space, from, to, limit_m);
        let mut planner = Planner::new(space, *from, *to, &circles, limit_m);
        match planner.search() {
            Some((nodes, cost)) if last_round || cost.0 <= bound_m + FREE_TOLERANCE_M => {
                return Ok(planner.build_path(&nodes));
            }
            // A path exists but is longer than the bound: widen.
            Some(_) => {}
            None => {
                if last_round || separated(&space.field, from, to, &circles) {
                    return Err(PathError::Unreachable);
                }
            }
        }
        bound_m = (2.0 * bound_m).min(cover_m);
    }
}

/// Disks that meet the field and may meet the ellipse `|x - s| + |x - t| <= limit_m`
/// (a superset: `|c - s| + |c - t| <= limit_m + 2 r`), in the grid's deterministic order.
fn candidate_disks(space: &FreeSpace, s: &Point, t: &Point, limit_m: f64) -> Vec<Disk> {
    let r_max = space.max_radius_m();
    let field = &space.field;
    // The ellipse lies in the disk of radius limit/2 around the midpoint of s and t.
    let mid = nalgebra::center(s, t);
    let half_m = 0.5 * limit_m + r_max;
    let min = Point::new((mid.x - half_m).max(-r_max), (mid.y - half_m).max(-r_max));
    let max = Point::new(
        (mid.x + half_m).min(field.width_m + r_max),
        (mid.y + half_m).min(field.height_m + r_max),
    );
    let mut out = Vec::new();
    let mut keep = |d: &Disk| {
        let usable = d.radius_m > 0.0 && d.radius_m.is_finite();
        let meets_field = usable && (field.clamp(&d.centre) - d.centre).norm() <= d.radius_m;
        if meets_field
            && (d.centre - s).norm() + (d.centre - t).norm() <= limit_m + 2.0 * d.radius_m
        {
            out.push(*d);
        }
    };
    let _ = space.visit_box(&min, &max, |_, d| {
        keep(d);
        ControlFlow::<()>::Continue(())
    });
    // A path bends round a grown polygon only on the circles of its convex corners.
    let _ = space.visit_polygons_box(&min, &max, |_, polygon| {
        polygon.bend_disks().for_each(|d| keep(&d));
        ControlFlow::<()>::Continue(())
    });
    out
}
