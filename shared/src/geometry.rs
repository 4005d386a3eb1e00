//! Plane geometry shared by every planner: points, disks, the rectangular field, and a
//! uniform-grid spatial index over disks.
//!
//! Everything is `f64` and uses nalgebra's `Point2`/`Vector2`, the same types parry2d-f64
//! uses, so there is one vector type in the whole system.

use std::ops::ControlFlow;

/// A point of the plane, in metres.
pub type Point = nalgebra::Point2<f64>;
/// A displacement in the plane, in metres.
pub type Vector = nalgebra::Vector2<f64>;

/// A closed disk: the set of points within `radius_m` of `centre`.
///
/// Planners work with *inflated* disks: an obstacle or another agent grown by the moving
/// agent's own radius, so that the moving agent becomes a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Centre of the disk.
    pub centre: Point,
    /// Radius of the disk, in metres (strictly positive).
    pub radius_m: f64,
}

impl Disk {
    /// A disk of radius `radius_m` around (`x_m`, `y_m`).
    pub fn new(x_m: f64, y_m: f64, radius_m: f64) -> Self {
        Self {
            centre: Point::new(x_m, y_m),
            radius_m,
        }
    }

    /// The same disk with its radius grown by `by_m`.
    pub fn inflated(&self, by_m: f64) -> Self {
        Self {
            centre: self.centre,
            radius_m: self.radius_m + by_m,
        }
    }

    /// Signed distance from `p` to the disk's boundary: negative inside, zero on it.
    pub fn signed_distance_m(&self, p: &Point) -> f64 {
        (p - self.centre).norm() - self.radius_m
    }

    /// The point of the boundary circle at angle `angle_rad` (counter-clockwise from +x).
    pub fn boundary_point(&self, angle_rad: f64) -> Point {
        self.centre + self.radius_m * Vector::new(angle_rad.cos(), angle_rad.sin())
    }

    /// Smallest distance from the segment `a`-`b` to the centre, minus the radius:
    /// negative when the segment enters the open disk.
    pub fn signed_distance_to_segment_m(&self, a: &Point, b: &Point) -> f64 {
        distance_point_segment(&self.centre, a, b) - self.radius_m
    }
}

/// Distance from `p` to the segment `a`-`b`.
pub fn distance_point_segment(p: &Point, a: &Point, b: &Point) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 == 0.0 {
        return (p - a).norm();
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    (p - (a + t * ab)).norm()
}

/// A pose in SE(2): position and heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Position x, in metres.
    pub x_m: f64,
    /// Position y, in metres.
    pub y_m: f64,
    /// Heading, counter-clockwise from +x, in radians.
    pub heading_rad: f64,
}

impl Pose {
    /// A pose at (`x_m`, `y_m`) facing `heading_rad`.
    pub fn new(x_m: f64, y_m: f64, heading_rad: f64) -> Self {
        Self {
            x_m,
            y_m,
            heading_rad,
        }
    }

    /// The position as a point.
    pub fn position(&self) -> Point {
        Point::new(self.x_m, self.y_m)
    }
}

/// Wrap an angle into `(-pi, pi]`.
pub fn wrap_angle_rad(angle_rad: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut a = angle_rad % two_pi;
    if a <= -std::f64::consts::PI {
        a += two_pi;
    } else if a > std::f64::consts::PI {
        a -= two_pi;
    }
    a
}

/// The playing field: the closed rectangle `[0, width_m] x [0, height_m]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    /// Extent along x, in metres.
    pub width_m: f64,
    /// Extent along y, in metres.
    pub height_m: f64,
}

impl Field {
    /// A field of the given size.
    pub fn new(width_m: f64, height_m: f64) -> Self {
        Self { width_m, height_m }
    }

    /// Whether `p` lies in the field, allowing `tolerance_m` outside its edges.
    pub fn contains(&self, p: &Point, tolerance_m: f64) -> bool {
        p.x >= -tolerance_m
            && p.y >= -tolerance_m
            && p.x <= self.width_m + tolerance_m
            && p.y <= self.height_m + tolerance_m
    }

    /// Distance from `p` to the nearest edge, negative outside the field.
    pub fn signed_inset_m(&self, p: &Point) -> f64 {
        p.x.min(p.y)
            .min(self.width_m - p.x)
            .min(self.height_m - p.y)
    }

    /// The nearest point of the field to `p` (`p` itself when inside).
    pub fn clamp(&self, p: &Point) -> Point {
        Point::new(p.x.clamp(0.0, self.width_m), p.y.clamp(0.0, self.height_m))
    }

    /// The four corners, counter-clockwise from the origin.
    pub fn corners(&self) -> [Point; 4] {
        [
            Point::new(0.0, 0.0),
            Point::new(self.width_m, 0.0),
            Point::new(self.width_m, self.height_m),
            Point::new(0.0, self.height_m),
        ]
    }
}

/// A set of disks with a uniform-grid index, so that local queries cost what is local,
/// not what is in the whole field.
///
/// Each disk is registered in every cell its bounding box overlaps. Box queries visit each
/// disk once (a disk is reported only from the first cell where its box and the query box
/// meet), so no scratch memory is needed and the grid can be shared read-only.
#[derive(Clone, Debug)]
pub struct DiskGrid {
    disks: Vec<Disk>,
    origin: Point,
    cell_m: f64,
    columns: usize,
    rows: usize,
    /// `cell_start[c]..cell_start[c + 1]` indexes `cell_items` for cell `c`.
    cell_start: Vec<u32>,
    cell_items: Vec<u32>,
    max_radius_m: f64,
}

impl DiskGrid {
    /// Index `disks`. The cell size adapts to the disks' sizes and density.
    pub fn new(disks: Vec<Disk>) -> Self {
        if disks.is_empty() {
            return Self {
                disks,
                origin: Point::origin(),
                cell_m: 1.0,
                columns: 0,
                rows: 0,
                cell_start: vec![0],
                cell_items: Vec::new(),
                max_radius_m: 0.0,
            };
        }
        let (mut min, mut max) = (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        let mut max_radius_m: f64 = 0.0;
        for d in &disks {
            min.x = min.x.min(d.centre.x - d.radius_m);
            min.y = min.y.min(d.centre.y - d.radius_m);
            max.x = max.x.max(d.centre.x + d.radius_m);
            max.y = max.y.max(d.centre.y + d.radius_m);
            max_radius_m = max_radius_m.max(d.radius_m);
        }
        let area = ((max.x - min.x) * (max.y - min.y)).max(f64::MIN_POSITIVE);
        // About two disks' worth of cell per disk, never smaller than a disk's diameter.
        let by_density = (area / disks.len() as f64).sqrt();
        let cell_m = (2.0 * max_radius_m).max(by_density).max(1e-6);
        let columns = (((max.x - min.x) / cell_m).floor() as usize + 1).min(1 << 14);
        let rows = (((max.y - min.y) / cell_m).floor() as usize + 1).min(1 << 14);
        let mut grid = Self {
            disks,
            origin: min,
            cell_m,
            columns,
            rows,
            cell_start: Vec::new(),
            cell_items: Vec::new(),
            max_radius_m,
        };
        let mut counts = vec![0u32; columns * rows + 1];
        for d in &grid.disks {
            let (c0, r0, c1, r1) = grid.cell_range(&d.centre, d.radius_m, d.radius_m);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    counts[r * columns + c] += 1;
                }
            }
        }
        let mut start = Vec::with_capacity(counts.len() + 1);
        let mut acc = 0u32;
        for n in &counts {
            start.push(acc);
            acc += n;
        }
        start.push(acc);
        let mut fill = start.clone();
        let mut items = vec![0u32; acc as usize];
        for (i, d) in grid.disks.iter().enumerate() {
            let (c0, r0, c1, r1) = grid.cell_range(&d.centre, d.radius_m, d.radius_m);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let k = r * columns + c;
                    items[fill[k] as usize] = i as u32;
                    fill[k] += 1;
                }
            }
        }
        grid.cell_start = start;
        grid.cell_items = items;
        grid
    }

    /// The indexed disks, in the order given to [`DiskGrid::new`].
    pub fn disks(&self) -> &[Disk] {
        &self.disks
    }

    /// Largest radius among the disks (0 when empty).
    pub fn max_radius_m(&self) -> f64 {
        self.max_radius_m
    }

    /// Cell column/row range covering the box `centre ± (half_w, half_h)`, clamped.
    fn cell_range(&self, centre: &Point, half_w: f64, half_h: f64) -> (usize, usize, usize, usize) {
        let to_cell = |v: f64, o: f64, n: usize| -> usize {
            let k = ((v - o) / self.cell_m).floor();
            if k <= 0.0 { 0 } else { (k as usize).min(n - 1) }
        };
        (
            to_cell(centre.x - half_w, self.origin.x, self.columns),
            to_cell(centre.y - half_h, self.origin.y, self.rows),
            to_cell(centre.x + half_w, self.origin.x, self.columns),
            to_cell(centre.y + half_h, self.origin.y, self.rows),
        )
    }

    /// Visit once each disk whose bounding box meets the axis-aligned box `[min, max]`
    /// (a superset of the disks that meet the box). `visit` gets the disk's index and the
    /// disk, and may stop the walk by returning `ControlFlow::Break`.
    pub fn visit_box<B>(
        &self,
        min: &Point,
        max: &Point,
        mut visit: impl FnMut(usize, &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        if self.disks.is_empty() || !(min.x <= max.x && min.y <= max.y) {
            return ControlFlow::Continue(());
        }
        let centre = nalgebra::center(min, max);
        let (c0, r0, c1, r1) =
            self.cell_range(&centre, 0.5 * (max.x - min.x), 0.5 * (max.y - min.y));
        for r in r0..=r1 {
            for c in c0..=c1 {
                let k = r * self.columns + c;
                for &i in
                    &self.cell_items[self.cell_start[k] as usize..self.cell_start[k + 1] as usize]
                {
                    let d = &self.disks[i as usize];
                    if d.centre.x + d.radius_m < min.x
                        || d.centre.x - d.radius_m > max.x
                        || d.centre.y + d.radius_m < min.y
                        || d.centre.y - d.radius_m > max.y
                    {
                        continue;
                    }
                    // Report the disk only from the first cell shared by its box and the query's.
                    let (dc0, dr0, _, _) = self.cell_range(&d.centre, d.radius_m, d.radius_m);
                    if c == dc0.max(c0) && r == dr0.max(r0) {
                        visit(i as usize, d)?;
                    }
                }
            }
        }
        ControlFlow::Continue(())
    }

    /// Visit once each disk that may come within `reach_m` of `p` (a superset).
    pub fn visit_near<B>(
        &self,
        p: &Point,
        reach_m: f64,
        visit: impl FnMut(usize, &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        let d = Vector::new(reach_m, reach_m);
        self.visit_box(&(p - d), &(p + d), visit)
    }
}

/// The free space a point agent moves in: the field minus the union of one or more
/// indexed disk layers (static obstacles, other agents), every disk already inflated.
///
/// A point is *free* when it lies in the field and at distance `>= radius` from every
/// disk centre (the boundary is free: touching is allowed, overlapping is not).
#[derive(Clone, Copy, Debug)]
pub struct FreeSpace<'a> {
    /// The playing field.
    pub field: Field,
    /// The blocking disks, in layers (for example static obstacles and other agents).
    pub layers: &'a [&'a DiskGrid],
}

impl<'a> FreeSpace<'a> {
    /// Free space in `field` outside every disk of `layers`.
    pub fn new(field: Field, layers: &'a [&'a DiskGrid]) -> Self {
        Self { field, layers }
    }

    /// Largest disk radius over all layers.
    pub fn max_radius_m(&self) -> f64 {
        self.layers
            .iter()
            .map(|g| g.max_radius_m())
            .fold(0.0, f64::max)
    }

    /// Visit every disk of every layer whose box meets `[min, max]`; the index passed is
    /// `(layer, index in layer)`.
    pub fn visit_box<B>(
        &self,
        min: &Point,
        max: &Point,
        mut visit: impl FnMut((usize, usize), &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        for (layer, grid) in self.layers.iter().enumerate() {
            grid.visit_box(min, max, |i, d| visit((layer, i), d))?;
        }
        ControlFlow::Continue(())
    }

    /// Visit every disk of every layer that may come within `reach_m` of `p`.
    pub fn visit_near<B>(
        &self,
        p: &Point,
        reach_m: f64,
        visit: impl FnMut((usize, usize), &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        let d = Vector::new(reach_m, reach_m);
        self.visit_box(&(p - d), &(p + d), visit)
    }

    /// Smallest signed distance from `p` to any disk boundary (negative inside a disk),
    /// looking only at disks within `reach_m`; `f64::INFINITY` if none is that close.
    pub fn clearance_m(&self, p: &Point, reach_m: f64) -> f64 {
        let mut best = f64::INFINITY;
        let _ = self.visit_near(p, reach_m, |_, d| {
            best = best.min(d.signed_distance_m(p));
            ControlFlow::<()>::Continue(())
        });
        best
    }

    /// Whether `p` is free, allowing it to sit up to `tolerance_m` inside a disk or
    /// outside the field.
    pub fn is_free(&self, p: &Point, tolerance_m: f64) -> bool {
        if !self.field.contains(p, tolerance_m) {
            return false;
        }
        self.visit_near(p, 0.0, |_, d| {
            if d.signed_distance_m(p) < -tolerance_m {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .is_continue()
    }

    /// Whether the whole segment `a`-`b` is free, with the same tolerance as
    /// [`FreeSpace::is_free`].
    pub fn is_segment_free(&self, a: &Point, b: &Point, tolerance_m: f64) -> bool {
        if !self.field.contains(a, tolerance_m) || !self.field.contains(b, tolerance_m) {
            return false;
        }
        let min = Point::new(a.x.min(b.x), a.y.min(b.y));
        let max = Point::new(a.x.max(b.x), a.y.max(b.y));
        self.visit_box(&min, &max, |_, d| {
            if d.signed_distance_to_segment_m(a, b) < -tolerance_m {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .is_continue()
    }
}

/// The points where the circles of radius `r1_m` around `c1` and `r2_m` around `c2` cross.
///
/// `None` when the circles do not meet (apart, or one strictly inside the other) or are
/// concentric. Tangent circles give their touching point twice. The two points are
/// ordered: the first lies to the left of the direction `c1 -> c2`.
pub fn circle_circle_intersections(
    c1: &Point,
    r1_m: f64,
    c2: &Point,
    r2_m: f64,
) -> Option<[Point; 2]> {
    let between = c2 - c1;
    let distance_m = between.norm();
    // Written so that NaN inputs give `None`.
    let circles_cross =
        distance_m > 0.0 && distance_m <= r1_m + r2_m && distance_m >= (r1_m - r2_m).abs();
    if !circles_cross {
        return None;
    }
    // Signed distance from c1, along c1 -> c2, to the chord through the crossings.
    let along_m = (distance_m * distance_m + r1_m * r1_m - r2_m * r2_m) / (2.0 * distance_m);
    // (r1 - a)(r1 + a) loses less precision than r1^2 - a^2; rounding may push it below
    // zero at a tangency.
    let half_chord_m = ((r1_m - along_m) * (r1_m + along_m)).max(0.0).sqrt();
    let axis = between / distance_m;
    let normal = Vector::new(-axis.y, axis.x);
    let foot = c1 + along_m * axis;
    Some([foot + half_chord_m * normal, foot - half_chord_m * normal])
}

/// The points where the circle of radius `radius_m` around `centre` crosses the line
/// through `line_point` with direction `line_direction` (any non-zero length).
///
/// `None` when the line misses the circle or the direction is zero. A tangent line gives
/// its touching point twice. The points are ordered along `line_direction`.
pub fn circle_line_intersections(
    centre: &Point,
    radius_m: f64,
    line_point: &Point,
    line_direction: &Vector,
) -> Option<[Point; 2]> {
    let length2 = line_direction.norm_squared();
    let has_direction = length2 > 0.0;
    if !has_direction {
        return None;
    }
    let foot = line_point + ((centre - line_point).dot(line_direction) / length2) * line_direction;
    let offset_m = (centre - foot).norm();
    let line_meets_circle = offset_m <= radius_m;
    if !line_meets_circle {
        return None;
    }
    // Half chord in units of the direction's length.
    let half_chord = ((radius_m - offset_m) * (radius_m + offset_m) / length2).sqrt();
    Some([
        foot - half_chord * line_direction,
        foot + half_chord * line_direction,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_force_box(disks: &[Disk], min: &Point, max: &Point) -> Vec<usize> {
        disks
            .iter()
            .enumerate()
            .filter(|(_, d)| {
                d.centre.x + d.radius_m >= min.x
                    && d.centre.x - d.radius_m <= max.x
                    && d.centre.y + d.radius_m >= min.y
                    && d.centre.y - d.radius_m <= max.y
            })
            .map(|(i, _)| i)
            .collect()
    }

    #[test]
    fn grid_box_query_visits_each_overlapping_disk_exactly_once() {
        let mut disks = Vec::new();
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            disks.push(Disk::new(next() * 50.0, next() * 30.0, 0.1 + next() * 2.0));
        }
        let grid = DiskGrid::new(disks.clone());
        for _ in 0..200 {
            let a = Point::new(next() * 60.0 - 5.0, next() * 40.0 - 5.0);
            let b = Point::new(a.x + next() * 10.0, a.y + next() * 10.0);
            let mut seen = Vec::new();
            let _ = grid.visit_box(&a, &b, |i, _| {
                seen.push(i);
                ControlFlow::<()>::Continue(())
            });
            let mut sorted = seen.clone();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), seen.len(), "a disk was visited twice");
            assert_eq!(sorted, brute_force_box(&disks, &a, &b));
        }
    }

    #[test]
    fn free_space_point_and_segment_tests_agree_with_the_definition() {
        let grid = DiskGrid::new(vec![Disk::new(5.0, 5.0, 1.0)]);
        let layers = [&grid];
        let space = FreeSpace::new(Field::new(10.0, 10.0), &layers);
        assert!(
            space.is_free(&Point::new(6.0, 5.0), 0.0),
            "the boundary is free"
        );
        assert!(!space.is_free(&Point::new(5.5, 5.0), 0.0));
        assert!(
            !space.is_free(&Point::new(-0.1, 5.0), 0.0),
            "outside the field"
        );
        assert!(space.is_segment_free(&Point::new(0.0, 6.0), &Point::new(10.0, 6.0), 0.0));
        assert!(!space.is_segment_free(&Point::new(0.0, 5.9), &Point::new(10.0, 5.9), 0.0));
    }

    #[test]
    fn circle_circle_intersections_lie_on_both_circles() {
        let (c1, c2) = (Point::new(1.0, 2.0), Point::new(4.0, 6.0));
        let [p, q] = circle_circle_intersections(&c1, 3.0, &c2, 4.0).expect("they cross");
        for x in [p, q] {
            assert!(((x - c1).norm() - 3.0).abs() < 1e-12);
            assert!(((x - c2).norm() - 4.0).abs() < 1e-12);
        }
        assert!((p - q).norm() > 1.0);
        // Left of c1 -> c2 first.
        let axis = c2 - c1;
        assert!(axis.perp(&(p - c1)) > 0.0 && axis.perp(&(q - c1)) < 0.0);
    }

    #[test]
    fn circle_circle_intersections_handle_tangency_and_misses() {
        let o = Point::origin();
        let [p, q] = circle_circle_intersections(&o, 1.0, &Point::new(3.0, 0.0), 2.0)
            .expect("external tangency");
        assert_eq!(p, Point::new(1.0, 0.0));
        assert_eq!(p, q);
        let [p, _] = circle_circle_intersections(&o, 3.0, &Point::new(1.0, 0.0), 2.0)
            .expect("internal tangency");
        assert!((p - Point::new(3.0, 0.0)).norm() < 1e-12);
        assert!(circle_circle_intersections(&o, 1.0, &Point::new(3.0, 0.0), 1.0).is_none());
        assert!(circle_circle_intersections(&o, 3.0, &Point::new(0.5, 0.0), 1.0).is_none());
        assert!(
            circle_circle_intersections(&o, 1.0, &o, 1.0).is_none(),
            "concentric"
        );
    }

    #[test]
    fn circle_line_intersections_lie_on_circle_and_line() {
        let c = Point::new(2.0, 1.0);
        let [p, q] =
            circle_line_intersections(&c, 2.5, &Point::new(0.0, 0.0), &Vector::new(0.0, 5.0))
                .expect("the line x = 0 crosses");
        for x in [p, q] {
            assert_eq!(x.x, 0.0);
            assert!(((x - c).norm() - 2.5).abs() < 1e-12);
        }
        assert!(p.y < q.y, "ordered along the direction");
        let [t, u] =
            circle_line_intersections(&c, 2.0, &Point::new(0.0, 3.0), &Vector::new(1.0, 0.0))
                .expect("tangent");
        assert_eq!(t, Point::new(2.0, 3.0));
        assert_eq!(t, u);
        assert!(
            circle_line_intersections(&c, 2.0, &Point::new(0.0, 3.5), &Vector::new(1.0, 0.0))
                .is_none()
        );
        assert!(circle_line_intersections(&c, 2.0, &c, &Vector::zeros()).is_none());
    }
}
