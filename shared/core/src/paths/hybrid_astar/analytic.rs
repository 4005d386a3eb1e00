//! The analytic expansion: the obstacle-free shortest curve (Reeds-Shepp, or Dubins when
//! forward only) straight to the goal, kept when it is collision free.

use super::collision::Checker;
use super::primitive::Piece;
use super::settings::HybridAStarSettings;
use crate::geometry::{Pose, wrap_angle_rad};
use crate::paths::curve::{CurvePath, Steer};
use crate::paths::dubins;
use crate::paths::reeds_shepp;

/// The curve path (Reeds-Shepp, or Dubins when forward only) from `from` to `goal` as
/// pieces, if it is free and ends at the goal.
pub(super) fn analytic_expansion(
    checker: &mut Checker,
    settings: &HybridAStarSettings,
    from: &Pose,
    goal: &Pose,
) -> Option<Vec<Piece>> {
    let rho = settings.turning_radius_m;
    let curve: CurvePath = if settings.allow_reverse {
        reeds_shepp::shortest_path(from, goal, rho)
    } else {
        dubins::shortest_path(from, goal, rho)
    };
    let mut pieces = Vec::with_capacity(curve.segments.len());
    let mut pose = *from;
    for segment in &curve.segments {
        if !segment.length_m.is_finite() {
            return None;
        }
        if segment.length_m == 0.0 {
            continue;
        }
        let curvature_per_m = match segment.steer {
            Steer::Left => 1.0 / curve.turning_radius_m,
            Steer::Straight => 0.0,
            Steer::Right => -1.0 / curve.turning_radius_m,
        };
        let piece = Piece {
            start: pose,
            curvature_per_m,
            length_m: segment.length_m,
        };
        if !checker.piece_free(&piece) {
            return None;
        }
        pose = piece.end();
        pieces.push(piece);
    }
    // Guard against a curve path that does not end at the goal.
    let gap_m = (pose.position() - goal.position()).norm();
    let gap_rad = wrap_angle_rad(pose.heading_rad - goal.heading_rad).abs();
    (gap_m <= 1e-7 && gap_rad <= 1e-7).then_some(pieces)
}
