//! Cost of one CBF-QP turn: the exact 2-D QP alone (with the constraints of a realistic
//! turn) and a whole `plan_move`, as the obstacle field gets denser.
//!
//! Fields of 100 m x 100 m hold seeded random obstacles of radius 0.5 to 1.5 m; the agent
//! (radius 0.3 m, default settings: 5 m sensing radius) stands at random free points with
//! its slot 3 m away in a random direction, among 5 other agents nearby.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shared::control::cbf::{CbfController, solve_qp_2d};
use shared::control::formation::Slot;
use shared::control::vocabulary::{AgentSpec, Body, CbfSettings};
use shared::geometry::{Disk, Field, Point, Pose, Vector};

/// Queries per case, cycled through by the benchmark loop.
const QUERY_COUNT: usize = 256;
const AGENT_RADIUS_M: f64 = 0.3;

/// One turn's inputs: position, centre (= slot), other agents.
struct Query {
    me: Point,
    centre: Pose,
    others: Vec<Body>,
}

fn workload(count: usize, seed: u64) -> (CbfController, Vec<Query>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let field = Field::new(100.0, 100.0);
    let obstacles: Vec<Disk> = (0..count)
        .map(|_| {
            Disk::new(
                rng.random::<f64>() * 100.0,
                rng.random::<f64>() * 100.0,
                0.5 + rng.random::<f64>(),
            )
        })
        .collect();
    let spec = AgentSpec::new(Slot::new(0.0, 0.0), AGENT_RADIUS_M);
    let controller = CbfController::new(field, &obstacles, &spec, CbfSettings::default())
        .expect("default settings are valid");
    let free = |p: &Point, others: &[Body]| {
        field.signed_inset_m(p) >= AGENT_RADIUS_M
            && obstacles
                .iter()
                .all(|d| (p - d.centre).norm() >= d.radius_m + AGENT_RADIUS_M)
            && others
                .iter()
                .all(|o| (p - o.position).norm() >= o.radius_m + AGENT_RADIUS_M)
    };
    let mut queries = Vec::with_capacity(QUERY_COUNT);
    while queries.len() < QUERY_COUNT {
        let me = Point::new(
            5.0 + rng.random::<f64>() * 90.0,
            5.0 + rng.random::<f64>() * 90.0,
        );
        let others: Vec<Body> = (0..5)
            .map(|_| Body {
                position: me
                    + Vector::new(
                        rng.random::<f64>() * 8.0 - 4.0,
                        rng.random::<f64>() * 8.0 - 4.0,
                    ),
                radius_m: AGENT_RADIUS_M,
            })
            .collect();
        if !free(&me, &others) {
            continue;
        }
        let angle = rng.random::<f64>() * std::f64::consts::TAU;
        let slot = me + 3.0 * Vector::new(angle.cos(), angle.sin());
        queries.push(Query {
            me,
            centre: Pose::new(slot.x, slot.y, 0.0),
            others,
        });
    }
    (controller, queries)
}

fn bench_cbf(c: &mut Criterion) {
    let mut group = c.benchmark_group("cbf");
    for (seed, count) in [100usize, 500, 1500].into_iter().enumerate() {
        let (controller, queries) = workload(count, 0xcbf + seed as u64);
        let problems: Vec<(Vector, Vec<_>)> = queries
            .iter()
            .map(|q| {
                let slot = q.centre.position();
                let u_nom = (slot - q.me).cap_magnitude(1.0);
                (u_nom, controller.constraints(&q.me, &q.others))
            })
            .collect();
        let mut next = 0;
        group.bench_function(format!("solve_qp_2d/{count}_obstacles"), |b| {
            b.iter(|| {
                next = (next + 1) % problems.len();
                let (u_nom, rows) = &problems[next];
                black_box(solve_qp_2d(black_box(u_nom), black_box(rows)))
            })
        });
        let mut next = 0;
        group.bench_function(format!("plan_move/{count}_obstacles"), |b| {
            b.iter(|| {
                next = (next + 1) % queries.len();
                let q = &queries[next];
                black_box(controller.plan_move(&q.centre, black_box(&q.me), &q.others))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_cbf);
criterion_main!(benches);
