//! Which arcs of a circle are free: the exact arc check of the tangent graph.
//!
//! The part of a circle that lies strictly inside another disk, or outside a field edge,
//! is an open angular interval (from the circle-circle or circle-line intersection
//! angles). The part inside a grown polygon is a union of open intervals between the
//! angles where the circle crosses the polygon's boundary pieces (its offset sides and
//! corner circles), each interval tested at its middle. An arc is free iff it enters
//! none of them.

use std::f64::consts::TAU;

use super::tolerance::FREE_TOLERANCE_M;
use crate::geometry::{
    Disk, Field, InflatedPolygon, Point, PolygonLayer, Vector, circle_circle_intersections,
    circle_line_intersections,
};

/// Non-negative remainder of `x` modulo a full turn, in `[0, 2 pi)`.
pub(super) fn turn_rem(x: f64) -> f64 {
    let r = x.rem_euclid(TAU);
    if r >= TAU { 0.0 } else { r }
}

/// Open angular intervals `(start, width)` of a circle that lie strictly inside other disks
/// or outside the field (beyond tolerance). A width of a full turn blocks the whole circle.
pub(super) fn blocked_intervals(
    k: usize,
    circles: &[Disk],
    polygons: Option<&PolygonLayer>,
    field: &Field,
) -> Vec<(f64, f64)> {
    let ck = circles[k].centre;
    let rk = circles[k].radius_m;
    let mut out = Vec::new();
    // The circle point at angle phi is blocked iff cos(phi - alpha) > c.
    let mut push = |alpha: f64, c: f64| {
        if c >= 1.0 || c.is_nan() {
            return;
        }
        if c <= -1.0 {
            out.push((0.0, TAU));
            return;
        }
        let half = c.acos();
        out.push((turn_rem(alpha - half), 2.0 * half));
    };
    for (j, dj) in circles.iter().enumerate() {
        if j == k {
            continue;
        }
        let reach = dj.radius_m - FREE_TOLERANCE_M;
        if reach <= 0.0 {
            continue;
        }
        let v = dj.centre - ck;
        let d = v.norm();
        if d >= rk + reach || d + reach <= rk {
            continue;
        }
        if d == 0.0 {
            // Concentric: reached here only when the circle is inside the larger disk.
            push(0.0, -1.0);
            continue;
        }
        // |ck + rk u(phi) - cj|^2 < reach^2  <=>  cos(phi - alpha) > (d^2 + rk^2 - reach^2) / (2 d rk).
        push(
            v.y.atan2(v.x),
            (d * d + rk * rk - reach * reach) / (2.0 * d * rk),
        );
    }
    // Field edges, as outward normal m and offset h (inside: m . p <= h); the circle point is
    // outside iff m . ck + rk cos(phi - alpha_m) > h + tol.
    let edges = [
        (Vector::new(-1.0, 0.0), 0.0),
        (Vector::new(1.0, 0.0), field.width_m),
        (Vector::new(0.0, -1.0), 0.0),
        (Vector::new(0.0, 1.0), field.height_m),
    ];
    for (m, h) in edges {
        push(
            m.y.atan2(m.x),
            (h + FREE_TOLERANCE_M - m.dot(&ck.coords)) / rk,
        );
    }
    let reach = Vector::new(rk, rk);
    if let Some(layer) = polygons {
        let _ = layer.visit_box(&(ck - reach), &(ck + reach), |_, polygon| {
            push_polygon_intervals(&circles[k], polygon, &mut out);
            std::ops::ControlFlow::<()>::Continue(())
        });
    }
    out
}

/// Push the open angular intervals of the circle of `disk` that lie inside `polygon`
/// beyond the tolerance (inside the polygon grown by its radius less the tolerance).
fn push_polygon_intervals(disk: &Disk, polygon: &InflatedPolygon, out: &mut Vec<(f64, f64)>) {
    let shrunk = polygon.inflated(-FREE_TOLERANCE_M.min(polygon.radius_m()));
    let (c, rho) = (disk.centre, disk.radius_m);
    let angle_of = |p: &Point| {
        let v = p - c;
        turn_rem(v.y.atan2(v.x))
    };
    let mut angles = Vec::new();
    for (a, b) in shrunk.offset_sides() {
        let along = b - a;
        if let Some(points) = circle_line_intersections(&c, rho, &a, &along) {
            for p in points {
                let t = (p - a).dot(&along) / along.norm_squared();
                if (0.0..=1.0).contains(&t) {
                    angles.push(angle_of(&p));
                }
            }
        }
    }
    for corner in shrunk.corner_disks() {
        if let Some(points) = circle_circle_intersections(&c, rho, &corner.centre, corner.radius_m)
        {
            angles.extend(points.iter().map(angle_of));
        }
    }
    angles.sort_unstable_by(f64::total_cmp);
    angles.dedup();
    let inside = |angle: f64| {
        let p = c + rho * Vector::new(angle.cos(), angle.sin());
        shrunk.signed_distance_m(&p) < 0.0
    };
    if angles.is_empty() {
        if inside(0.0) {
            out.push((0.0, TAU));
        }
        return;
    }
    for (i, &start) in angles.iter().enumerate() {
        let end = if i + 1 < angles.len() {
            angles[i + 1]
        } else {
            angles[0] + TAU
        };
        let width = end - start;
        if width > 0.0 && inside(start + 0.5 * width) {
            out.push((start, width));
        }
    }
}

/// How far (unsigned angle) one can travel around a circle from `angle_rad` in `sense`
/// without entering any blocked interval; a full turn when nothing blocks.
pub(super) fn free_extent_rad(intervals: &[(f64, f64)], angle_rad: f64, sense: i8) -> f64 {
    let mut extent = TAU;
    for &(start, width) in intervals {
        if width >= TAU {
            return 0.0;
        }
        let (inside_at, distance) = if sense > 0 {
            (turn_rem(angle_rad - start), turn_rem(start - angle_rad))
        } else {
            let end = start + width;
            (turn_rem(end - angle_rad), turn_rem(angle_rad - end))
        };
        if inside_at > 0.0 && inside_at < width {
            return 0.0;
        }
        extent = extent.min(distance);
    }
    extent
}
