//! Properties of the best point on random fields, checked by brute force over all disks,
//! independently of the grid index.

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shared::control::best_point::{
    BestPointError, nearest_free_point, nearest_reachable_free_point,
};
use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point, Vector};

/// Feasibility and optimality slack, in metres.
const TOLERANCE_M: f64 = 1e-9;

/// A random field with disks (already inflated) and a query.
#[derive(Clone, Debug)]
struct Scene {
    field: Field,
    disks: Vec<Disk>,
    query: Point,
    /// Seed of the sample points used to look for a better free point.
    sample_seed: u64,
}

/// Where the query is put.
#[derive(Clone, Copy, Debug)]
enum QueryPlacement {
    /// Anywhere in the field grown by 5 m on each side (often outside the field).
    Anywhere(f64, f64),
    /// Exactly at the centre of a disk (index modulo the number of disks).
    AtCentre(usize),
    /// Exactly on the circle of a disk, at the given angle.
    OnCircle(usize, f64),
}

fn placement() -> impl Strategy<Value = QueryPlacement> {
    prop_oneof![
        3 => (0.0..1.0f64, 0.0..1.0f64).prop_map(|(x, y)| QueryPlacement::Anywhere(x, y)),
        1 => any::<usize>().prop_map(QueryPlacement::AtCentre),
        1 => (any::<usize>(), 0.0..std::f64::consts::TAU)
            .prop_map(|(i, a)| QueryPlacement::OnCircle(i, a)),
    ]
}

/// A degenerate configuration added to the random disks.
#[derive(Clone, Copy, Debug)]
enum Degeneracy {
    /// Nothing added.
    None,
    /// A disk sharing the first disk's centre.
    Concentric,
    /// A disk (angle, radius) externally tangent to the first disk.
    Tangent(f64, f64),
    /// The first disk moved to touch the left edge.
    TouchingEdge,
}

fn degeneracy() -> impl Strategy<Value = Degeneracy> {
    prop_oneof![
        2 => Just(Degeneracy::None),
        1 => Just(Degeneracy::Concentric),
        1 => (0.0..std::f64::consts::TAU, 0.2..4.0f64)
            .prop_map(|(a, r)| Degeneracy::Tangent(a, r)),
        1 => Just(Degeneracy::TouchingEdge),
    ]
}

prop_compose! {
    fn scene()(
        width_m in 4.0..40.0f64,
        height_m in 4.0..40.0f64,
        unit_disks in prop::collection::vec((-0.1..1.1f64, -0.1..1.1f64, 0.2..4.0f64), 0..25),
        degeneracy in degeneracy(),
        placement in placement(),
        sample_seed in any::<u64>(),
    ) -> Scene {
        let mut disks: Vec<Disk> = unit_disks
            .iter()
            .map(|&(x, y, r)| Disk::new(x * width_m, y * height_m, r))
            .collect();
        if let Some(&first) = disks.first() {
            match degeneracy {
                Degeneracy::None => {}
                Degeneracy::Concentric => {
                    disks.push(Disk { radius_m: 0.5 * first.radius_m + 0.3, ..first });
                }
                Degeneracy::Tangent(angle_rad, radius_m) => {
                    let centre = first.centre
                        + (first.radius_m + radius_m) * Vector::new(angle_rad.cos(), angle_rad.sin());
                    disks.push(Disk { centre, radius_m });
                }
                Degeneracy::TouchingEdge => {
                    disks[0].centre.x = first.radius_m;
                }
            }
        }
        let query = match placement {
            QueryPlacement::Anywhere(x, y) => {
                Point::new(-5.0 + x * (width_m + 10.0), -5.0 + y * (height_m + 10.0))
            }
            QueryPlacement::AtCentre(i) if !disks.is_empty() => disks[i % disks.len()].centre,
            QueryPlacement::OnCircle(i, a) if !disks.is_empty() => {
                disks[i % disks.len()].boundary_point(a)
            }
            _ => Point::new(0.5 * width_m, 0.5 * height_m),
        };
        Scene { field: Field::new(width_m, height_m), disks, query, sample_seed }
    }
}

/// Exactly free, by brute force over every disk.
fn is_free_brute_force(scene: &Scene, p: &Point) -> bool {
    scene.field.contains(p, 0.0)
        && scene
            .disks
            .iter()
            .all(|d| (p - d.centre).norm() >= d.radius_m)
}

/// Feasible to the tolerance, by brute force over every disk.
fn is_feasible_brute_force(scene: &Scene, p: &Point) -> bool {
    scene.field.contains(p, TOLERANCE_M)
        && scene
            .disks
            .iter()
            .all(|d| (p - d.centre).norm() >= d.radius_m - TOLERANCE_M)
}

/// Points to compare the result with: uniform points over the field, the corners, and a
/// fine polar grid around the query out to `radius_m`.
fn sample_points(scene: &Scene, radius_m: f64) -> Vec<Point> {
    let mut rng = ChaCha8Rng::seed_from_u64(scene.sample_seed);
    let mut points: Vec<Point> = scene.field.corners().to_vec();
    for _ in 0..3000 {
        points.push(Point::new(
            rng.random::<f64>() * scene.field.width_m,
            rng.random::<f64>() * scene.field.height_m,
        ));
    }
    let (rings, spokes) = (60, 360);
    for i in 1..=rings {
        let r = radius_m * f64::from(i) / f64::from(rings);
        for k in 0..spokes {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(spokes);
            points.push(scene.query + r * Vector::new(a.cos(), a.sin()));
        }
    }
    points
}

fn with_space<T>(scene: &Scene, run: impl FnOnce(&FreeSpace) -> T) -> T {
    let grid = DiskGrid::new(scene.disks.clone());
    let layers = [&grid];
    run(&FreeSpace::new(scene.field, &layers))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn best_point_is_feasible_and_no_sampled_free_point_is_nearer(scene in scene()) {
        let result = with_space(&scene, |space| nearest_free_point(space, &scene.query));
        match result {
            Ok(p) => {
                prop_assert!(is_feasible_brute_force(&scene, &p), "{p:?} is not free");
                let best_m = (p - scene.query).norm();
                for s in sample_points(&scene, best_m) {
                    prop_assert!(
                        !is_free_brute_force(&scene, &s) || (s - scene.query).norm() >= best_m - TOLERANCE_M,
                        "free sample {s:?} at {} beats {p:?} at {best_m}",
                        (s - scene.query).norm()
                    );
                }
            }
            Err(BestPointError::NoFreePoint) => {
                let diagonal_m = scene.field.width_m.hypot(scene.field.height_m);
                for s in sample_points(&scene, diagonal_m) {
                    prop_assert!(!is_free_brute_force(&scene, &s), "{s:?} is free");
                }
            }
        }
    }

    #[test]
    fn splitting_the_disks_into_layers_changes_nothing(scene in scene()) {
        let one_layer = with_space(&scene, |space| nearest_free_point(space, &scene.query));
        let layer_of = |parity: usize| {
            let disks = scene.disks.iter().enumerate().filter(|(i, _)| i % 2 == parity);
            DiskGrid::new(disks.map(|(_, d)| *d).collect())
        };
        let (even, odd) = (layer_of(0), layer_of(1));
        let layers = [&even, &odd];
        let two_layers = nearest_free_point(&FreeSpace::new(scene.field, &layers), &scene.query);
        match (one_layer, two_layers) {
            (Ok(a), Ok(b)) => prop_assert!(
                ((a - scene.query).norm() - (b - scene.query).norm()).abs() <= TOLERANCE_M
            ),
            (a, b) => prop_assert_eq!(a, b),
        }
    }

    #[test]
    fn reachable_best_point_respects_the_closure_and_the_agent_position(
        scene in scene(),
        line_point in (0.0..1.0f64, 0.0..1.0f64),
        line_angle_rad in 0.0..std::f64::consts::TAU,
    ) {
        let anchor = Point::new(line_point.0 * scene.field.width_m, line_point.1 * scene.field.height_m);
        let normal = Vector::new(line_angle_rad.cos(), line_angle_rad.sin());
        let accepts = |p: &Point| (p - anchor).dot(&normal) >= 0.0;
        let diagonal_m = scene.field.width_m.hypot(scene.field.height_m);
        let Some(from) = sample_points(&scene, diagonal_m)
            .into_iter()
            .find(|p| is_free_brute_force(&scene, p) && accepts(p))
        else {
            return Ok(());
        };
        let from_m = (from - scene.query).norm();
        with_space(&scene, |space| {
            let mut asked = Vec::new();
            let reached = nearest_reachable_free_point(space, &scene.query, &from, |p| {
                asked.push(*p);
                accepts(p)
            });
            let p = reached.map_err(|e| TestCaseError::fail(format!("from is free, yet {e}")))?;
            prop_assert!(p == from || accepts(&p), "{p:?} was refused by the closure");
            prop_assert!(is_feasible_brute_force(&scene, &p), "{p:?} is not free");
            prop_assert!((p - scene.query).norm() <= from_m);
            // The closure is asked about free points nearer than `from`, nearest first,
            // each once.
            for (k, a) in asked.iter().enumerate() {
                prop_assert!(is_feasible_brute_force(&scene, a), "asked about {a:?}");
                prop_assert!((a - scene.query).norm() < from_m);
                prop_assert!(!asked[..k].contains(a), "asked twice about {a:?}");
                if k > 0 {
                    prop_assert!((a - scene.query).norm() >= (asked[k - 1] - scene.query).norm());
                }
            }

            // Accepting everything gives the best point whenever it is nearer than `from`.
            let reached = nearest_reachable_free_point(space, &scene.query, &from, |_| true)
                .map_err(|e| TestCaseError::fail(format!("from is free, yet {e}")))?;
            let best = nearest_free_point(space, &scene.query)
                .map_err(|e| TestCaseError::fail(format!("from is free, yet {e}")))?;
            let best_m = (best - scene.query).norm();
            if best_m < from_m {
                prop_assert_eq!(reached, best);
            } else {
                prop_assert_eq!(reached, from);
            }
            Ok(())
        })?;
    }
}
