//! The entry points: the nearest free point (Theorem 1), and the nearest one a
//! reachability test accepts.

use super::candidates::{CandidateSearch, FEASIBILITY_TOLERANCE_M};
use crate::geometry::{FreeSpace, Point};

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
/// Free means inside the field, at distance `>= radius` from every disk centre and from
/// every polygon by its radius, up to [`FEASIBILITY_TOLERANCE_M`]. `query` may lie anywhere, also outside the field or inside
/// disks. Ties between equally near points are broken deterministically (smallest `x`,
/// then smallest `y`, among the candidates).
///
/// ```
/// use shared::control::best_point::nearest_free_point;
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
/// # Ok::<(), shared::control::best_point::BestPointError>(())
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
/// use shared::control::best_point::{nearest_free_point, nearest_reachable_free_point};
/// use shared::paths::disk_path::PathsFrom;
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
/// # Ok::<(), shared::control::best_point::BestPointError>(())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Disk, DiskGrid, Field};

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
