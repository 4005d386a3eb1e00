//! The monitor's checks on hand-made moves.

use super::*;

/// Agent 0's move from `from` along `waypoints` to `best`, straight segments, meant to
/// end at `best`.
fn move_of<'a>(from: &'a Point, waypoints: &'a [Point], best: &'a Point) -> MoveUnderCheck<'a> {
    MoveUnderCheck {
        agent: 0,
        from,
        waypoints,
        best,
        under_way: false,
        chord_errors_m: &[],
    }
}

/// `bodies` standing, none passing, no grid.
fn still(bodies: &[Body]) -> Standing<'_> {
    Standing {
        bodies,
        passing: &[],
        grid: None,
    }
}

fn bodies() -> Vec<Body> {
    vec![
        Body {
            position: Point::new(1.0, 5.0),
            radius_m: 0.3,
        },
        Body {
            position: Point::new(5.0, 7.5),
            radius_m: 0.3,
        },
    ]
}

#[test]
fn moves_longer_than_the_top_speed_and_moves_that_meet_are_caught() {
    let path = [Point::new(0.0, 0.0), Point::new(3.0, 4.0)];
    assert_eq!(check_length(&path, None), Ok(()));
    assert_eq!(check_length(&path, Some(5.0)), Ok(()));
    assert!(matches!(
        check_length(&path, Some(4.9)),
        Err(Refusal::TooLong { .. })
    ));
    let across = [Point::new(0.0, 4.0), Point::new(3.0, 0.0)];
    assert_eq!(distance_between_moves_m(&path, &across), 0.0);
    let beside = [Point::new(10.0, 4.0)];
    assert!((distance_between_moves_m(&path, &beside) - 7.0).abs() < 1e-12);
}

#[test]
fn moves_made_at_once_meet_only_where_both_agents_are_at_the_same_time() {
    // Both cross (1.5, 2): one halfway through the step, the other at its end.
    let first = [Point::new(0.0, 0.0), Point::new(3.0, 4.0)];
    let second = [Point::new(1.5, -2.0), Point::new(1.5, 2.0)];
    assert_eq!(distance_between_moves_m(&first, &second), 0.0);
    let apart = distance_between_simultaneous_moves_m(&first, &second);
    assert!(apart > 0.9, "{apart}");
    // Against shared's own arithmetic, on polylines of one to three points.
    let moves: [&[Point]; 4] = [
        &first,
        &second,
        &[Point::new(2.0, 1.0)],
        &[
            Point::new(4.0, 0.0),
            Point::new(1.0, 1.0),
            Point::new(0.0, 3.0),
        ],
    ];
    for a in moves {
        for b in moves {
            let parry = distance_between_simultaneous_moves_m(a, b);
            let own = shared::geometry::distance_at_the_same_time_m(a, b);
            assert!(
                (parry - own).abs() < 1e-9,
                "{a:?} {b:?}: {parry} against {own}"
            );
        }
    }
}

#[test]
fn the_monitor_keeps_moves_clear_of_polygons_non_convex_ones_too() {
    // A U open upwards: its notch (4..6 x 3..8) is free.
    let u = Polygon::new(vec![
        Point::new(3.0, 2.0),
        Point::new(7.0, 2.0),
        Point::new(7.0, 8.0),
        Point::new(6.0, 8.0),
        Point::new(6.0, 3.0),
        Point::new(4.0, 3.0),
        Point::new(4.0, 8.0),
        Point::new(3.0, 8.0),
    ])
    .expect("simple");
    let m = SafetyMonitor::new(Field::new(10.0, 10.0), &[]).with_polygons(&[u]);
    let lone = |p: Point| {
        vec![Body {
            position: p,
            radius_m: 0.3,
        }]
    };
    // Down into the notch, keeping 0.3 m from its walls: accepted.
    let from = Point::new(5.0, 9.5);
    let into = [from, Point::new(5.0, 3.3)];
    assert_eq!(
        m.check(&move_of(&from, &into, &into[1]), &still(&lone(from)), 8),
        Ok(())
    );
    // 0.1 m too deep, or through a wall, or standing inside: refused.
    for end in [Point::new(5.0, 3.2), Point::new(8.5, 5.0)] {
        let mv = [from, end];
        assert_eq!(
            m.check(&move_of(&from, &mv, &end), &still(&lone(from)), 8),
            Err(Refusal::Polygon {
                segment: 0,
                polygon: 0
            }),
            "{end:?}"
        );
    }
    let inside = Point::new(3.5, 5.0);
    assert!(matches!(
        m.check(
            &move_of(&inside, &[inside], &inside),
            &still(&lone(inside)),
            8
        ),
        Err(Refusal::Polygon { .. })
    ));
}

#[test]
fn the_monitor_refuses_what_breaks_the_invariant_and_accepts_the_rest() {
    let m = SafetyMonitor::new(Field::new(10.0, 10.0), &[Disk::new(5.0, 5.0, 1.0)]);
    let from = Point::new(1.0, 5.0);
    let clear = [from, Point::new(3.0, 3.0)];
    assert_eq!(
        m.check(&move_of(&from, &clear, &clear[1]), &still(&bodies()), 8),
        Ok(())
    );
    let through = [from, Point::new(9.0, 5.0)];
    assert!(matches!(
        m.check(&move_of(&from, &through, &through[1]), &still(&bodies()), 8),
        Err(Refusal::Obstacle { obstacle: 0, .. })
    ));
    let around = [
        from,
        Point::new(3.0, 7.0),
        Point::new(7.0, 7.0),
        Point::new(9.0, 5.0),
    ];
    assert_eq!(
        m.check(
            &move_of(&from, &around, &around[3]),
            &still(&bodies()[..1]),
            8
        ),
        Ok(())
    );
    assert!(matches!(
        m.check(&move_of(&from, &around, &around[3]), &still(&bodies()), 8),
        Err(Refusal::Agent { agent: 1, .. })
    ));
    // A mate that moves at the same time is not in the way here: the two moves are
    // checked against each other in time when the group is settled.
    let passing = vec![false, true];
    assert_eq!(
        m.check(
            &move_of(&from, &around, &around[3]),
            &Standing {
                bodies: &bodies(),
                passing: &passing,
                grid: None
            },
            8
        ),
        Ok(())
    );
    let nan = [from, Point::new(f64::NAN, 0.0)];
    assert!(matches!(
        m.check(&move_of(&from, &nan, &nan[1]), &still(&bodies()), 8),
        Err(Refusal::NotFinite(1))
    ));
    let jump = [Point::new(2.0, 2.0)];
    assert!(matches!(
        m.check(&move_of(&from, &jump, &jump[0]), &still(&bodies()), 8),
        Err(Refusal::Teleport(_))
    ));
    let out = [from, Point::new(0.2, 5.0)];
    assert!(matches!(
        m.check(&move_of(&from, &out, &out[1]), &still(&bodies()), 8),
        Err(Refusal::OutsideField(1))
    ));
    assert!(matches!(
        m.check(&move_of(&from, &clear, &from), &still(&bodies()), 8),
        Err(Refusal::WrongEnd)
    ));
    // Under way, a move may stop short of its best point.
    assert_eq!(
        m.check(
            &MoveUnderCheck {
                under_way: true,
                ..move_of(&from, &clear, &from)
            },
            &still(&bodies()),
            8
        ),
        Ok(())
    );
    // Touching is allowed: exactly the radii sum away.
    let touch = [from, Point::new(3.7, 5.0)];
    assert_eq!(
        m.check(
            &move_of(&from, &touch, &touch[1]),
            &still(&bodies()[..1]),
            8
        ),
        Ok(())
    );
}

proptest::proptest! {
    /// With a grid over the bodies the monitor checks a move against the bodies near it
    /// only: it must refuse exactly what the check against every body refuses, naming the
    /// same segment and the same agent.
    #[test]
    fn a_grid_over_the_bodies_changes_no_verdict(
        spots in proptest::collection::vec((1.0f64..19.0, 1.0f64..19.0, 0.1f64..0.6), 2..60),
        path in proptest::collection::vec((1.0f64..19.0, 1.0f64..19.0), 0..4),
        passing_bits in proptest::collection::vec(proptest::bool::weighted(0.2), 60),
        mover_pick in 0usize..60,
    ) {
        let bodies: Vec<Body> = spots
            .iter()
            .map(|&(x, y, r)| Body { position: Point::new(x, y), radius_m: r })
            .collect();
        let agent = mover_pick % bodies.len();
        let from = bodies[agent].position;
        let waypoints: Vec<Point> = std::iter::once(from)
            .chain(path.iter().map(|&(x, y)| Point::new(x, y)))
            .collect();
        let best = *waypoints.last().expect("one at least");
        let grid = shared::control::safety::bodies_grid(&bodies);
        let passing = &passing_bits[..bodies.len()];
        let m = SafetyMonitor::new(Field::new(20.0, 20.0), &[]);
        let mv = MoveUnderCheck {
            agent,
            from: &from,
            waypoints: &waypoints,
            best: &best,
            under_way: false,
            chord_errors_m: &[],
        };
        let scan = Standing { bodies: &bodies, passing, grid: None };
        let indexed = Standing { grid: Some(&grid), ..scan };
        proptest::prop_assert_eq!(m.check(&mv, &scan, 8), m.check(&mv, &indexed, 8));
    }
}
