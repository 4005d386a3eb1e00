//! The nine closed-form formulas of the Reeds-Shepp paper (section 8), each solving one
//! base word (starting with `L+`) for a goal `(x, y, phi)` in the start's frame, turning
//! radius 1. Names (t, u, v, xi, eta, ...) follow the paper, as OMPL does.

use std::f64::consts::{PI, TAU};

/// Acceptance tolerance of the formulas for "non-negative" and "non-positive" lengths
/// (OMPL's `ZERO`): a tiny wrong-signed length from rounding still counts.
const ZERO: f64 = 10.0 * f64::EPSILON;

/// The three free lengths `(t, u, v)` of a base word, in units of the turning radius.
pub(super) type Lengths = (f64, f64, f64);

/// A closed-form solution for one base word: from the goal `(x, y, phi)` to the word's free
/// lengths, or `None` when the word cannot reach the goal.
pub(super) type Formula = fn(f64, f64, f64) -> Option<Lengths>;

/// Wraps an angle into `[-pi, pi]` (OMPL's `mod2pi`).
fn mod2pi(angle: f64) -> f64 {
    let v = angle % TAU;
    if v < -PI {
        v + TAU
    } else if v > PI {
        v - TAU
    } else {
        v
    }
}

/// Polar coordinates `(r, theta)` of `(x, y)`.
fn polar(x: f64, y: f64) -> (f64, f64) {
    ((x * x + y * y).sqrt(), y.atan2(x))
}

/// The outer arc angles `(tau, omega)` of the CCCC words given the middle arcs `u`, `v`.
fn tau_omega(u: f64, v: f64, xi: f64, eta: f64, phi: f64) -> (f64, f64) {
    let delta = mod2pi(u - v);
    let a = u.sin() - delta.sin();
    let b = u.cos() - delta.cos() - 1.0;
    let t1 = (eta * a - xi * b).atan2(xi * a + eta * b);
    let t2 = 2.0 * (delta.cos() - v.cos() - u.cos()) + 3.0;
    let tau = if t2 < 0.0 {
        mod2pi(t1 + PI)
    } else {
        mod2pi(t1)
    };
    let omega = mod2pi(tau - u + v - phi);
    (tau, omega)
}

/// Formula 8.1, `L+ S+ L+`.
pub(super) fn lp_sp_lp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let (u, t) = polar(x - phi.sin(), y - 1.0 + phi.cos());
    if t >= -ZERO {
        let v = mod2pi(phi - t);
        if v >= -ZERO {
            return Some((t, u, v));
        }
    }
    None
}

/// Formula 8.2, `L+ S+ R+`.
pub(super) fn lp_sp_rp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let (u1, t1) = polar(x + phi.sin(), y - 1.0 - phi.cos());
    let u1_sq = u1 * u1;
    if u1_sq >= 4.0 {
        let u = (u1_sq - 4.0).sqrt();
        let theta = 2.0_f64.atan2(u);
        let t = mod2pi(t1 + theta);
        let v = mod2pi(t - phi);
        return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
    }
    None
}

/// Formulas 8.3/8.4 (with the paper's typo corrected), `L+ R- L`.
pub(super) fn lp_rm_l(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x - phi.sin();
    let eta = y - 1.0 + phi.cos();
    let (u1, theta) = polar(xi, eta);
    if u1 <= 4.0 {
        let u = -2.0 * (0.25 * u1).asin();
        let t = mod2pi(theta + 0.5 * u + PI);
        let v = mod2pi(phi - t + u);
        return (t >= -ZERO && u <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.7, `L+ R+u L-u R-`.
pub(super) fn lp_rup_lum_rm(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let rho = 0.25 * (2.0 + (xi * xi + eta * eta).sqrt());
    if rho <= 1.0 {
        let u = rho.acos();
        let (t, v) = tau_omega(u, -u, xi, eta, phi);
        return (t >= -ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.8, `L+ R-u L-u R+`.
pub(super) fn lp_rum_lum_rp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let rho = (20.0 - xi * xi - eta * eta) / 16.0;
    if (0.0..=1.0).contains(&rho) {
        let u = -rho.acos();
        if u >= -0.5 * PI {
            let (t, v) = tau_omega(u, u, xi, eta, phi);
            return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
        }
    }
    None
}

/// Formula 8.9, `L+ R-(pi/2) S- L-`.
pub(super) fn lp_rm_sm_lm(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x - phi.sin();
    let eta = y - 1.0 + phi.cos();
    let (rho, theta) = polar(xi, eta);
    if rho >= 2.0 {
        let r = (rho * rho - 4.0).sqrt();
        let u = 2.0 - r;
        let t = mod2pi(theta + r.atan2(-2.0));
        let v = mod2pi(phi - 0.5 * PI - t);
        return (t >= -ZERO && u <= ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.10, `L+ R-(pi/2) S- R-`.
pub(super) fn lp_rm_sm_rm(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let (rho, theta) = polar(-eta, xi);
    if rho >= 2.0 {
        let t = theta;
        let u = 2.0 - rho;
        let v = mod2pi(t + 0.5 * PI - phi);
        return (t >= -ZERO && u <= ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.11 (with the paper's typo corrected), `L+ R-(pi/2) S- L-(pi/2) R+`.
pub(super) fn lp_rm_s_lm_rp(x: f64, y: f64, phi: f64) -> Option<Lengths> {
    let xi = x + phi.sin();
    let eta = y - 1.0 - phi.cos();
    let (rho, _theta) = polar(xi, eta);
    if rho >= 2.0 {
        let u = 4.0 - (rho * rho - 4.0).sqrt();
        if u <= ZERO {
            let t = mod2pi(((4.0 - u) * xi - 2.0 * eta).atan2(-2.0 * xi + (u - 4.0) * eta));
            let v = mod2pi(t - phi);
            return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
        }
    }
    None
}
