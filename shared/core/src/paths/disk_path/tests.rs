//! End-to-end tests of [`shortest_path`], and the scenes the unit tests share.

use std::f64::consts::TAU;

use super::free_arcs::turn_rem;
use super::{DiskPath, PathError, PathPiece, shortest_path};
use crate::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};

fn plan(field: Field, disks: Vec<Disk>, from: Point, to: Point) -> Result<DiskPath, PathError> {
    let grid = DiskGrid::new(disks);
    let layers = [&grid];
    let space = FreeSpace::new(field, &layers);
    shortest_path(&space, &from, &to)
}

/// Brute-force minimum clearance of dense samples against every disk, and the
/// smallest inset into the field.
fn min_clearance_and_inset(path: &DiskPath, disks: &[Disk], field: &Field) -> (f64, f64) {
    let mut clearance = f64::INFINITY;
    let mut inset = f64::INFINITY;
    for p in path.sample(1e-3) {
        for d in disks {
            clearance = clearance.min((p - d.centre).norm() - d.radius_m);
        }
        inset = inset.min(field.signed_inset_m(&p));
    }
    (clearance, inset)
}

fn assert_continuous(path: &DiskPath, from: &Point, to: &Point) {
    assert_eq!(path.start(), *from);
    assert_eq!(path.end(), *to);
    for w in path.pieces.windows(2) {
        assert!(
            (w[0].end() - w[1].start()).norm() <= 1e-9,
            "gap between {:?} and {:?}",
            w[0],
            w[1]
        );
    }
}

#[test]
fn straight_line_when_visible() {
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(5.0, 8.0, 1.0)];
    let (a, b) = (Point::new(1.0, 1.0), Point::new(9.0, 2.0));
    let path = plan(field, disks, a, b).expect("path");
    assert_eq!(path.pieces, vec![PathPiece::Segment { from: a, to: b }]);
    assert!((path.length_m() - (b - a).norm()).abs() < 1e-12);
}

#[test]
fn same_point_is_a_zero_length_segment() {
    let field = Field::new(10.0, 10.0);
    let a = Point::new(3.0, 3.0);
    let path = plan(field, vec![], a, a).expect("path");
    assert_eq!(path.pieces.len(), 1);
    assert_eq!(path.length_m(), 0.0);
    assert_eq!((path.start(), path.end()), (a, a));
    assert_eq!(path.sample(0.1), vec![a, a]);
}

#[test]
fn one_disk_in_the_way_matches_the_analytic_length() {
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(5.0, 5.0, 1.0)];
    let (a, b) = (Point::new(2.0, 5.0), Point::new(8.0, 5.0));
    let path = plan(field, disks.clone(), a, b).expect("path");
    // Two tangents of length sqrt(3^2 - 1^2), and the arc between the tangent points.
    let expected = 2.0 * 8f64.sqrt() + (std::f64::consts::PI - 2.0 * (1.0f64 / 3.0).acos());
    assert!(
        (path.length_m() - expected).abs() < 1e-9,
        "{} vs {}",
        path.length_m(),
        expected
    );
    assert_eq!(path.pieces.len(), 3);
    assert!(matches!(path.pieces[1], PathPiece::Arc { .. }));
    assert_continuous(&path, &a, &b);
    let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9 && inset >= -1e-9);
}

#[test]
fn start_and_goal_on_the_boundary() {
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(5.0, 5.0, 1.0)];
    let (a, b) = (Point::new(4.0, 5.0), Point::new(6.0, 5.0));
    let path = plan(field, disks.clone(), a, b).expect("path");
    assert!((path.length_m() - std::f64::consts::PI).abs() < 1e-9);
    assert_continuous(&path, &a, &b);
    // Start on the boundary, goal far: tangent from the goal, arc from the start.
    let c = Point::new(9.0, 5.0);
    let path = plan(field, disks.clone(), a, c).expect("path");
    let expected = 15f64.sqrt() + (std::f64::consts::PI - (0.25f64).acos());
    assert!(
        (path.length_m() - expected).abs() < 1e-9,
        "{} vs {}",
        path.length_m(),
        expected
    );
    assert_continuous(&path, &a, &c);
    let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9);
}

#[test]
fn goal_where_two_circles_cross() {
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(4.0, 5.0, 1.0), Disk::new(5.5, 5.0, 1.0)];
    // Upper intersection point of the two circles.
    let y = 5.0 + (1.0f64 - 0.75f64 * 0.75).sqrt();
    let goal = Point::new(4.75, y);
    let start = Point::new(4.75, 3.0);
    let path = plan(field, disks.clone(), start, goal).expect("path");
    assert_continuous(&path, &start, &goal);
    let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9, "{clearance}");
    let back = plan(field, disks.clone(), goal, start).expect("path back");
    assert!((back.length_m() - path.length_m()).abs() < 1e-9);
}

#[test]
fn enclosed_goal_is_unreachable() {
    let field = Field::new(20.0, 20.0);
    let mut disks = Vec::new();
    for i in 0..12 {
        let a = i as f64 * TAU / 12.0;
        disks.push(Disk::new(10.0 + 3.0 * a.cos(), 10.0 + 3.0 * a.sin(), 1.0));
    }
    let inside = Point::new(10.0, 10.0);
    let outside = Point::new(1.0, 2.0);
    assert_eq!(
        plan(field, disks.clone(), outside, inside),
        Err(PathError::Unreachable)
    );
    assert_eq!(
        plan(field, disks.clone(), inside, outside),
        Err(PathError::Unreachable)
    );
    assert_eq!(
        plan(
            field,
            disks.clone(),
            Point::new(10.0, 10.0),
            Point::new(10.0, 14.5)
        ),
        Err(PathError::Unreachable)
    );
    // Remove one disk of the ring: a path exists and goes through the gap.
    disks.remove(3);
    let path = plan(field, disks.clone(), outside, inside).expect("path through the gap");
    let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9);
}

#[test]
fn wall_and_disk_enclose_a_corner() {
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(0.0, 0.0, 3.0)];
    let r = plan(field, disks, Point::new(0.5, 0.5), Point::new(8.0, 8.0));
    assert_eq!(r, Err(PathError::StartNotFree));
    // A disk across the corner region: x + y < 2 is cut off by a barrier of three disks.
    let disks = vec![
        Disk::new(0.0, 3.0, 1.0),
        Disk::new(1.5, 1.5, 1.3),
        Disk::new(3.0, 0.0, 1.0),
    ];
    let r = plan(field, disks, Point::new(0.3, 0.3), Point::new(8.0, 8.0));
    assert_eq!(r, Err(PathError::Unreachable));
}

#[test]
fn disk_sticking_out_of_the_field_forces_the_other_side() {
    let field = Field::new(10.0, 10.0);
    // Centre above the line s-t, so going below would be shorter, but the disk reaches
    // below y = 0: the lower arc would leave the field.
    let disks = vec![Disk::new(5.0, 1.5, 2.0)];
    let (a, b) = (Point::new(1.0, 1.0), Point::new(9.0, 1.0));
    let path = plan(field, disks.clone(), a, b).expect("path");
    let c = disks[0].centre;
    let (va, vb) = (a - c, b - c);
    let d = va.norm();
    let (angle_a, angle_b) = (va.y.atan2(va.x), vb.y.atan2(vb.x));
    let over_top = turn_rem(angle_a - angle_b);
    let expected = 2.0 * (d * d - 4.0).sqrt() + 2.0 * (over_top - 2.0 * (2.0 / d).acos());
    assert!(
        (path.length_m() - expected).abs() < 1e-9,
        "{} vs {}",
        path.length_m(),
        expected
    );
    let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9 && inset >= -1e-9);
    assert!(
        path.sample(0.01).iter().any(|p| p.y > 3.0),
        "goes over the top"
    );
}

#[test]
fn an_arc_may_not_dip_out_of_the_field() {
    // Start and goal on the circle, both in the field; the short arc between them passes
    // below y = 0, so the path goes the long way round (three quarters of the circle).
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(5.0, 2.0, 2.5)];
    let a = disks[0].boundary_point(-0.75 * std::f64::consts::PI);
    let b = disks[0].boundary_point(-0.25 * std::f64::consts::PI);
    assert!(field.contains(&a, 0.0) && field.contains(&b, 0.0));
    let path = plan(field, disks.clone(), a, b).expect("path");
    let expected = 2.5 * 1.5 * std::f64::consts::PI;
    assert!(
        (path.length_m() - expected).abs() < 1e-9,
        "{} vs {}",
        path.length_m(),
        expected
    );
    let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9 && inset >= -1e-9);
}

#[test]
fn long_wall_needs_several_ellipse_rounds() {
    // A wall of overlapping disks between start and goal; its free end lies far outside
    // the first ellipses, whose candidate disks stop part-way up the wall.
    let field = Field::new(60.0, 20.0);
    let disks: Vec<Disk> = (0..28)
        .map(|i| Disk::new(30.0, 0.6 * i as f64, 0.5))
        .collect();
    let (a, b) = (Point::new(29.0, 5.0), Point::new(31.0, 5.0));
    let path = plan(field, disks.clone(), a, b).expect("path");
    assert_continuous(&path, &a, &b);
    let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9 && inset >= -1e-9, "{clearance} {inset}");
    // Around the top disk (30, 16.2): symmetric tangents plus the arc over it.
    let top = disks[27];
    let d = (top.centre - a).norm();
    // a and b seen from the top centre are 2 atan(1 / 11.2) apart below it; the arc
    // covers the rest of the turn minus the two tangent angles.
    let below = 2.0 * (1.0f64 / 11.2).atan();
    let over = TAU - below - 2.0 * (0.5 / d).acos();
    let expected = 2.0 * (d * d - 0.25).sqrt() + 0.5 * over;
    assert!(
        (path.length_m() - expected).abs() < 1e-9,
        "{} vs {}",
        path.length_m(),
        expected
    );
}

#[test]
fn a_path_longer_than_the_ellipse_bound_is_not_trusted() {
    // Wall of small disks with one large disk k in it. In the round with bound 16 the
    // tangent points on k lie in the ellipse but the arc over k's top runs into the next
    // wall disk, which is not a candidate yet: that (invalid) path is longer than the
    // bound, so it must be rejected and the search widened.
    let field = Field::new(60.0, 60.0);
    let mut disks: Vec<Disk> = (0..=27)
        .map(|i| Disk::new(30.0, 0.6 * i as f64, 0.5))
        .collect();
    disks.push(Disk::new(30.0, 18.2, 2.0));
    disks.extend((0..=33).map(|i| Disk::new(30.0, 20.0 + 0.6 * i as f64, 0.5)));
    let (a, b) = (Point::new(29.0, 11.0), Point::new(31.0, 11.0));
    let path = plan(field, disks.clone(), a, b).expect("path");
    let (clearance, inset) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9 && inset >= -1e-9, "{clearance} {inset}");
    // Up the left side: tangent to k, arc on k, outer tangent from k to the top wall
    // disk (30, 39.8), over its top, and the mirror image down to b.
    let (ck, rk, r_top, rise) = (Point::new(30.0, 18.2), 2.0, 0.5, 39.8 - 18.2);
    let d1 = (ck - a).norm();
    let theta1 = (a - ck).y.atan2((a - ck).x) + TAU - (rk / d1).acos();
    let alpha = ((rk - r_top) / rise).asin();
    let theta2 = std::f64::consts::PI - alpha;
    let side = (d1 * d1 - rk * rk).sqrt()
        + rk * (theta1 - theta2)
        + (rise * rise - (rk - r_top).powi(2)).sqrt();
    let expected = 2.0 * side + r_top * (std::f64::consts::PI - 2.0 * alpha);
    assert!(
        (path.length_m() - expected).abs() < 1e-9,
        "{} vs {}",
        path.length_m(),
        expected
    );
}

#[test]
fn start_and_goal_within_tolerance_inside_a_disk() {
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(5.0, 5.0, 1.0)];
    let a = Point::new(4.0 + 5e-10, 5.0);
    let b = Point::new(6.0 - 5e-10, 5.0);
    let path = plan(field, disks.clone(), a, b).expect("path");
    assert_continuous(&path, &a, &b);
    assert!((path.length_m() - std::f64::consts::PI).abs() < 1e-8);
    let (clearance, _) = min_clearance_and_inset(&path, &disks, &field);
    assert!(clearance >= -1e-9, "{clearance}");
    let deep = Point::new(4.0 + 2e-9, 5.0);
    assert_eq!(plan(field, disks, deep, b), Err(PathError::StartNotFree));
}

#[test]
fn every_layer_blocks() {
    let field = Field::new(10.0, 10.0);
    let obstacles = DiskGrid::new(vec![Disk::new(5.0, 5.0, 1.0)]);
    let agents = DiskGrid::new(vec![Disk::new(5.0, 6.5, 0.6), Disk::new(5.0, 3.5, 0.6)]);
    let layers = [&obstacles, &agents];
    let space = FreeSpace::new(field, &layers);
    let (a, b) = (Point::new(2.0, 5.0), Point::new(8.0, 5.0));
    let path = shortest_path(&space, &a, &b).expect("path");
    let mut all = obstacles.disks().to_vec();
    all.extend_from_slice(agents.disks());
    let (clearance, _) = min_clearance_and_inset(&path, &all, &field);
    assert!(clearance >= -1e-9, "{clearance}");
    let one_disk = 2.0 * 8f64.sqrt() + (std::f64::consts::PI - 2.0 * (1.0f64 / 3.0).acos());
    assert!(
        path.length_m() > one_disk + 0.1,
        "the agents' layer must lengthen the path"
    );
}

#[test]
fn start_and_goal_outside_free_space_are_rejected() {
    let field = Field::new(10.0, 10.0);
    let disks = vec![Disk::new(5.0, 5.0, 1.0)];
    let inside = Point::new(5.2, 5.0);
    let free = Point::new(1.0, 1.0);
    assert_eq!(
        plan(field, disks.clone(), inside, free),
        Err(PathError::StartNotFree)
    );
    assert_eq!(
        plan(field, disks.clone(), free, inside),
        Err(PathError::GoalNotFree)
    );
    assert_eq!(
        plan(field, disks.clone(), Point::new(-1.0, 1.0), free),
        Err(PathError::StartNotFree)
    );
    let nan = Point::new(f64::NAN, 1.0);
    assert_eq!(plan(field, disks, nan, free), Err(PathError::StartNotFree));
}

#[test]
fn determinism() {
    let field = Field::new(20.0, 20.0);
    let disks: Vec<Disk> = (0..30)
        .map(|i| {
            let f = i as f64;
            Disk::new(
                (f * 7.3) % 20.0,
                (f * 3.7 + 1.0) % 20.0,
                0.8 + (f * 0.37) % 0.9,
            )
        })
        .collect();
    let (a, b) = (Point::new(0.2, 0.2), Point::new(19.5, 19.7));
    let p1 = plan(field, disks.clone(), a, b);
    let p2 = plan(field, disks, a, b);
    assert_eq!(format!("{p1:?}"), format!("{p2:?}"));
}

/// A packed block of agents at 1 m spacing, each inflated to 0.601 m (radius 0.3 m
/// twice plus a margin): orthogonal neighbours overlap, so every agent's position is a
/// pocket closed by its eight neighbours.
pub(super) fn packed_block() -> (Field, Vec<Disk>) {
    let mut disks = Vec::new();
    for i in 0..9 {
        for j in 0..7 {
            disks.push(Disk::new(2.0 + i as f64, 2.0 + j as f64, 0.601));
        }
    }
    (Field::new(14.0, 12.0), disks)
}
