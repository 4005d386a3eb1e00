//! Clearances: how far a body stands from the nearest obstacle, polygon or other body
//! (distance minus radii), with a grid over the bodies for the nearest one.

use std::ops::ControlFlow;

use crate::control::vocabulary::Body;
use crate::geometry::{Disk, DiskGrid, Point, Polygon};

/// Clearance of `body` (distance minus radii) to the nearest obstacle and to the nearest
/// of `others`, looking for obstacles within `reach_m`: `(obstacle, other)`, each
/// `f64::INFINITY` when there is none.
pub fn clearances_m(
    body: &Body,
    obstacles: &DiskGrid,
    others: &[Body],
    reach_m: f64,
) -> (f64, f64) {
    clearances_skipping_m(body, obstacles, others, None, reach_m)
}

/// [`clearances_m`] of body `agent` of `bodies` against the other bodies of `bodies`
/// (without copying them out).
pub fn clearances_of_m(
    bodies: &[Body],
    agent: usize,
    obstacles: &DiskGrid,
    reach_m: f64,
) -> (f64, f64) {
    clearances_skipping_m(&bodies[agent], obstacles, bodies, Some(agent), reach_m)
}

/// A grid over `bodies`, a disk each in the same order: what [`Others::grid`](super::Others::grid) and
/// [`clearance_to_others_m`] take.
pub fn bodies_grid(bodies: &[Body]) -> DiskGrid {
    DiskGrid::new(
        bodies
            .iter()
            .map(|b| Disk {
                centre: b.position,
                radius_m: b.radius_m,
            })
            .collect(),
    )
}

/// The clearance of body `agent` of `bodies` to the nearest other one (distance minus
/// radii; `f64::INFINITY` if there is none): [`clearances_of_m`]'s second value, to the
/// bit, found with `grid`, a grid over exactly `bodies` (same order, same disks), among
/// the bodies near it. The search widens until the nearest found is surely the nearest.
pub fn clearance_to_others_m(bodies: &[Body], agent: usize, grid: &DiskGrid) -> f64 {
    let body = &bodies[agent];
    let clearance_to = |o: &Body| (body.position - o.position).norm() - o.radius_m - body.radius_m;
    let scan = || {
        bodies
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != agent)
            .map(|(_, o)| clearance_to(o))
            .fold(f64::INFINITY, f64::min)
    };
    // Not a grid over these bodies: each in turn.
    if grid.disks().len() != bodies.len() {
        return scan();
    }
    // A body of clearance c has its disk within c + the body's radius of its centre: its
    // box meets the query's once the reach is that far.
    let mut look_m = 1.0_f64;
    let mut span_m = None;
    loop {
        let mut nearest = f64::INFINITY;
        let _ = grid.visit_near(&body.position, look_m + body.radius_m, |j, _| {
            if j != agent {
                nearest = nearest.min(clearance_to(&bodies[j]));
            }
            ControlFlow::<()>::Continue(())
        });
        // Every body within `look_m` (a nanometre to spare for rounding) was seen.
        if nearest <= look_m - 1e-9 {
            return nearest;
        }
        let span_m = *span_m.get_or_insert_with(|| grid_span_m(grid));
        if !span_m.is_finite() {
            // Bodies at no finite place: each in turn.
            return scan();
        }
        if look_m > span_m {
            // The query covers the whole grid: what was seen is all there is.
            return nearest;
        }
        look_m *= 4.0;
    }
}

/// The longest side of the box round `grid`'s disks (0 when empty).
fn grid_span_m(grid: &DiskGrid) -> f64 {
    let (mut min, mut max) = (
        Point::new(f64::INFINITY, f64::INFINITY),
        Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for d in grid.disks() {
        min.x = min.x.min(d.centre.x - d.radius_m);
        min.y = min.y.min(d.centre.y - d.radius_m);
        max.x = max.x.max(d.centre.x + d.radius_m);
        max.y = max.y.max(d.centre.y + d.radius_m);
    }
    (max.x - min.x).max(max.y - min.y).max(0.0)
}

fn clearances_skipping_m(
    body: &Body,
    obstacles: &DiskGrid,
    bodies: &[Body],
    skip: Option<usize>,
    reach_m: f64,
) -> (f64, f64) {
    let mut to_obstacle = f64::INFINITY;
    let _ = obstacles.visit_near(&body.position, reach_m, |_, o| {
        to_obstacle =
            to_obstacle.min((body.position - o.centre).norm() - o.radius_m - body.radius_m);
        ControlFlow::<()>::Continue(())
    });
    let mut to_other = f64::INFINITY;
    for (j, o) in bodies.iter().enumerate() {
        if Some(j) == skip {
            continue;
        }
        let d = body.position - o.position;
        let radii_m = o.radius_m + body.radius_m;
        // The distance is at least the larger of the two offsets: a body that far along
        // one axis is no nearer than the nearest so far, and is skipped without the
        // square root (with a nanometre to spare for rounding, so the minimum is the
        // same to the bit).
        if d.x.abs().max(d.y.abs()) - radii_m > to_other + 1e-9 {
            continue;
        }
        to_other = to_other.min(d.norm() - o.radius_m - body.radius_m);
    }
    (to_obstacle, to_other)
}

/// Clearance of `body` (distance minus radius) to the nearest of `polygons`,
/// `f64::INFINITY` when there is none; negative inside one.
pub fn clearance_to_polygons_m(body: &Body, polygons: &[Polygon]) -> f64 {
    polygons
        .iter()
        .map(|p| p.signed_distance_m(&body.position) - body.radius_m)
        .fold(f64::INFINITY, f64::min)
}
