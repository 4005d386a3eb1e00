//! Property tests of Hybrid A* on small random fields: whenever a path comes back, it
//! starts and ends exactly at the given poses, keeps the clearance (brute force over every
//! obstacle, at every pose and along every chord), respects the turning radius and, when
//! reverse is not allowed, never backs up. Blocked endpoints are reported as such.

use proptest::prelude::*;

use shared::geometry::{Disk, Field, Pose, distance_point_segment, wrap_angle_rad};
use shared::paths::hybrid_astar::{HybridAStarSettings, PlanError, plan, resample};

#[derive(Clone, Debug)]
struct Case {
    field: Field,
    obstacles: Vec<Disk>,
    start: Pose,
    goal: Pose,
    turning_radius_m: f64,
    clearance_m: f64,
    allow_reverse: bool,
}

fn case() -> impl Strategy<Value = Case> {
    (15.0..40.0f64, 15.0..30.0f64)
        .prop_flat_map(|(w, h)| {
            let pose = move || {
                (0.8..w - 0.8, 0.8..h - 0.8, -3.2..3.2f64).prop_map(|(x, y, t)| Pose::new(x, y, t))
            };
            (
                Just(Field::new(w, h)),
                prop::collection::vec(
                    (0.0..w, 0.0..h, 0.3..1.5f64).prop_map(|(x, y, r)| Disk::new(x, y, r)),
                    0..15,
                ),
                pose(),
                pose(),
                1.0..3.0f64,
                0.2..0.6f64,
                any::<bool>(),
                prop::bool::weighted(0.75),
            )
        })
        .prop_map(
            |(
                field,
                mut obstacles,
                start,
                goal,
                turning_radius_m,
                clearance_m,
                allow_reverse,
                clear_ends,
            )| {
                if clear_ends {
                    // Mostly keep the endpoints free, so that most cases plan.
                    obstacles.retain(|d| {
                        [start, goal].iter().all(|p| {
                            (p.position() - d.centre).norm() > d.radius_m + clearance_m + 0.1
                        })
                    });
                }
                Case {
                    field,
                    obstacles,
                    start,
                    goal,
                    turning_radius_m,
                    clearance_m,
                    allow_reverse,
                }
            },
        )
}

fn blocked(case: &Case, p: &Pose) -> bool {
    let c = case.clearance_m;
    let f = &case.field;
    p.x_m < c
        || p.y_m < c
        || p.x_m > f.width_m - c
        || p.y_m > f.height_m - c
        || case
            .obstacles
            .iter()
            .any(|d| (p.position() - d.centre).norm() < d.radius_m + c)
}

fn same_pose(a: &Pose, b: &Pose) -> bool {
    (a.x_m - b.x_m).abs() <= 1e-9
        && (a.y_m - b.y_m).abs() <= 1e-9
        && wrap_angle_rad(a.heading_rad - b.heading_rad).abs() <= 1e-9
}

fn check_path(
    case: &Case,
    settings: &HybridAStarSettings,
    path: &[Pose],
) -> Result<(), TestCaseError> {
    let c = case.clearance_m;
    prop_assert!(path.len() >= 2);
    prop_assert!(same_pose(&path[0], &case.start), "first {:?}", path[0]);
    prop_assert!(
        same_pose(&path[path.len() - 1], &case.goal),
        "last {:?}",
        path[path.len() - 1]
    );
    let f = &case.field;
    for p in path {
        let q = p.position();
        prop_assert!(
            q.x >= c - 1e-9
                && q.y >= c - 1e-9
                && q.x <= f.width_m - c + 1e-9
                && q.y <= f.height_m - c + 1e-9,
            "pose {:?} leaves the field",
            p
        );
        for d in &case.obstacles {
            prop_assert!(
                (q - d.centre).norm() - d.radius_m >= c - 1e-9,
                "pose {:?} hits {:?}",
                p,
                d
            );
        }
    }
    let limit = 1.0 / settings.turning_radius_m;
    for w in path.windows(2) {
        let (a, b) = (w[0].position(), w[1].position());
        for d in &case.obstacles {
            prop_assert!(distance_point_segment(&d.centre, &a, &b) - d.radius_m >= c - 1e-9);
        }
        let distance = (b - a).norm();
        let turn = wrap_angle_rad(w[1].heading_rad - w[0].heading_rad).abs();
        prop_assert!(distance <= settings.sample_spacing_m + 1e-9);
        if distance < 1e-9 {
            prop_assert!(turn < 1e-9);
            continue;
        }
        prop_assert!(
            turn / distance <= limit * (1.0 + 1e-3) + 1e-9,
            "curvature {}",
            turn / distance
        );
        let along = (b - a).dot(&nalgebra::Vector2::new(
            w[0].heading_rad.cos(),
            w[0].heading_rad.sin(),
        ));
        if !case.allow_reverse {
            prop_assert!(along > 0.0, "reverse motion");
        }
    }
    let samples = resample(path, 0.4);
    prop_assert!(same_pose(&samples[0], &case.start));
    prop_assert_eq!(samples[samples.len() - 1], case.goal);
    for w in samples.windows(2) {
        prop_assert!((w[1].position() - w[0].position()).norm() <= 0.4 + 1e-9);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn returned_paths_have_every_property(case in case()) {
        let mut settings = HybridAStarSettings::new(case.turning_radius_m, case.clearance_m, case.allow_reverse);
        settings.max_expansions = 20_000;
        let result = plan(&case.field, &case.obstacles, &case.start, &case.goal, &settings);
        match result {
            Ok(path) => {
                prop_assert!(!blocked(&case, &case.start) && !blocked(&case, &case.goal));
                check_path(&case, &settings, &path)?;
            }
            Err(PlanError::StartBlocked) => prop_assert!(blocked(&case, &case.start)),
            Err(PlanError::GoalBlocked) => {
                prop_assert!(!blocked(&case, &case.start) && blocked(&case, &case.goal));
            }
            Err(PlanError::NoPath) | Err(PlanError::ExpansionLimit { .. }) => {}
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }
}
