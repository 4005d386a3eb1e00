//! Property tests for `shared::paths::disk_path::shortest_path`, checked independently of the
//! controller's own geometry:
//!
//! - validity: continuity, exact end points, brute-force clearance of dense samples
//!   (spacing 1e-4 m) against every disk, exact distance of every straight piece, field
//!   containment;
//! - length: at least the straight-line distance, and equal to the length of a dense
//!   polyline through the samples;
//! - optimality: never longer than a path found by an independent approximate planner
//!   (Dijkstra on a visibility graph of points slightly outside every circle, every edge
//!   checked exactly). That path is genuinely free, so the exact optimum cannot be longer:
//!   the only slack is floating-point rounding (1e-9 m);
//! - reachability: `Unreachable` only when the approximate planner finds nothing either,
//!   and (on ring instances with unambiguous gaps) exactly when the ring is closed;
//! - `polyline(e)`: vertices on the path, chords within `e` of it, clearance `>= -e`;
//! - `PathsFrom` (one start, many goals) answers exactly as `shortest_path`, bit for bit,
//!   on packed lattices of disks (pockets, near-tangent overlaps around the barrier margin),
//!   and the reachable best point chosen with it is the same point with the same path.

use std::f64::consts::TAU;

use proptest::prelude::*;
use proptest::test_runner::Config;
use shared::control::best_point::nearest_reachable_free_point;
use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};
use shared::paths::disk_path::{DiskPath, PathError, PathPiece, PathsFrom, shortest_path};

const TOL_M: f64 = 1e-9;

/// Distance from `p` to the segment `a`-`b` (written here, not taken from the library).
fn dist_to_segment(p: &Point, a: &Point, b: &Point) -> f64 {
    let ab = b - a;
    let len2 = ab.dot(&ab);
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + t * ab)).norm()
}

fn rem_turn(x: f64) -> f64 {
    x.rem_euclid(TAU)
}

/// Distance from `p` to one piece of a path.
fn dist_to_piece(p: &Point, piece: &PathPiece) -> f64 {
    match *piece {
        PathPiece::Segment { from, to } => dist_to_segment(p, &from, &to),
        PathPiece::Arc {
            centre,
            radius_m,
            start_rad,
            sweep_rad,
        } => {
            let v = p - centre;
            let phi = v.y.atan2(v.x);
            let rel = if sweep_rad >= 0.0 {
                rem_turn(phi - start_rad)
            } else {
                rem_turn(start_rad - phi)
            };
            if rel <= sweep_rad.abs() {
                (v.norm() - radius_m).abs()
            } else {
                (p - piece.start()).norm().min((p - piece.end()).norm())
            }
        }
    }
}

fn dist_to_path(p: &Point, path: &DiskPath) -> f64 {
    path.pieces
        .iter()
        .map(|q| dist_to_piece(p, q))
        .fold(f64::INFINITY, f64::min)
}

fn is_free(p: &Point, disks: &[Disk], field: &Field, tol: f64) -> bool {
    field.contains(p, tol)
        && disks
            .iter()
            .all(|d| (p - d.centre).norm() >= d.radius_m - tol)
}

/// Independent approximate planner: visibility graph over `per_circle` points on each
/// circle grown so that the chords between neighbours stay outside the disk, plus start and
/// goal; every edge checked exactly (distance `>= r` to every disk, inside the field).
/// Returns the length of the shortest path in that graph, a length of a genuinely free path.
fn approximate_length(
    field: &Field,
    disks: &[Disk],
    s: &Point,
    t: &Point,
    per_circle: usize,
) -> Option<f64> {
    let half_step = std::f64::consts::PI / per_circle as f64;
    let mut nodes = vec![*s, *t];
    for d in disks {
        let grown = d.radius_m / half_step.cos() * (1.0 + 1e-9) + 1e-9;
        for i in 0..per_circle {
            let a = i as f64 * TAU / per_circle as f64;
            let p = d.centre + grown * nalgebra::Vector2::new(a.cos(), a.sin());
            if is_free(&p, disks, field, 0.0) {
                nodes.push(p);
            }
        }
    }
    let visible = |a: &Point, b: &Point| {
        disks
            .iter()
            .all(|d| dist_to_segment(&d.centre, a, b) >= d.radius_m)
    };
    let n = nodes.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    dist[0] = 0.0;
    loop {
        let mut best = None;
        for i in 0..n {
            if !done[i] && dist[i].is_finite() && best.is_none_or(|b: usize| dist[i] < dist[b]) {
                best = Some(i);
            }
        }
        let u = best?;
        if u == 1 {
            return Some(dist[1]);
        }
        done[u] = true;
        for v in 0..n {
            if done[v] {
                continue;
            }
            let w = dist[u] + (nodes[v] - nodes[u]).norm();
            if w < dist[v] && visible(&nodes[u], &nodes[v]) {
                dist[v] = w;
            }
        }
    }
}

/// Everything that must hold of a returned path, checked by brute force.
fn check_path(
    path: &DiskPath,
    field: &Field,
    disks: &[Disk],
    s: &Point,
    t: &Point,
) -> Result<(), TestCaseError> {
    // (a) continuity and exact end points.
    prop_assert!(!path.pieces.is_empty());
    prop_assert!(
        (path.start() - s).norm() <= TOL_M,
        "start {:?} vs {:?}",
        path.start(),
        s
    );
    prop_assert!(
        (path.end() - t).norm() <= TOL_M,
        "end {:?} vs {:?}",
        path.end(),
        t
    );
    for w in path.pieces.windows(2) {
        prop_assert!(
            (w[0].end() - w[1].start()).norm() <= TOL_M,
            "gap: {:?} then {:?}",
            w[0],
            w[1]
        );
    }
    // (b) clearance, dense samples and exact segment distances.
    let samples = path.sample(1e-4);
    for p in &samples {
        prop_assert!(field.contains(p, TOL_M), "sample {p:?} outside the field");
        for d in disks {
            let c = (p - d.centre).norm() - d.radius_m;
            prop_assert!(c >= -TOL_M, "sample {p:?} inside {d:?} by {c}");
        }
    }
    for piece in &path.pieces {
        if let PathPiece::Segment { from, to } = piece {
            for d in disks {
                let c = dist_to_segment(&d.centre, from, to) - d.radius_m;
                prop_assert!(c >= -TOL_M, "segment {piece:?} enters {d:?} by {c}");
            }
        }
    }
    // (c) no shorter than the straight line.
    let length = path.length_m();
    prop_assert!(length >= (t - s).norm() - TOL_M);
    // (d) the length is the limit of the sampled polyline's length (chord deficit of an arc
    // step h is about h^3 / (24 r^2): negligible at h = 1e-4 m).
    let sampled: f64 = samples.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    prop_assert!(
        sampled <= length + 1e-9 && length - sampled <= 1e-7,
        "sampled {sampled} vs {length}"
    );
    Ok(())
}

/// The polyline contract.
fn check_polyline(path: &DiskPath, disks: &[Disk], e: f64) -> Result<(), TestCaseError> {
    let poly = path.polyline(e);
    prop_assert!(poly.len() >= 2);
    prop_assert_eq!(poly[0], path.start());
    prop_assert_eq!(*poly.last().unwrap_or(&Point::origin()), path.end());
    for v in &poly {
        prop_assert!(dist_to_path(v, path) <= 1e-9, "vertex {v:?} off the path");
    }
    for w in poly.windows(2) {
        let n = ((w[1] - w[0]).norm() / (0.25 * e)).ceil().max(1.0) as usize;
        for i in 0..=n {
            let p = w[0] + (i as f64 / n as f64) * (w[1] - w[0]);
            prop_assert!(
                dist_to_path(&p, path) <= e + 1e-9,
                "chord point {p:?} too far from the path"
            );
        }
        for d in disks {
            let c = dist_to_segment(&d.centre, &w[0], &w[1]) - d.radius_m;
            prop_assert!(c >= -e - 1e-9, "chord enters {d:?} by {c}");
        }
    }
    Ok(())
}

#[derive(Clone, Debug)]
struct Instance {
    field: Field,
    disks: Vec<Disk>,
    start: Point,
    goal: Point,
}

/// A point from raw unit numbers: exactly on a circle (`snap < 0.3`), in the band
/// `x in [x0, x0 + 0.4] * width` (`snap < 0.8`, so that start and goal face each other across
/// the field and the straight line is often blocked), or uniform in the field.
fn make_point(field: &Field, disks: &[Disk], raw: (f64, f64, f64, usize), x0: f64) -> Point {
    let (u, v, snap, pick) = raw;
    if snap < 0.3 && !disks.is_empty() {
        let d = &disks[pick % disks.len()];
        return d.centre + d.radius_m * nalgebra::Vector2::new((u * TAU).cos(), (u * TAU).sin());
    }
    if snap < 0.8 {
        return Point::new((x0 + 0.4 * u) * field.width_m, v * field.height_m);
    }
    Point::new(u * field.width_m, v * field.height_m)
}

/// Random fields, random (possibly overlapping, possibly sticking out) disks, free start
/// and goal (uniform or exactly on a circle).
fn instances(max_disks: usize, max_side_m: f64) -> impl Strategy<Value = Instance> {
    let raw_point = (0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64, 0usize..64);
    (
        4.0..max_side_m,
        4.0..max_side_m,
        prop::collection::vec((-0.1..1.1f64, -0.1..1.1f64, 0.3..2.5f64), 1..=max_disks),
        prop::collection::vec(raw_point.clone(), 8),
        prop::collection::vec(raw_point, 8),
    )
        .prop_filter_map(
            "no free start or goal",
            |(w, h, raw_disks, starts, goals)| {
                let field = Field::new(w, h);
                let disks: Vec<Disk> = raw_disks
                    .iter()
                    .map(|&(x, y, r)| Disk::new(x * w, y * h, r))
                    .collect();
                let pick = |raws: &[(f64, f64, f64, usize)], x0: f64| {
                    raws.iter()
                        .map(|&raw| make_point(&field, &disks, raw, x0))
                        .find(|p| is_free(p, &disks, &field, TOL_M))
                };
                let start = pick(&starts, 0.0)?;
                let goal = pick(&goals, 0.6)?;
                Some(Instance {
                    field,
                    disks,
                    start,
                    goal,
                })
            },
        )
}

fn run(inst: &Instance) -> Result<DiskPath, PathError> {
    let grid = DiskGrid::new(inst.disks.clone());
    let layers = [&grid];
    let space = FreeSpace::new(inst.field, &layers);
    shortest_path(&space, &inst.start, &inst.goal)
}

fn config(cases: u32) -> Config {
    Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// Small instances: validity, optimality against the approximate planner, reachability.
    #[test]
    fn small_instances_are_valid_and_optimal(inst in instances(8, 14.0), e_pick in 0usize..3) {
        let result = run(&inst);
        let approx = approximate_length(&inst.field, &inst.disks, &inst.start, &inst.goal, 48);
        match &result {
            Ok(path) => {
                check_path(path, &inst.field, &inst.disks, &inst.start, &inst.goal)?;
                check_polyline(path, &inst.disks, [1e-1, 1e-2, 1e-3][e_pick])?;
                if let Some(a) = approx {
                    prop_assert!(path.length_m() <= a + 1e-9, "exact {} longer than approximate {}", path.length_m(), a);
                }
            }
            Err(PathError::Unreachable) => {
                prop_assert!(approx.is_none(), "unreachable, but the approximate planner found a path of {:?}", approx);
            }
            Err(other) => prop_assert!(false, "free start and goal rejected: {other:?}"),
        }
    }
}

proptest! {
    #![proptest_config(config(48))]

    /// More disks in a larger field (several ellipse rounds): validity and optimality against
    /// a coarser (still genuinely free) approximate path.
    #[test]
    fn larger_instances_are_valid_and_optimal(inst in instances(40, 30.0)) {
        let result = run(&inst);
        let approx = approximate_length(&inst.field, &inst.disks, &inst.start, &inst.goal, 16);
        match &result {
            Ok(path) => {
                check_path(path, &inst.field, &inst.disks, &inst.start, &inst.goal)?;
                if let Some(a) = approx {
                    prop_assert!(path.length_m() <= a + 1e-9, "exact {} longer than approximate {}", path.length_m(), a);
                }
            }
            Err(PathError::Unreachable) => prop_assert!(approx.is_none()),
            Err(other) => prop_assert!(false, "free start and goal rejected: {other:?}"),
        }
    }
}

/// A ring of disks around `centre`, either closed (neighbours overlap by at least 5 cm) or
/// with one unambiguous gap (at least 0.5 m wide), plus a few loose disks.
#[derive(Clone, Debug)]
struct Ring {
    inst: Instance,
    closed: bool,
}

fn rings() -> impl Strategy<Value = Ring> {
    (
        3usize..10,
        2.0..4.0f64,
        0.0..1.0f64,
        any::<bool>(),
        0.0..1.0f64,
        any::<bool>(),
        prop::collection::vec((0.0..1.0f64, 0.0..1.0f64, 0.3..1.0f64), 0..4),
        (0.0..1.0f64, 0.0..1.0f64),
    )
        .prop_filter_map(
            "ambiguous ring",
            |(count, ring_r, phase, closed, gap_frac, inside_start, loose, (gu, gv))| {
                let field = Field::new(20.0, 20.0);
                let centre = Point::new(10.0, 10.0);
                let spacing = 2.0 * ring_r * (std::f64::consts::PI / count as f64).sin();
                // Closed: neighbours overlap by >= 5 cm. Open: one disk removed, gap >= 0.5 m.
                let disk_r = 0.5 * spacing + 0.05 + 0.3 * gap_frac;
                let mut disks = Vec::new();
                for i in 0..count {
                    if !closed && i == 0 {
                        continue;
                    }
                    let a = phase * TAU + i as f64 * TAU / count as f64;
                    disks.push(Disk::new(
                        centre.x + ring_r * a.cos(),
                        centre.y + ring_r * a.sin(),
                        disk_r,
                    ));
                }
                if !closed {
                    // Width of the gap left by the removed disk, between its two neighbours.
                    let gap = 2.0 * ring_r * (TAU / count as f64).sin() - 2.0 * disk_r;
                    if gap < 0.5 {
                        return None;
                    }
                }
                // The hole must hold a free point.
                if ring_r - disk_r < 0.3 {
                    return None;
                }
                for &(x, y, r) in &loose {
                    let c = Point::new(1.0 + 18.0 * x, 1.0 + 18.0 * y);
                    if (c - centre).norm() > ring_r + disk_r + r + 0.5 {
                        disks.push(Disk::new(c.x, c.y, r));
                    }
                }
                let inner = centre;
                let outer = Point::new(0.2 + 19.6 * gu, 0.2 + 19.6 * gv);
                if (outer - centre).norm() < ring_r + disk_r + 0.3
                    || !is_free(&outer, &disks, &field, 0.0)
                {
                    return None;
                }
                let (start, goal) = if inside_start {
                    (inner, outer)
                } else {
                    (outer, inner)
                };
                Some(Ring {
                    inst: Instance {
                        field,
                        disks,
                        start,
                        goal,
                    },
                    closed,
                })
            },
        )
}

proptest! {
    #![proptest_config(config(96))]

    /// Enclosures: unreachable exactly when the ring is closed; the approximate planner
    /// agrees.
    #[test]
    fn rings_are_unreachable_exactly_when_closed(ring in rings()) {
        let inst = &ring.inst;
        let result = run(inst);
        let approx = approximate_length(&inst.field, &inst.disks, &inst.start, &inst.goal, 48);
        if ring.closed {
            prop_assert_eq!(result.clone().err(), Some(PathError::Unreachable));
            prop_assert!(approx.is_none());
        } else {
            let path = result.map_err(|e| TestCaseError::fail(format!("open ring: {e:?}")))?;
            check_path(&path, &inst.field, &inst.disks, &inst.start, &inst.goal)?;
            let a = approx.ok_or_else(|| TestCaseError::fail("approximate planner found no way through the gap"))?;
            prop_assert!(path.length_m() <= a + 1e-9);
        }
    }
}

/// A packed lattice of disks (a tight formation, every agent inflated): pockets closed by
/// overlapping neighbours, some disks missing, overlaps from clear to within rounding of
/// tangency (around the barrier margin of 1e-6 m), a start, goals and a query.
#[derive(Clone, Debug)]
struct Lattice {
    field: Field,
    disks: Vec<Disk>,
    start: Point,
    goals: Vec<Point>,
    query: Point,
}

/// Overlap `2 r - spacing` of lattice neighbours: clear, or near tangency.
fn lattice_overlap() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => 0.01..0.25f64,
        1 => prop::sample::select(vec![
            -2e-6, -1e-7, -2e-9, -1e-9, 0.0, 1e-9, 2e-9, 1e-7, 5e-7, 1e-6 - 1e-9, 1e-6,
            1e-6 + 1e-9, 2e-6,
        ]),
    ]
}

fn lattices() -> impl Strategy<Value = Lattice> {
    let raw_point = (0.0..1.0f64, 0.0..1.0f64, 0u8..4, 0usize..1024);
    (
        (0.7..1.6f64, lattice_overlap(), 0.0..0.08f64),
        (3usize..9, 3usize..8, 0.0..1.0f64, 0.0..1.0f64),
        prop::collection::vec((0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64), 64),
        0.0..0.15f64,
        prop::collection::vec(raw_point.clone(), 8),
        prop::collection::vec(raw_point, 24),
        (0.0..1.0f64, 0.0..1.0f64),
    )
        .prop_filter_map(
            "no free start",
            |((spacing, overlap, jitter), (cols, rows, ox, oy), noise, holes, starts, goals, q)| {
                let radius = 0.5 * (spacing + overlap);
                let field =
                    Field::new((cols as f64 + 1.5) * spacing, (rows as f64 + 1.5) * spacing);
                // The lattice may stick out of the field on the low side (walls close pockets).
                let origin = Point::new((ox - 0.3) * spacing, (oy - 0.3) * spacing);
                let mut disks = Vec::new();
                for i in 0..cols {
                    for j in 0..rows {
                        let (nx, ny, keep) = noise[(i * rows + j) % noise.len()];
                        if keep < holes {
                            continue;
                        }
                        let c = origin
                            + spacing * nalgebra::Vector2::new(i as f64 + 0.5, j as f64 + 0.5)
                            + jitter * spacing * nalgebra::Vector2::new(nx - 0.5, ny - 0.5);
                        disks.push(Disk {
                            centre: c,
                            radius_m: radius,
                        });
                    }
                }
                // Pocket centres, points exactly on circles or at crossings of two circles
                // (where best points lie), or anywhere.
                let place = |(u, v, kind, pick): (f64, f64, u8, usize)| -> Point {
                    let n = disks.len().max(1);
                    match kind {
                        0 => {
                            let i = (u * (cols + 1) as f64).floor();
                            let j = (v * (rows + 1) as f64).floor();
                            origin + spacing * nalgebra::Vector2::new(i, j)
                        }
                        1 if !disks.is_empty() => disks[pick % n].boundary_point(u * TAU),
                        2 if disks.len() > 1 => {
                            let a = disks[pick % n];
                            let b = disks[(pick + 1 + (v * 8.0) as usize) % n];
                            shared::geometry::circle_circle_intersections(
                                &a.centre, a.radius_m, &b.centre, b.radius_m,
                            )
                            .map_or(a.boundary_point(u * TAU), |x| x[(u < 0.5) as usize])
                        }
                        _ => Point::new(u * field.width_m, v * field.height_m),
                    }
                };
                let start = starts
                    .into_iter()
                    .map(place)
                    .find(|p| is_free(p, &disks, &field, 0.0))?;
                Some(Lattice {
                    field,
                    start,
                    goals: goals.into_iter().map(place).collect(),
                    query: Point::new(q.0 * field.width_m, q.1 * field.height_m),
                    disks,
                })
            },
        )
}

proptest! {
    #![proptest_config(config(64))]

    /// One start, many goals: the same answer as `shortest_path`, bit for bit (the barrier
    /// test only ever rejects unreachable goals).
    #[test]
    fn paths_from_one_start_match_shortest_path(lattice in lattices()) {
        let grid = DiskGrid::new(lattice.disks.clone());
        let layers = [&grid];
        let space = FreeSpace::new(lattice.field, &layers);
        let mut paths = PathsFrom::new(&space, &lattice.start);
        for goal in &lattice.goals {
            let fast = paths.shortest_path(goal);
            let slow = shortest_path(&space, &lattice.start, goal);
            // Debug output of f64 round-trips: equal text, equal bits.
            prop_assert_eq!(format!("{fast:?}"), format!("{slow:?}"), "goal {:?}", goal);
        }
    }
}

proptest! {
    #![proptest_config(config(24))]

    /// The reachable best point (the agent's turn) is the same point with the same path
    /// whether candidates are tested with `PathsFrom` or one `shortest_path` each.
    #[test]
    fn reachable_best_point_is_unchanged_by_paths_from(lattice in lattices()) {
        let grid = DiskGrid::new(lattice.disks.clone());
        let layers = [&grid];
        let space = FreeSpace::new(lattice.field, &layers);
        let from = lattice.start;
        let mut slow_path = None;
        let slow = nearest_reachable_free_point(&space, &lattice.query, &from, |p| {
            shortest_path(&space, &from, p).map(|path| slow_path = Some(path)).is_ok()
        });
        let mut fast_path = None;
        let mut paths = PathsFrom::new(&space, &from);
        let fast = nearest_reachable_free_point(&space, &lattice.query, &from, |p| {
            paths.shortest_path(p).map(|path| fast_path = Some(path)).is_ok()
        });
        prop_assert_eq!(format!("{fast:?}"), format!("{slow:?}"));
        prop_assert_eq!(format!("{fast_path:?}"), format!("{slow_path:?}"));
    }
}
