//! Tests of the QP and the barrier controllers.

use super::*;

#[test]
fn degenerate_rows_are_ignored_or_infeasible() {
    let u = Vector::new(1.0, -2.0);
    let ok = [HalfPlane::new(Vector::zeros(), 0.0)];
    assert_eq!(solve_qp_2d(&u, &ok), Ok(u));
    let bad = [HalfPlane::new(Vector::zeros(), -1e-300)];
    assert_eq!(solve_qp_2d(&u, &bad), Err(QpError::Infeasible));
    let nan = [HalfPlane::new(Vector::new(f64::NAN, 1.0), 0.0)];
    assert_eq!(solve_qp_2d(&u, &nan), Err(QpError::NotFinite));
}

#[test]
fn parallel_rows_and_single_point_sets() {
    let u = Vector::new(3.0, 3.0);
    // 1 <= x <= 1 and y <= 0: the set is a half-line.
    let rows = [
        HalfPlane::new(Vector::new(1.0, 0.0), 1.0),
        HalfPlane::new(Vector::new(-2.0, 0.0), -2.0),
        HalfPlane::new(Vector::new(0.0, 5.0), 0.0),
    ];
    assert_eq!(solve_qp_2d(&u, &rows), Ok(Vector::new(1.0, 0.0)));
    let empty = [
        HalfPlane::new(Vector::new(1.0, 0.0), 1.0),
        HalfPlane::new(Vector::new(-1.0, 0.0), -1.5),
    ];
    assert_eq!(solve_qp_2d(&u, &empty), Err(QpError::Infeasible));
}
