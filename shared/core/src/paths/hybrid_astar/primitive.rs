//! Motion primitives: pieces of constant curvature, their exact geometry, and the dense
//! poses along a chain of them.

use std::f64::consts::{FRAC_PI_2, TAU};

use super::settings::HybridAStarSettings;
use crate::geometry::{Point, Pose, distance_point_segment, wrap_angle_rad};

/// A piece of constant curvature: from `start`, drive `length_m` (negative = backwards)
/// with signed curvature `curvature_per_m` (positive turns left when driving forwards).
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece {
    pub(super) start: Pose,
    pub(super) curvature_per_m: f64,
    pub(super) length_m: f64,
}

impl Piece {
    /// The pose after `s_m` of signed arc length (same sign convention as `length_m`).
    pub(super) fn pose_at(&self, s_m: f64) -> Pose {
        let Pose {
            x_m,
            y_m,
            heading_rad: h,
        } = self.start;
        let k = self.curvature_per_m;
        if k == 0.0 {
            Pose::new(x_m + s_m * h.cos(), y_m + s_m * h.sin(), h)
        } else {
            let h1 = h + k * s_m;
            Pose::new(
                x_m + (h1.sin() - h.sin()) / k,
                y_m - (h1.cos() - h.cos()) / k,
                wrap_angle_rad(h1),
            )
        }
    }

    pub(super) fn end(&self) -> Pose {
        self.pose_at(self.length_m)
    }

    /// Centre of the turning circle, the angle of the start point seen from it, and the
    /// signed angle swept (only for arcs).
    fn circle(&self) -> (Point, f64, f64) {
        let k = self.curvature_per_m;
        let h = self.start.heading_rad;
        let centre = Point::new(self.start.x_m - h.sin() / k, self.start.y_m + h.cos() / k);
        let phi0 = (self.start.y_m - centre.y).atan2(self.start.x_m - centre.x);
        (centre, phi0, k * self.length_m)
    }

    /// Whether the angle `angle_rad` (seen from the circle's centre) lies on the arc.
    fn sweeps(phi0: f64, sweep: f64, angle_rad: f64) -> bool {
        if sweep.abs() >= TAU {
            return true;
        }
        let rel = ((angle_rad - phi0) * sweep.signum()).rem_euclid(TAU);
        rel <= sweep.abs()
    }

    /// Axis-aligned bounding box of the piece.
    pub(super) fn bounding_box(&self) -> (Point, Point) {
        let a = self.start.position();
        let b = self.end().position();
        let mut min = Point::new(a.x.min(b.x), a.y.min(b.y));
        let mut max = Point::new(a.x.max(b.x), a.y.max(b.y));
        if self.curvature_per_m != 0.0 {
            let (centre, phi0, sweep) = self.circle();
            let r = 1.0 / self.curvature_per_m.abs();
            for (i, extreme) in [
                (0, centre.x + r),
                (1, centre.y + r),
                (2, centre.x - r),
                (3, centre.y - r),
            ] {
                if Self::sweeps(phi0, sweep, i as f64 * FRAC_PI_2) {
                    match i {
                        0 => max.x = max.x.max(extreme),
                        1 => max.y = max.y.max(extreme),
                        2 => min.x = min.x.min(extreme),
                        _ => min.y = min.y.min(extreme),
                    }
                }
            }
        }
        (min, max)
    }

    /// Smallest distance from `p` to the piece (exact).
    pub(super) fn distance_m(&self, p: &Point) -> f64 {
        let a = self.start.position();
        let b = self.end().position();
        if self.curvature_per_m == 0.0 {
            return distance_point_segment(p, &a, &b);
        }
        let (centre, phi0, sweep) = self.circle();
        let r = 1.0 / self.curvature_per_m.abs();
        let d = p - centre;
        let dn = d.norm();
        if dn == 0.0 {
            return r;
        }
        if Self::sweeps(phi0, sweep, d.y.atan2(d.x)) {
            (dn - r).abs()
        } else {
            (p - a).norm().min((p - b).norm())
        }
    }

    /// Number of chords the piece is drawn with at `spacing_m`.
    pub(super) fn chords(&self, spacing_m: f64) -> usize {
        if self.curvature_per_m == 0.0 {
            1
        } else {
            ((self.length_m.abs() / spacing_m).ceil() as usize).max(1)
        }
    }
}

/// The dense path through `pieces` (each with its exact end pose): `start`, poses at most
/// `spacing_m` apart, and `goal` exactly in place of the last end pose.
pub(super) fn dense_path(
    start: &Pose,
    goal: &Pose,
    pieces: impl Iterator<Item = (Piece, Pose)>,
    spacing_m: f64,
) -> Vec<Pose> {
    let mut path = vec![*start];
    for (piece, end) in pieces {
        let n = ((piece.length_m.abs() / spacing_m).ceil() as usize).max(1);
        for i in 1..n {
            path.push(piece.pose_at(piece.length_m * i as f64 / n as f64));
        }
        path.push(end);
    }
    if path.len() > 1 {
        let last = path.len() - 1;
        path[last] = *goal;
    } else {
        path.push(*goal);
    }
    path
}

/// A motion primitive of the search: drive `length_m` (negative = backwards) with signed
/// curvature `curvature_per_m`, at a cost of `cost_m` (the length with its penalties).
#[derive(Clone, Copy, Debug)]
pub(super) struct Primitive {
    pub(super) curvature_per_m: f64,
    pub(super) length_m: f64,
    pub(super) cost_m: f64,
}

impl Primitive {
    /// The primitives a node is expanded with: straight, full left and full right, each
    /// [`HybridAStarSettings::primitive_length_m`] long, forwards and (when reverse is
    /// allowed) backwards, turns and reverse penalised.
    pub(super) fn set(settings: &HybridAStarSettings) -> Vec<Self> {
        let length_m = settings.primitive_length_m();
        let k = 1.0 / settings.turning_radius_m;
        let mut primitives = Vec::new();
        let directions: &[f64] = if settings.allow_reverse {
            &[1.0, -1.0]
        } else {
            &[1.0]
        };
        for &direction in directions {
            for curvature_per_m in [0.0, k, -k] {
                let mut cost_m = length_m;
                if curvature_per_m != 0.0 {
                    cost_m *= settings.turn_penalty;
                }
                if direction < 0.0 {
                    cost_m *= settings.reverse_penalty;
                }
                primitives.push(Primitive {
                    curvature_per_m,
                    length_m: direction * length_m,
                    cost_m,
                });
            }
        }
        primitives
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    #[test]
    fn arc_distance_and_bounding_box_are_exact() {
        // Quarter circle of radius 2 centred at the origin, from (2, 0) heading north.
        let piece = Piece {
            start: Pose::new(2.0, 0.0, FRAC_PI_2),
            curvature_per_m: 0.5,
            length_m: PI,
        };
        let end = piece.end();
        assert!((end.x_m).abs() < 1e-12 && (end.y_m - 2.0).abs() < 1e-12);
        assert!((piece.distance_m(&Point::new(3.0, 3.0)) - (18f64.sqrt() - 2.0)).abs() < 1e-12);
        assert!((piece.distance_m(&Point::new(0.0, 0.0)) - 2.0).abs() < 1e-12);
        // Beyond the arc's end: nearest is the endpoint (0, 2).
        assert!((piece.distance_m(&Point::new(-1.0, 1.0)) - 2f64.sqrt()).abs() < 1e-12);
        let (min, max) = piece.bounding_box();
        assert!((min.x).abs() < 1e-12 && (min.y).abs() < 1e-12);
        assert!((max.x - 2.0).abs() < 1e-12 && (max.y - 2.0).abs() < 1e-12);
        // Driven backwards: the arc below, from (2, 0) to (0, -2).
        let back = Piece {
            length_m: -PI,
            ..piece
        };
        let end = back.end();
        assert!((end.x_m).abs() < 1e-12 && (end.y_m + 2.0).abs() < 1e-12);
        let (min, _) = back.bounding_box();
        assert!((min.y + 2.0).abs() < 1e-12);
    }
}
