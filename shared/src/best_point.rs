//! The best point of the paper's Theorem 1: the point of the field nearest to an agent's
//! ideal slot `x*` that lies outside every (inflated) disk, found exactly.
//!
//! # Method
//!
//! The free set `F` is the closed field rectangle minus the open disks (a point on a
//! circle is free). If `x*` is free it is the answer. Otherwise the nearest point `p` of
//! `F` lies on the boundary of `F`, and the constraints active at `p` make it one of:
//!
//! - the radial projection of `x*` onto one circle (one circle active);
//! - the clamp of `x*` into the field, or its perpendicular projection onto an edge (one
//!   edge active);
//! - a crossing of two circles, of a circle and an edge line, or a field corner (two
//!   constraints active).
//!
//! The same holds for the nearest point of any one connected component of `F` (a
//! component is closed, and near its nearest point it coincides with `F`), which is what
//! [`nearest_reachable_free_point`] relies on.
//!
//! If `x*` sits exactly at a centre every point of that circle ties; one deterministic
//! point is offered, and if it is blocked, the ends of the free arcs of that circle (which
//! are crossings, at the same distance) are offered by the other candidate kinds.
//!
//! # Cost
//!
//! Candidates are enumerated from the disks near `x*` only, by rings of growing radius
//! `rho`: every candidate within `rho` of `x*` lies on a circle that meets the ball of
//! radius `rho` around `x*` and on a disk whose bounding box meets the bounding box of
//! that ball clipped to the field, so one grid box query per ring finds every disk that
//! can contribute. Candidates are then tried nearest first, and only those within `rho`:
//! the first free one is optimal. When none is free, `rho` grows (the margin beyond the
//! lower bound doubles) and the new disks add their candidates. Each feasibility test is
//! one grid point query. The cost depends on the disks near `x*`, not on the field.

use std::cmp::Ordering;
use std::ops::ControlFlow;

use crate::geometry::{
    Disk, Field, FreeSpace, Point, Vector, circle_circle_intersections, circle_line_intersections,
};

/// How far, in metres, a candidate may sit inside a disk or outside the field and still
/// count as free: room for the rounding of the constructions, nothing more. Reported
/// points are the exact constructions, never nudged.
pub const FEASIBILITY_TOLERANCE_M: f64 = 1e-9;

/// Why there is no best point.
#[derive(Debug, thiserror::Error, Clone, Copy, PartialEq, Eq)]
pub enum BestPointError {
    /// No point of the field is free (also reported for a non-finite query or a field
    /// with a negative or non-finite size, which have no nearest point either).
    #[error("no free point in the field")]
    NoFreePoint,
}

/// Theorem 1: the free point of `space` nearest to `query`.
///
/// Free means inside the field and at distance `>= radius` from every disk centre, up to
/// [`FEASIBILITY_TOLERANCE_M`]. `query` may lie anywhere, also outside the field or inside
/// disks. Ties between equally near points are broken deterministically (smallest `x`,
/// then smallest `y`, among the candidates).
///
/// ```
/// use shared::best_point::nearest_free_point;
/// use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};
///
/// let grid = DiskGrid::new(vec![Disk::new(5.0, 5.0, 1.0), Disk::new(9.5, 5.0, 1.0)]);
/// let layers = [&grid];
/// let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
/// // A free query is its own best point.
/// let free = Point::new(2.0, 2.0);
/// assert_eq!(nearest_free_point(&space, &free), Ok(free));
/// // Inside a disk: the radial projection onto its circle.
/// let best = nearest_free_point(&space, &Point::new(5.5, 5.0))?;
/// assert!((best - Point::new(6.0, 5.0)).norm() < 1e-12);
/// // Outside the field, beside a disk that crosses the edge: the circle meets the edge at
/// // two points equally near; the tie goes to the smaller `y`.
/// let best = nearest_free_point(&space, &Point::new(10.5, 5.0))?;
/// assert!((best - Point::new(10.0, 5.0 - 0.75f64.sqrt())).norm() < 1e-12);
/// # Ok::<(), shared::best_point::BestPointError>(())
/// ```
pub fn nearest_free_point(space: &FreeSpace, query: &Point) -> Result<Point, BestPointError> {
    let mut search = CandidateSearch::new(space, query).ok_or(BestPointError::NoFreePoint)?;
    search
        .next_free(f64::INFINITY)
        .map(|candidate| candidate.point)
        .ok_or(BestPointError::NoFreePoint)
}

/// The reachability guarantee (the paper's Assumption 9 made true): the free point nearest
/// to `query` among those `is_reachable` accepts, trying candidates in increasing distance
/// from `query`.
///
/// `from` (the agent's current position, assumed free and reachable by definition) is
/// always a candidate, so the search never needs to look farther than
/// `||from - query||`; returns `from` when nothing nearer is reachable. `is_reachable` is
/// called only on free candidates strictly nearer than `from`, nearest first (ties: smallest
/// `x`, then smallest `y`), never twice on the same point, and never on `from` itself.
///
/// When `from` is not free, it is not a fallback: the result is the nearest free
/// candidate `is_reachable` accepts, or [`BestPointError::NoFreePoint`] when it accepts
/// none.
///
/// ```
/// use std::f64::consts::{FRAC_PI_4, PI};
///
/// use shared::best_point::{nearest_free_point, nearest_reachable_free_point};
/// use shared::disk_path::PathsFrom;
/// use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};
///
/// // Eight overlapping disks ring the slot: the slot is free, but closed off.
/// let slot = Point::new(5.0, 5.0);
/// let ring = (0..8)
///     .map(|k| {
///         let a = k as f64 * FRAC_PI_4;
///         Disk::new(5.0 + 2.0 * a.cos(), 5.0 + 2.0 * a.sin(), 1.0)
///     })
///     .collect();
/// let grid = DiskGrid::new(ring);
/// let layers = [&grid];
/// let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
/// assert_eq!(nearest_free_point(&space, &slot), Ok(slot));
///
/// // From outside the ring, the best reachable point is where two neighbouring circles
/// // cross on the outside.
/// let me = Point::new(1.0, 1.0);
/// let mut paths = PathsFrom::new(&space, &me);
/// let best = nearest_reachable_free_point(&space, &slot, &me, |p| {
///     paths.shortest_path(p).is_ok()
/// })?;
/// let expected_m = 2.0 * (PI / 8.0).cos() + (2f64.sqrt() - 1.0).sqrt();
/// assert!(((best - slot).norm() - expected_m).abs() < 1e-9);
/// # Ok::<(), shared::best_point::BestPointError>(())
/// ```
pub fn nearest_reachable_free_point(
    space: &FreeSpace,
    query: &Point,
    from: &Point,
    mut is_reachable: impl FnMut(&Point) -> bool,
) -> Result<Point, BestPointError> {
    let from_is_free = space.is_free(from, FEASIBILITY_TOLERANCE_M);
    let fallback = if from_is_free {
        Ok(*from)
    } else {
        Err(BestPointError::NoFreePoint)
    };
    let limit_m = if from_is_free {
        (from - query).norm()
    } else {
        f64::INFINITY
    };
    let Some(mut search) = CandidateSearch::new(space, query) else {
        return fallback;
    };
    while let Some(candidate) = search.next_free(limit_m) {
        if candidate.distance_m >= limit_m {
            break;
        }
        if is_reachable(&candidate.point) {
            return Ok(candidate.point);
        }
    }
    fallback
}

/// A point that may be the best point, with its distance to the query.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    distance_m: f64,
    point: Point,
}

impl Candidate {
    /// Nearest first; ties by `x`, then `y`, so the order never depends on how the
    /// candidates were found.
    fn cmp_nearest_first(&self, other: &Self) -> Ordering {
        self.distance_m
            .total_cmp(&other.distance_m)
            .then(self.point.x.total_cmp(&other.point.x))
            .then(self.point.y.total_cmp(&other.point.y))
    }
}

/// The incremental enumeration: free candidates in increasing distance from the query.
struct CandidateSearch<'s> {
    space: &'s FreeSpace<'s>,
    query: Point,
    /// No free point is nearer than this (field distance, depth in the disks at `query`).
    lower_bound_m: f64,
    /// Every candidate within this distance of `query` is in `pending` or was tried.
    searched_m: f64,
    /// Rings enumerated so far.
    rings: u32,
    /// Margin of the next ring beyond `lower_bound_m`.
    ring_margin_m: f64,
    /// Distance from `query` to the farthest corner: a ring this large holds the field.
    field_reach_m: f64,
    /// The candidates owed to the field alone (clamp, edge projections, corners), each
    /// taken into `pending` once a ring reaches it.
    field_candidates: [Option<Candidate>; 9],
    /// Disks whose candidates have been enumerated.
    gathered: Vec<Disk>,
    /// The `(layer, index)` of the gathered disks, sorted.
    gathered_ids: Vec<(usize, usize)>,
    /// The query itself, when it is free and not yet handed out.
    free_query: Option<Candidate>,
    /// Candidates not tried yet, sorted farthest first (the nearest is popped).
    pending: Vec<Candidate>,
    /// The last candidate tried, to skip exact duplicates (which sort next to it).
    last_tried: Option<Point>,
}

impl<'s> CandidateSearch<'s> {
    /// A search around `query`; `None` when there is no nearest point to look for
    /// (non-finite query, degenerate field).
    fn new(space: &'s FreeSpace<'s>, query: &Point) -> Option<Self> {
        let field = space.field;
        let field_is_valid = field.width_m.is_finite()
            && field.height_m.is_finite()
            && field.width_m >= 0.0
            && field.height_m >= 0.0;
        if !field_is_valid || !query.x.is_finite() || !query.y.is_finite() {
            return None;
        }
        // How deep the query is in the disks: the same test as `FreeSpace::is_free`, and
        // a lower bound on the distance to any free point.
        let mut depth_m: f64 = 0.0;
        let _ = space.visit_near(query, 0.0, |_, disk| {
            depth_m = depth_m.max(-disk.signed_distance_m(query));
            ControlFlow::<()>::Continue(())
        });
        let query_is_free =
            field.contains(query, FEASIBILITY_TOLERANCE_M) && depth_m <= FEASIBILITY_TOLERANCE_M;
        let lower_bound_m = depth_m.max((query - field.clamp(query)).norm());
        let field_reach_m = field
            .corners()
            .iter()
            .map(|corner| (corner - query).norm())
            .fold(0.0, f64::max);
        let scale_m = lower_bound_m
            .max(field.width_m)
            .max(field.height_m)
            .max(1.0);
        let ring_margin_m = (0.25 * space.max_radius_m()).max(1e-12 * scale_m);
        Some(Self {
            space,
            query: *query,
            lower_bound_m,
            searched_m: 0.0,
            rings: 0,
            ring_margin_m,
            field_reach_m,
            field_candidates: [None; 9],
            gathered: Vec::new(),
            gathered_ids: Vec::new(),
            // At distance 0 the only candidate is the query itself.
            free_query: query_is_free.then_some(Candidate {
                distance_m: 0.0,
                point: *query,
            }),
            pending: Vec::new(),
            // The query is settled: copies of it (a clamp, a projection) are skipped.
            last_tried: Some(*query),
        })
    }

    /// Whether the rings so far hold the whole field: every candidate is known.
    fn is_exhaustive(&self) -> bool {
        self.searched_m >= self.field_reach_m
    }

    /// The next free candidate no farther than `limit_m`, nearest first; `None` when
    /// there is none.
    fn next_free(&mut self, limit_m: f64) -> Option<Candidate> {
        if let Some(query) = self.free_query.take() {
            return Some(query);
        }
        loop {
            let proven_m = if self.is_exhaustive() {
                f64::INFINITY
            } else {
                self.searched_m
            };
            while let Some(&candidate) = self.pending.last() {
                if candidate.distance_m > proven_m {
                    break;
                }
                if candidate.distance_m > limit_m {
                    return None;
                }
                self.pending.pop();
                if self.last_tried == Some(candidate.point) {
                    continue;
                }
                self.last_tried = Some(candidate.point);
                if self
                    .space
                    .is_free(&candidate.point, FEASIBILITY_TOLERANCE_M)
                {
                    return Some(candidate);
                }
            }
            if self.is_exhaustive() || self.searched_m >= limit_m {
                return None;
            }
            self.grow();
        }
    }

    /// Widen the search to the next ring and enumerate the candidates it brings.
    fn grow(&mut self) {
        if self.rings == 0 {
            self.field_candidates = field_candidates(&self.space.field, &self.query);
            self.pending.reserve(16);
        } else {
            self.ring_margin_m *= 2.0;
        }
        let radius_m = (self.lower_bound_m + self.ring_margin_m).max(self.searched_m);
        // Disks are gathered with some slack, so that rounding can never leave out a disk
        // with a candidate computed to lie within `radius_m`. Then every candidate pushed
        // by a later ring is computed to lie beyond `radius_m`, so none can repeat a point
        // already tried.
        let slack_m = 1e-9 * (1.0 + radius_m + self.query.x.abs() + self.query.y.abs());
        let reach_m = radius_m + slack_m;
        let holds_field = radius_m >= self.field_reach_m;
        for slot in &mut self.field_candidates {
            if let Some(candidate) = *slot
                && (holds_field || candidate.distance_m <= radius_m)
            {
                self.pending.push(candidate);
                *slot = None;
            }
        }
        let new_from = self.gathered.len();
        if let Some((min, max)) = self.ring_box(reach_m) {
            let query = self.query;
            let (gathered, gathered_ids) = (&mut self.gathered, &mut self.gathered_ids);
            // Ids gathered by earlier rings are sorted; a box query reports a disk once.
            let earlier = gathered_ids.len();
            let _ = self.space.visit_box(&min, &max, |id, disk| {
                let to_center_m = (disk.center - query).norm();
                let circle_meets_ring = (to_center_m - disk.radius_m).abs() <= reach_m;
                if disk.radius_m > 0.0
                    && circle_meets_ring
                    && gathered_ids[..earlier].binary_search(&id).is_err()
                {
                    gathered.push(*disk);
                    gathered_ids.push(id);
                }
                ControlFlow::<()>::Continue(())
            });
            gathered_ids.sort_unstable();
        }
        for i in new_from..self.gathered.len() {
            self.push_disk_candidates(i);
        }
        self.searched_m = radius_m;
        self.rings += 1;
        self.pending.sort_unstable_by(|a, b| b.cmp_nearest_first(a));
    }

    /// Bounding box of the ball of radius `reach_m` around the query clipped to the
    /// field (grown by the tolerance); `None` when they do not meet.
    fn ring_box(&self, reach_m: f64) -> Option<(Point, Point)> {
        let field = self.space.field;
        let q = self.query;
        let tol = FEASIBILITY_TOLERANCE_M;
        let mut min = Point::new((q.x - reach_m).max(-tol), (q.y - reach_m).max(-tol));
        let mut max = Point::new(
            (q.x + reach_m).min(field.width_m + tol),
            (q.y + reach_m).min(field.height_m + tol),
        );
        // Half extent of the ball along one axis at the given offset along the other.
        let half_extent = |offset_m: f64| {
            let h2 = (reach_m - offset_m) * (reach_m + offset_m);
            (h2 >= 0.0).then(|| h2.sqrt())
        };
        // Written so that NaN gives `false`; `f64::clamp` needs an ordered range.
        let is_box = |min: &Point, max: &Point| min.x <= max.x && min.y <= max.y;
        if !is_box(&min, &max) {
            return None;
        }
        let dy = half_extent(q.x.clamp(min.x, max.x) - q.x)?;
        min.y = min.y.max(q.y - dy);
        max.y = max.y.min(q.y + dy);
        if !is_box(&min, &max) {
            return None;
        }
        let dx = half_extent(q.y.clamp(min.y, max.y) - q.y)?;
        min.x = min.x.max(q.x - dx);
        max.x = max.x.min(q.x + dx);
        is_box(&min, &max).then_some((min, max))
    }

    /// Queue `point` if it lies in the field (a point outside can never be free).
    fn push(&mut self, point: Point) {
        if self.space.field.contains(&point, FEASIBILITY_TOLERANCE_M) {
            self.pending.push(Candidate {
                distance_m: (point - self.query).norm(),
                point,
            });
        }
    }

    /// The candidates owed to gathered disk `i`: the radial projection of the query onto
    /// its circle, its crossings with the edge lines, and its crossings with every disk
    /// gathered before it.
    fn push_disk_candidates(&mut self, i: usize) {
        let disk = self.gathered[i];
        let outward = self.query - disk.center;
        let outward_m = outward.norm();
        let direction = if outward_m > 0.0 {
            outward / outward_m
        } else {
            // The query is the centre: every point of the circle ties. Offer one; the ends
            // of the circle's free arcs come as crossings.
            Vector::x()
        };
        self.push(disk.center + disk.radius_m * direction);

        let field = self.space.field;
        let edge_lines = [
            (Point::new(0.0, 0.0), Vector::y()),
            (Point::new(field.width_m, 0.0), Vector::y()),
            (Point::new(0.0, 0.0), Vector::x()),
            (Point::new(0.0, field.height_m), Vector::x()),
        ];
        for (line_point, line_direction) in edge_lines {
            if let Some(crossings) =
                circle_line_intersections(&disk.center, disk.radius_m, &line_point, &line_direction)
            {
                crossings.into_iter().for_each(|p| self.push(p));
            }
        }

        for j in 0..i {
            let other = self.gathered[j];
            // Cheap rejection of the (many) pairs that are far apart.
            let reach_m = disk.radius_m + other.radius_m;
            if (disk.center - other.center).norm_squared() > reach_m * reach_m {
                continue;
            }
            if let Some(crossings) = circle_circle_intersections(
                &disk.center,
                disk.radius_m,
                &other.center,
                other.radius_m,
            ) {
                crossings.into_iter().for_each(|p| self.push(p));
            }
        }
    }
}

/// The candidates owed to the field alone: the clamp of `query` into the field, its
/// projections on the four edges (clamped to the edge), and the four corners.
fn field_candidates(field: &Field, query: &Point) -> [Option<Candidate>; 9] {
    let q = query;
    let [c0, c1, c2, c3] = field.corners();
    [
        field.clamp(q),
        field.clamp(&Point::new(0.0, q.y)),
        field.clamp(&Point::new(field.width_m, q.y)),
        field.clamp(&Point::new(q.x, 0.0)),
        field.clamp(&Point::new(q.x, field.height_m)),
        c0,
        c1,
        c2,
        c3,
    ]
    .map(|point| {
        Some(Candidate {
            distance_m: (point - q).norm(),
            point,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DiskGrid;

    fn solve(field: Field, disks: Vec<Disk>, query: Point) -> Result<Point, BestPointError> {
        let grid = DiskGrid::new(disks);
        let layers = [&grid];
        nearest_free_point(&FreeSpace::new(field, &layers), &query)
    }

    fn assert_near(p: Point, expected: Point) {
        assert!((p - expected).norm() < 1e-12, "{p:?} != {expected:?}");
    }

    #[test]
    fn a_free_query_is_its_own_best_point() {
        let q = Point::new(3.0, 4.0);
        let best = solve(Field::new(10.0, 10.0), vec![Disk::new(8.0, 8.0, 1.0)], q);
        assert_eq!(best, Ok(q));
    }

    #[test]
    fn a_query_on_a_circle_is_free() {
        let q = Point::new(6.0, 5.0);
        let best = solve(Field::new(10.0, 10.0), vec![Disk::new(5.0, 5.0, 1.0)], q);
        assert_eq!(best, Ok(q));
    }

    #[test]
    fn a_query_inside_one_disk_goes_radially_out() {
        let best = solve(
            Field::new(10.0, 10.0),
            vec![Disk::new(5.0, 5.0, 2.0)],
            Point::new(5.0, 5.5),
        );
        assert_near(best.expect("free space exists"), Point::new(5.0, 7.0));
    }

    #[test]
    fn a_query_at_a_centre_gets_a_deterministic_circle_point() {
        let best = solve(
            Field::new(10.0, 10.0),
            vec![Disk::new(5.0, 5.0, 2.0)],
            Point::new(5.0, 5.0),
        );
        assert_near(best.expect("free space exists"), Point::new(7.0, 5.0));
    }

    #[test]
    fn a_query_outside_the_field_is_clamped() {
        let best = solve(Field::new(10.0, 10.0), Vec::new(), Point::new(-3.0, 4.0));
        assert_eq!(best, Ok(Point::new(0.0, 4.0)));
        let best = solve(Field::new(10.0, 10.0), Vec::new(), Point::new(12.0, -1.0));
        assert_eq!(best, Ok(Point::new(10.0, 0.0)));
    }

    #[test]
    fn a_blocked_corner_region_leads_to_a_circle_edge_crossing() {
        // The disk covers the corner (0, 0); from outside the field beyond that corner
        // the nearest free point is where the circle crosses an edge.
        let best = solve(
            Field::new(10.0, 10.0),
            vec![Disk::new(0.0, 0.0, 2.0)],
            Point::new(-1.0, -1.0),
        )
        .expect("free space exists");
        // Both crossings (2, 0) and (0, 2) are at the same distance; the smaller x wins.
        assert_near(best, Point::new(0.0, 2.0));
    }

    #[test]
    fn a_far_query_is_clamped_without_scanning_the_field() {
        let disks = vec![Disk::new(0.0, 5.0, 1.0), Disk::new(5.0, 5.0, 1.0)];
        let best =
            solve(Field::new(10.0, 10.0), disks, Point::new(-1e4, 5.0)).expect("free space exists");
        // The clamp (0, 5) is blocked; the circle crosses the edge at (0, 4) and (0, 6).
        assert_eq!(best, Point::new(0.0, 4.0));
    }

    #[test]
    fn a_corner_is_the_answer_beyond_it() {
        let best = solve(
            Field::new(10.0, 10.0),
            vec![Disk::new(5.0, 5.0, 1.0)],
            Point::new(12.0, 13.0),
        );
        assert_eq!(best, Ok(Point::new(10.0, 10.0)));
    }

    #[test]
    fn two_overlapping_disks_push_the_query_to_their_crossing() {
        // Query in the lens of two disks: both radial projections fall inside the other
        // disk; the best point is a crossing of the two circles.
        let disks = vec![Disk::new(4.0, 5.0, 1.5), Disk::new(6.0, 5.0, 1.5)];
        let best =
            solve(Field::new(10.0, 10.0), disks, Point::new(5.0, 5.2)).expect("free space exists");
        let h = (1.5f64 * 1.5 - 1.0).sqrt();
        assert_near(best, Point::new(5.0, 5.0 + h));
    }

    #[test]
    fn a_fully_covered_field_has_no_free_point() {
        let best = solve(
            Field::new(4.0, 3.0),
            vec![Disk::new(2.0, 1.5, 3.0)],
            Point::new(1.0, 1.0),
        );
        assert_eq!(best, Err(BestPointError::NoFreePoint));
    }

    #[test]
    fn a_non_finite_query_has_no_best_point() {
        let best = solve(Field::new(4.0, 3.0), Vec::new(), Point::new(f64::NAN, 1.0));
        assert_eq!(best, Err(BestPointError::NoFreePoint));
    }

    #[test]
    fn reachability_skips_rejected_candidates_and_falls_back_to_from() {
        let grid = DiskGrid::new(vec![Disk::new(5.0, 5.0, 2.0)]);
        let layers = [&grid];
        let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
        let query = Point::new(5.0, 5.5);
        let from = Point::new(5.0, 0.5);
        let mut asked = Vec::new();
        // Refuse everything from y = 5 up: the radial projection (5, 7) and the edge
        // projection (5, 10) are asked and refused; nothing else is nearer than `from`.
        let best = nearest_reachable_free_point(&space, &query, &from, |p| {
            asked.push(*p);
            p.y < 5.0
        })
        .expect("from is free");
        assert_eq!(best, from);
        assert_eq!(asked, vec![Point::new(5.0, 7.0), Point::new(5.0, 10.0)]);
    }

    #[test]
    fn reachability_returns_from_when_it_is_nearest() {
        let grid = DiskGrid::new(vec![Disk::new(5.0, 5.0, 2.0)]);
        let layers = [&grid];
        let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
        let from = Point::new(5.0, 7.0);
        let best = nearest_reachable_free_point(&space, &Point::new(5.0, 5.5), &from, |_| {
            panic!("nothing is nearer than from")
        });
        assert_eq!(best, Ok(from));
    }

    #[test]
    fn reachability_without_a_free_from_reports_no_free_point() {
        let grid = DiskGrid::new(vec![Disk::new(5.0, 5.0, 2.0)]);
        let layers = [&grid];
        let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
        let from = Point::new(5.0, 5.0);
        let best = nearest_reachable_free_point(&space, &Point::new(5.0, 5.5), &from, |_| false);
        assert_eq!(best, Err(BestPointError::NoFreePoint));
        let best = nearest_reachable_free_point(&space, &Point::new(5.0, 5.5), &from, |_| true);
        assert_near(best.expect("a candidate is accepted"), Point::new(5.0, 7.0));
    }
}
