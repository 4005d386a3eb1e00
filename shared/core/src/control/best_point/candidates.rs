//! The candidates for the best point, and their enumeration nearest first by rings of
//! growing radius around the query (see the module docs for why that is exact).

use std::cmp::Ordering;
use std::ops::ControlFlow;

use crate::geometry::{
    Disk, Field, FreeSpace, Point, Vector, circle_circle_intersections, circle_line_intersections,
    line_line_intersection,
};

/// How far, in metres, a candidate may sit inside a disk or outside the field and still
/// count as free: room for the rounding of the constructions, nothing more. Reported
/// points are the exact constructions, never nudged.
pub const FEASIBILITY_TOLERANCE_M: f64 = 1e-9;

/// A point that may be the best point, with its distance to the query.
#[derive(Clone, Copy, Debug)]
pub(super) struct Candidate {
    pub(super) distance_m: f64,
    pub(super) point: Point,
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
pub(super) struct CandidateSearch<'s> {
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
    /// Disks whose candidates have been enumerated, the corner circles of the gathered
    /// polygons among them.
    gathered: Vec<Disk>,
    /// The `(layer, index)` of the gathered disks of the layers, sorted.
    gathered_ids: Vec<(usize, usize)>,
    /// The offset sides of the gathered polygons, `(start, end)`.
    gathered_sides: Vec<(Point, Point)>,
    /// The indices of the gathered polygons, sorted.
    gathered_polygons: Vec<usize>,
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
    pub(super) fn new(space: &'s FreeSpace<'s>, query: &Point) -> Option<Self> {
        let field = space.field;
        let field_is_valid = field.width_m.is_finite()
            && field.height_m.is_finite()
            && field.width_m >= 0.0
            && field.height_m >= 0.0;
        if !field_is_valid || !query.x.is_finite() || !query.y.is_finite() {
            return None;
        }
        // How deep the query is in the obstacles: the same test as `FreeSpace::is_free`,
        // and a lower bound on the distance to any free point.
        let depth_m = space.depth_m(query);
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
            gathered_sides: Vec::new(),
            gathered_polygons: Vec::new(),
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
    pub(super) fn next_free(&mut self, limit_m: f64) -> Option<Candidate> {
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
        let new_sides_from = self.gathered_sides.len();
        if let Some((min, max)) = self.ring_box(reach_m) {
            let query = self.query;
            let (gathered, gathered_ids) = (&mut self.gathered, &mut self.gathered_ids);
            // Ids gathered by earlier rings are sorted; a box query reports a disk once.
            let earlier = gathered_ids.len();
            let _ = self.space.visit_box(&min, &max, |id, disk| {
                let to_center_m = (disk.centre - query).norm();
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
            // A polygon is gathered whole: its corner circles with the disks, its offset
            // sides apart. Every piece of its boundary lies in its bounding box.
            let (gathered, sides, polygons) = (
                &mut self.gathered,
                &mut self.gathered_sides,
                &mut self.gathered_polygons,
            );
            let earlier = polygons.len();
            let _ = self.space.visit_polygons_box(&min, &max, |i, polygon| {
                if polygon.radius_m() > 0.0 && polygons[..earlier].binary_search(&i).is_err() {
                    gathered.extend(polygon.bend_disks());
                    sides.extend(polygon.offset_sides());
                    polygons.push(i);
                }
                ControlFlow::<()>::Continue(())
            });
            polygons.sort_unstable();
        }
        for i in new_from..self.gathered.len() {
            self.push_disk_candidates(i, new_sides_from);
        }
        for k in new_sides_from..self.gathered_sides.len() {
            self.push_side_candidates(k);
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
    /// its circle, its crossings with the edge lines, with every disk gathered before it
    /// and with the first `sides` offset sides (the later ones cross it in
    /// [`Self::push_side_candidates`]).
    fn push_disk_candidates(&mut self, i: usize, sides: usize) {
        let disk = self.gathered[i];
        let outward = self.query - disk.centre;
        let outward_m = outward.norm();
        let direction = if outward_m > 0.0 {
            outward / outward_m
        } else {
            // The query is the centre: every point of the circle ties. Offer one; the ends
            // of the circle's free arcs come as crossings.
            Vector::x()
        };
        self.push(disk.centre + disk.radius_m * direction);

        let edge_lines = field_edge_lines(&self.space.field);
        for (line_point, line_direction) in edge_lines {
            if let Some(crossings) =
                circle_line_intersections(&disk.centre, disk.radius_m, &line_point, &line_direction)
            {
                crossings.into_iter().for_each(|p| self.push(p));
            }
        }

        for j in 0..i {
            let other = self.gathered[j];
            // Cheap rejection of the (many) pairs that are far apart.
            let reach_m = disk.radius_m + other.radius_m;
            if (disk.centre - other.centre).norm_squared() > reach_m * reach_m {
                continue;
            }
            if let Some(crossings) = circle_circle_intersections(
                &disk.centre,
                disk.radius_m,
                &other.centre,
                other.radius_m,
            ) {
                crossings.into_iter().for_each(|p| self.push(p));
            }
        }

        for k in 0..sides {
            let (a, b) = self.gathered_sides[k];
            self.push_circle_side_crossings(&disk, &a, &b);
        }
    }

    /// Queue the crossings of the circle of `disk` with the segment `a`-`b`.
    fn push_circle_side_crossings(&mut self, disk: &Disk, a: &Point, b: &Point) {
        if let Some(crossings) = circle_line_intersections(&disk.centre, disk.radius_m, a, &(b - a))
        {
            for p in crossings {
                if on_segment(&p, a, b) {
                    self.push(p);
                }
            }
        }
    }

    /// The candidates owed to gathered offset side `k`: the projection of the query onto
    /// it, its crossings with the edge lines, with every gathered circle and with every
    /// offset side gathered before it.
    fn push_side_candidates(&mut self, k: usize) {
        let (a, b) = self.gathered_sides[k];
        let along = b - a;
        let length2 = along.norm_squared();
        if length2 <= 0.0 || !length2.is_finite() {
            return;
        }
        let t = ((self.query - a).dot(&along) / length2).clamp(0.0, 1.0);
        self.push(a + t * along);

        let edge_lines = field_edge_lines(&self.space.field);
        for (line_point, line_direction) in edge_lines {
            if let Some((p, t, _)) =
                line_line_intersection(&a, &along, &line_point, &line_direction)
                && within_unit(t)
            {
                self.push(p);
            }
        }
        for i in 0..self.gathered.len() {
            let disk = self.gathered[i];
            self.push_circle_side_crossings(&disk, &a, &b);
        }
        for j in 0..k {
            let (c, d) = self.gathered_sides[j];
            if let Some((p, t1, t2)) = line_line_intersection(&a, &along, &c, &(d - c))
                && within_unit(t1)
                && within_unit(t2)
            {
                self.push(p);
            }
        }
    }
}

/// The lines of the field's four edges, each as `(point, direction)`.
fn field_edge_lines(field: &Field) -> [(Point, Vector); 4] {
    [
        (Point::new(0.0, 0.0), Vector::y()),
        (Point::new(field.width_m, 0.0), Vector::y()),
        (Point::new(0.0, 0.0), Vector::x()),
        (Point::new(0.0, field.height_m), Vector::x()),
    ]
}

/// Whether a parameter along a segment lies on it, with room for rounding.
fn within_unit(t: f64) -> bool {
    const SLACK: f64 = 1e-9;
    (-SLACK..=1.0 + SLACK).contains(&t)
}

/// Whether `p`, known to lie on the line through `a`-`b`, lies on the segment.
fn on_segment(p: &Point, a: &Point, b: &Point) -> bool {
    let along = b - a;
    within_unit((p - a).dot(&along) / along.norm_squared())
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
