//! Tests of the geometry against brute force.

use std::ops::ControlFlow;

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
fn all_near_holds_when_no_near_disk_fails_and_stops_at_the_first_that_does() {
    let grid = DiskGrid::new(vec![Disk::new(1.0, 1.0, 0.5), Disk::new(9.0, 9.0, 0.5)]);
    let p = Point::new(1.0, 2.0);
    let clear_by = |m: f64| move |d: &Disk| d.signed_distance_m(&p) >= m;
    assert!(
        grid.all_near(&p, 1.0, clear_by(0.5)),
        "0.5 m from the near disk"
    );
    assert!(!grid.all_near(&p, 1.0, clear_by(0.6)));
    // The far disk is not looked at: a predicate that fails on it changes nothing.
    let mut looked = Vec::new();
    assert!(grid.all_near(&p, 1.0, |d| {
        looked.push(d.centre);
        d.centre.x < 5.0
    }));
    assert_eq!(looked, vec![Point::new(1.0, 1.0)]);
    // Stops at the first disk that fails.
    let mut calls = 0;
    assert!(!grid.all_near(&p, 20.0, |_| {
        calls += 1;
        false
    }));
    assert_eq!(calls, 1);
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
    let [p, q] = circle_line_intersections(&c, 2.5, &Point::new(0.0, 0.0), &Vector::new(0.0, 5.0))
        .expect("the line x = 0 crosses");
    for x in [p, q] {
        assert_eq!(x.x, 0.0);
        assert!(((x - c).norm() - 2.5).abs() < 1e-12);
    }
    assert!(p.y < q.y, "ordered along the direction");
    let [t, u] = circle_line_intersections(&c, 2.0, &Point::new(0.0, 3.0), &Vector::new(1.0, 0.0))
        .expect("tangent");
    assert_eq!(t, Point::new(2.0, 3.0));
    assert_eq!(t, u);
    assert!(
        circle_line_intersections(&c, 2.0, &Point::new(0.0, 3.5), &Vector::new(1.0, 0.0)).is_none()
    );
    assert!(circle_line_intersections(&c, 2.0, &c, &Vector::zeros()).is_none());
}
