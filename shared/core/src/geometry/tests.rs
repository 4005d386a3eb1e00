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

mod polygons {
    use proptest::prelude::*;

    use super::*;

    /// A star-shaped polygon round `c`: simple by construction, its corners at increasing
    /// angles (anticlockwise) or decreasing ones.
    fn star(c: Point, radii: &[f64], clockwise: bool) -> Vec<Point> {
        let n = radii.len() as f64;
        let mut v: Vec<Point> = radii
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let a = std::f64::consts::TAU * k as f64 / n;
                c + *r * Vector::new(a.cos(), a.sin())
            })
            .collect();
        if clockwise {
            v.reverse();
        }
        v
    }

    /// Whether `p` is in the triangle `a b c` (anticlockwise), boundary included.
    fn in_triangle(p: &Point, a: &Point, b: &Point, c: &Point) -> bool {
        let s = |u: &Point, w: &Point| (w - u).perp(&(p - u));
        s(a, b) >= 0.0 && s(b, c) >= 0.0 && s(c, a) >= 0.0
    }

    proptest! {
        #[test]
        fn star_shaped_polygons_are_simple_and_their_fans_agree(
            radii in proptest::collection::vec(0.5f64..3.0, 3..24),
            clockwise in any::<bool>(),
            probes in proptest::collection::vec((-3.5f64..3.5, -3.5f64..3.5), 32),
        ) {
            let c = Point::new(1.0, -2.0);
            let given = star(c, &radii, clockwise);
            let polygon = Polygon::new(given.clone()).unwrap();
            // Stored anticlockwise: the same corners, reversed if given clockwise.
            let mut expected = given;
            if clockwise {
                expected.reverse();
            }
            prop_assert_eq!(polygon.vertices(), &expected[..]);
            // Area and containment against the fan of triangles from the centre.
            let fan: Vec<(Point, Point)> = polygon.sides().collect();
            let area: f64 = fan.iter().map(|(a, b)| 0.5 * (a - c).perp(&(b - c))).sum();
            prop_assert!((polygon.area_m2() - area).abs() < 1e-9);
            for (x, y) in probes {
                let p = c + Vector::new(x, y);
                let inside = fan.iter().any(|(a, b)| in_triangle(&p, &c, a, b));
                let near_edge = fan.iter().any(|(a, b)| distance_point_segment(&p, a, b) < 1e-9);
                if !near_edge {
                    prop_assert_eq!(polygon.contains(&p), inside);
                    prop_assert_eq!(polygon.distance_m(&p) == 0.0, inside);
                }
            }
        }

        #[test]
        fn swapping_two_corners_of_a_convex_polygon_crosses_it(
            n in 5usize..16,
            k in 0usize..16,
        ) {
            // A regular polygon with corners k and k + 2 swapped: sides cross.
            let mut v = star(Point::origin(), &vec![1.0; n], false);
            let k = k % n;
            v.swap(k, (k + 2) % n);
            prop_assert!(
                matches!(Polygon::new(v), Err(PolygonError::SelfIntersecting { .. })),
                "n = {}, k = {}", n, k
            );
        }
    }

    #[test]
    fn degenerate_corners_are_refused_naming_the_vertex() {
        let p = |x, y| Point::new(x, y);
        let cases: [(Vec<Point>, &str); 5] = [
            (vec![p(0.0, 0.0), p(1.0, 0.0)], "at least 3 vertices, got 2"),
            (
                vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 0.0), p(0.0, 1.0)],
                "vertex 1 repeats",
            ),
            (
                vec![p(0.0, 0.0), p(f64::NAN, 0.0), p(0.0, 1.0)],
                "vertex 1 is not finite",
            ),
            (
                vec![p(0.0, 0.0), p(1.0, 0.0), p(2.0, 0.0)],
                "crosses itself",
            ),
            // A spike folding back along its own side.
            (
                vec![p(0.0, 0.0), p(2.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)],
                "side 0 (vertices 0-1) meets side 1",
            ),
        ];
        for (v, says) in cases {
            let e = Polygon::new(v.clone()).unwrap_err().to_string();
            assert!(e.contains(says), "{v:?}: {e}");
        }
        // Convex corners of an L: all but the inner one.
        let l = Polygon::new(vec![
            p(0.0, 0.0),
            p(2.0, 0.0),
            p(2.0, 1.0),
            p(1.0, 1.0),
            p(1.0, 2.0),
            p(0.0, 2.0),
        ])
        .unwrap();
        assert_eq!(l.convex_corners().collect::<Vec<_>>(), [0, 1, 2, 4, 5]);
    }
}
