//! The recorder's check of a move against the other bodies ([`check_move`]) finds the
//! same first overlap as the plain definition: every segment against every body, the
//! distance from the body's centre to the segment against the radii sum. It skips bodies
//! it can rule out by their box; this checks that it never skips one it should not. The
//! clearance to the nearest other body likewise equals the plain minimum. Both again with
//! a grid over the bodies, which finds the bodies near the move or the body only.

use proptest::prelude::*;
use shared::control::safety::{
    Others, SAFETY_TOLERANCE_M, Violation, bodies_grid, check_move, check_move_among,
    clearance_to_others_m, clearances_of_m,
};
use shared::control::vocabulary::{Body, MAX_WAYPOINTS};
use shared::geometry::{DiskGrid, Field, Point, distance_point_segment};

/// The first (segment, body, overlap) by the plain definition, segment by segment.
fn first_overlap(
    others: &[Body],
    radius_m: f64,
    waypoints: &[Point],
) -> Option<(usize, usize, f64)> {
    let single = [waypoints[0], waypoints[0]];
    let segments: &[Point] = if waypoints.len() == 1 {
        &single
    } else {
        waypoints
    };
    for (segment, w) in segments.windows(2).enumerate() {
        for (body, o) in others.iter().enumerate() {
            let overlap_m =
                o.radius_m + radius_m - distance_point_segment(&o.position, &w[0], &w[1]);
            if overlap_m > SAFETY_TOLERANCE_M {
                return Some((segment, body, overlap_m));
            }
        }
    }
    None
}

fn point() -> impl Strategy<Value = Point> {
    (1.0..19.0_f64, 1.0..19.0_f64).prop_map(|(x, y)| Point::new(x, y))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn the_first_overlap_is_the_plain_definitions(
        others in prop::collection::vec((point(), 0.05..0.8_f64), 0..40),
        from in point(),
        rest in prop::collection::vec(point(), 0..5),
        radius_m in 0.05..0.5_f64,
    ) {
        let field = Field::new(20.0, 20.0);
        let obstacles = DiskGrid::new(Vec::new());
        let others: Vec<Body> = others
            .into_iter()
            .map(|(position, radius_m)| Body { position, radius_m })
            .collect();
        // Moves that stay inside the field, as the field check would refuse them first.
        let waypoints: Vec<Point> = std::iter::once(from).chain(rest).collect();
        let got = check_move(&field, &obstacles, &others, radius_m, &from, &waypoints, MAX_WAYPOINTS);
        // The same move as the last of all the bodies, the others found with a grid.
        let mut all = others.clone();
        all.push(Body { position: from, radius_m });
        let grid = bodies_grid(&all);
        let among = Others { bodies: &all, passing: &[], grid: Some(&grid) };
        let with_grid = check_move_among(
            &field, &obstacles, &among, others.len(), &from, &waypoints, &[], MAX_WAYPOINTS,
        );
        prop_assert_eq!(&with_grid, &got);
        match first_overlap(&others, radius_m, &waypoints) {
            None => prop_assert!(got.is_ok(), "{got:?}"),
            Some((segment, body, overlap_m)) => prop_assert_eq!(
                got,
                Err(Violation::HitsBody { segment, body, overlap_m })
            ),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// The clearance to the nearest other body is the plain minimum over all of them, to
    /// the bit (bodies ruled out by their offsets are skipped).
    #[test]
    fn the_clearance_to_the_others_is_the_plain_minimum(
        bodies in prop::collection::vec((point(), 0.05..0.8_f64), 1..40),
        agent_pick in 0usize..1000,
    ) {
        let bodies: Vec<Body> = bodies
            .into_iter()
            .map(|(position, radius_m)| Body { position, radius_m })
            .collect();
        let agent = agent_pick % bodies.len();
        let me = &bodies[agent];
        let want = bodies
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != agent)
            .map(|(_, o)| (me.position - o.position).norm() - o.radius_m - me.radius_m)
            .fold(f64::INFINITY, f64::min);
        let obstacles = DiskGrid::new(Vec::new());
        let (_, got) = clearances_of_m(&bodies, agent, &obstacles, 1.0);
        prop_assert_eq!(got.to_bits(), want.to_bits());
        let with_grid = clearance_to_others_m(&bodies, agent, &bodies_grid(&bodies));
        prop_assert_eq!(with_grid.to_bits(), want.to_bits());
    }
}
