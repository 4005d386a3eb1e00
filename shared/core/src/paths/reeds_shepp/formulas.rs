//! The nine closed-form formulas of the Reeds-Shepp paper (section 8), each solving one
//! base word (starting with `L+`) for a goal `(x, y, phi)` in the start's frame, turning
//! radius 1. Names (t, u, v, xi, eta, ...) follow the paper, as OMPL does.
//!
//! Each formula also takes the cost its word must stay below to be of any use (the
//! family's search bound) and gives up as soon as a part of that cost it has computed
//! (the middle length `u`) reaches it, before the arc tangents of the rest: the search
//! would refuse such a word anyway, so the shortest word found is the same.

use std::f64::consts::{PI, TAU};

/// Acceptance tolerance of the formulas for "non-negative" and "non-positive" lengths
/// (OMPL's `ZERO`): a tiny wrong-signed length from rounding still counts.
const ZERO: f64 = 10.0 * f64::EPSILON;

/// The three free lengths `(t, u, v)` of a base word, in units of the turning radius.
pub(super) type Lengths = (f64, f64, f64);

/// A goal `(x, y, phi)` in the start's frame, with the sine and cosine of `phi` (computed
/// once for all the formulas and symmetries: both are exact under `phi -> -phi`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Goal {
    /// Ahead of the start, in turning radii.
    pub x: f64,
    /// To the start's left, in turning radii.
    pub y: f64,
    /// The heading change, radians.
    pub phi: f64,
    /// `phi.sin()`.
    pub sin_phi: f64,
    /// `phi.cos()`.
    pub cos_phi: f64,
}

impl Goal {
    /// The goal `(x, y, phi)`.
    pub fn new(x: f64, y: f64, phi: f64) -> Self {
        let (sin_phi, cos_phi) = phi.sin_cos();
        Self {
            x,
            y,
            phi,
            sin_phi,
            cos_phi,
        }
    }

    /// The goal as seen from the end of a word read backwards (for `CC|C` and
    /// `C S C|C`).
    pub fn backwards(&self) -> Self {
        Self {
            x: self.x * self.cos_phi + self.y * self.sin_phi,
            y: self.x * self.sin_phi - self.y * self.cos_phi,
            ..*self
        }
    }
}

/// A closed-form solution for one base word: from the goal and the family's cost bound
/// to the word's free lengths, or `None` when the word cannot reach the goal or its
/// middle alone (`|u|`, counted twice for `CCCC`) is no shorter than the bound (a word
/// returned may still cost more than the bound: the search filters it).
pub(super) type Formula = fn(&Goal, f64) -> Option<Lengths>;

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

/// The distance of `(x, y)` from the origin (its angle, `y.atan2(x)`, is computed only
/// where a formula needs it).
fn norm(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
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
pub(super) fn lp_sp_lp(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x - g.sin_phi;
    let eta = g.y - 1.0 + g.cos_phi;
    let u = norm(xi, eta);
    if u >= bound {
        return None;
    }
    let t = eta.atan2(xi);
    if t >= -ZERO {
        let v = mod2pi(g.phi - t);
        if v >= -ZERO {
            return Some((t, u, v));
        }
    }
    None
}

/// Formula 8.2, `L+ S+ R+`.
pub(super) fn lp_sp_rp(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x + g.sin_phi;
    let eta = g.y - 1.0 - g.cos_phi;
    let u1 = norm(xi, eta);
    let u1_sq = u1 * u1;
    if u1_sq >= 4.0 {
        let u = (u1_sq - 4.0).sqrt();
        if u >= bound {
            return None;
        }
        let theta = 2.0_f64.atan2(u);
        let t = mod2pi(eta.atan2(xi) + theta);
        let v = mod2pi(t - g.phi);
        return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
    }
    None
}

/// Formulas 8.3/8.4 (with the paper's typo corrected), `L+ R- L`.
pub(super) fn lp_rm_l(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x - g.sin_phi;
    let eta = g.y - 1.0 + g.cos_phi;
    let u1 = norm(xi, eta);
    if u1 <= 4.0 {
        let u = -2.0 * (0.25 * u1).asin();
        if u.abs() >= bound {
            return None;
        }
        let t = mod2pi(eta.atan2(xi) + 0.5 * u + PI);
        let v = mod2pi(g.phi - t + u);
        return (t >= -ZERO && u <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.7, `L+ R+u L-u R-`.
pub(super) fn lp_rup_lum_rm(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x + g.sin_phi;
    let eta = g.y - 1.0 - g.cos_phi;
    let rho = 0.25 * (2.0 + (xi * xi + eta * eta).sqrt());
    if rho <= 1.0 {
        let u = rho.acos();
        if 2.0 * u.abs() >= bound {
            return None;
        }
        let (t, v) = tau_omega(u, -u, xi, eta, g.phi);
        return (t >= -ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.8, `L+ R-u L-u R+`.
pub(super) fn lp_rum_lum_rp(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x + g.sin_phi;
    let eta = g.y - 1.0 - g.cos_phi;
    let rho = (20.0 - xi * xi - eta * eta) / 16.0;
    if (0.0..=1.0).contains(&rho) {
        let u = -rho.acos();
        if u >= -0.5 * PI {
            if 2.0 * u.abs() >= bound {
                return None;
            }
            let (t, v) = tau_omega(u, u, xi, eta, g.phi);
            return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
        }
    }
    None
}

/// Formula 8.9, `L+ R-(pi/2) S- L-`.
pub(super) fn lp_rm_sm_lm(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x - g.sin_phi;
    let eta = g.y - 1.0 + g.cos_phi;
    let rho = norm(xi, eta);
    if rho >= 2.0 {
        let r = (rho * rho - 4.0).sqrt();
        let u = 2.0 - r;
        if u.abs() >= bound {
            return None;
        }
        let t = mod2pi(eta.atan2(xi) + r.atan2(-2.0));
        let v = mod2pi(g.phi - 0.5 * PI - t);
        return (t >= -ZERO && u <= ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.10, `L+ R-(pi/2) S- R-`.
pub(super) fn lp_rm_sm_rm(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x + g.sin_phi;
    let eta = g.y - 1.0 - g.cos_phi;
    let rho = norm(-eta, xi);
    if rho >= 2.0 {
        let u = 2.0 - rho;
        if u.abs() >= bound {
            return None;
        }
        let t = xi.atan2(-eta);
        let v = mod2pi(t + 0.5 * PI - g.phi);
        return (t >= -ZERO && u <= ZERO && v <= ZERO).then_some((t, u, v));
    }
    None
}

/// Formula 8.11 (with the paper's typo corrected), `L+ R-(pi/2) S- L-(pi/2) R+`.
pub(super) fn lp_rm_s_lm_rp(g: &Goal, bound: f64) -> Option<Lengths> {
    let xi = g.x + g.sin_phi;
    let eta = g.y - 1.0 - g.cos_phi;
    let rho = norm(xi, eta);
    if rho >= 2.0 {
        let u = 4.0 - (rho * rho - 4.0).sqrt();
        if u <= ZERO {
            if u.abs() >= bound {
                return None;
            }
            let t = mod2pi(((4.0 - u) * xi - 2.0 * eta).atan2(-2.0 * xi + (u - 4.0) * eta));
            let v = mod2pi(t - g.phi);
            return (t >= -ZERO && v >= -ZERO).then_some((t, u, v));
        }
    }
    None
}
