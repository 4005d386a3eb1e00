//! Curvature-bounded paths between poses: a sequence of arcs of one turning radius and
//! straight lines, each driven forwards or in reverse.
//!
//! [`CurvePath`] is what both shortest-path solvers return: `reeds_shepp` (forwards and
//! reverse) and `dubins` (forwards only). This module knows how to follow, measure and
//! sample such a path and nothing of how one is found: both solvers import it, it imports
//! neither, and neither solver imports the other.

use crate::geometry::{Pose, wrap_angle_rad};

/// Which way a segment of a curvature-bounded path steers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Steer {
    /// Counter-clockwise arc of the turning radius (curvature `+1/rho` when driving forwards).
    Left,
    /// Straight line (curvature 0).
    Straight,
    /// Clockwise arc of the turning radius (curvature `-1/rho` when driving forwards).
    Right,
}

impl Steer {
    /// The sign of the path curvature: `+1` for [`Steer::Left`], `0` for [`Steer::Straight`],
    /// `-1` for [`Steer::Right`].
    pub fn curvature_sign(self) -> f64 {
        match self {
            Steer::Left => 1.0,
            Steer::Straight => 0.0,
            Steer::Right => -1.0,
        }
    }

    /// The mirror image: `Left` and `Right` swapped.
    pub fn mirrored(self) -> Self {
        match self {
            Steer::Left => Steer::Right,
            Steer::Straight => Steer::Straight,
            Steer::Right => Steer::Left,
        }
    }
}

/// One segment of a [`CurvePath`]: an arc of the path's turning radius or a straight line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Which way the segment steers.
    pub steer: Steer,
    /// Signed arc length, in metres: positive drives forwards, negative drives in reverse.
    pub length_m: f64,
}

impl Segment {
    /// Whether the segment is driven in reverse.
    pub fn is_reverse(&self) -> bool {
        self.length_m < 0.0
    }

    /// Signed curvature of the segment's geometric curve, in 1/metres, for a path of turning
    /// radius `turning_radius_m`: `+1/rho` for a left arc, `-1/rho` for a right arc, 0 for a
    /// straight line. (The heading changes by `curvature * length_m` along the segment.)
    pub fn curvature_per_m(&self, turning_radius_m: f64) -> f64 {
        self.steer.curvature_sign() / turning_radius_m
    }
}

/// A curvature-bounded path: a sequence of arcs of radius `turning_radius_m` and straight
/// lines, followed from a start pose. Reeds-Shepp paths may contain reverse segments, Dubins
/// paths never do.
///
/// The path is stored relative to its start: the same path can be followed from any pose.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvePath {
    /// The segments in driving order. Zero-length (and negligible, below `1e-12` turning
    /// radii) segments are omitted, so a path between identical poses has none.
    pub segments: Vec<Segment>,
    /// Radius of every arc segment, in metres.
    pub turning_radius_m: f64,
}

impl CurvePath {
    /// The "path" between poses that no path joins (or given non-finite numbers): one
    /// straight segment of NaN length, so every length computed from it is NaN.
    pub fn unreachable(turning_radius_m: f64) -> Self {
        Self {
            segments: vec![Segment {
                steer: Steer::Straight,
                length_m: f64::NAN,
            }],
            turning_radius_m,
        }
    }

    /// Total length travelled, in metres: the sum of the absolute segment lengths.
    pub fn length_m(&self) -> f64 {
        self.segments.iter().map(|s| s.length_m.abs()).sum()
    }

    /// Whether any segment is driven in reverse.
    pub fn has_reverse(&self) -> bool {
        self.segments.iter().any(Segment::is_reverse)
    }

    /// The pose after travelling arc length `s_m` along the path from `start`.
    ///
    /// `s_m` counts distance travelled, forwards or in reverse, and is clamped to
    /// `[0, length_m()]` (NaN counts as 0). The heading is wrapped into `(-pi, pi]`.
    pub fn pose_at(&self, start: &Pose, s_m: f64) -> Pose {
        let mut remaining_m = if s_m.is_nan() { 0.0 } else { s_m.max(0.0) };
        let mut pose = *start;
        for segment in &self.segments {
            let segment_m = segment.length_m.abs();
            if remaining_m < segment_m {
                let partial_m = remaining_m.copysign(segment.length_m);
                pose = advance(&pose, segment.steer, partial_m, self.turning_radius_m);
                return wrapped(pose);
            }
            pose = advance(
                &pose,
                segment.steer,
                segment.length_m,
                self.turning_radius_m,
            );
            remaining_m -= segment_m;
        }
        wrapped(pose)
    }

    /// The pose reached at the end of the path followed from `start`, heading wrapped into
    /// `(-pi, pi]`.
    pub fn end_pose(&self, start: &Pose) -> Pose {
        let pose = self.segments.iter().fold(*start, |pose, segment| {
            advance(
                &pose,
                segment.steer,
                segment.length_m,
                self.turning_radius_m,
            )
        });
        wrapped(pose)
    }

    /// Poses along the path followed from `start`: `start` itself, then one pose every
    /// `spacing_m` of arc length, then the exact [`end_pose`](Self::end_pose). Consecutive
    /// poses are at most `spacing_m` apart, both in arc length and in straight-line distance.
    /// The result always holds at least two poses (start and end, equal for an empty path).
    /// Headings are wrapped into `(-pi, pi]`.
    ///
    /// # Panics
    ///
    /// If `spacing_m` is not strictly positive (or is NaN).
    pub fn sample(&self, start: &Pose, spacing_m: f64) -> Vec<Pose> {
        assert!(
            spacing_m > 0.0,
            "sampling spacing must be > 0 m, got {spacing_m}"
        );
        let total_m = self.length_m();
        // Number of spacing steps needed to cover the path; interior samples are 1..count.
        let count = (total_m / spacing_m).ceil() as usize;
        let mut poses = Vec::with_capacity(count.max(1) + 1);
        poses.push(wrapped(*start));

        // Walk the segments once: `segment_start` is the pose at arc length `segment_start_m`,
        // where segment `index` begins.
        let mut index = 0;
        let mut segment_start = *start;
        let mut segment_start_m = 0.0;
        for step in 1..count {
            let s_m = step as f64 * spacing_m;
            while index < self.segments.len()
                && s_m > segment_start_m + self.segments[index].length_m.abs()
            {
                let segment = &self.segments[index];
                segment_start = advance(
                    &segment_start,
                    segment.steer,
                    segment.length_m,
                    self.turning_radius_m,
                );
                segment_start_m += segment.length_m.abs();
                index += 1;
            }
            let Some(segment) = self.segments.get(index) else {
                break;
            };
            let partial_m = (s_m - segment_start_m).copysign(segment.length_m);
            poses.push(wrapped(advance(
                &segment_start,
                segment.steer,
                partial_m,
                self.turning_radius_m,
            )));
        }
        poses.push(self.end_pose(start));
        poses
    }
}

/// The pose after driving `length_m` (signed: negative is reverse) along one segment from
/// `pose`, integrated in closed form. The heading is left unwrapped.
///
/// An arc of signed length `l` and curvature `k = sign / rho` turns the heading by `k l` and
/// moves along the chord of length `2 rho sin(l / (2 rho))` in the direction of the mean
/// heading `theta + k l / 2`; this half-angle form stays accurate for short arcs.
fn advance(pose: &Pose, steer: Steer, length_m: f64, turning_radius_m: f64) -> Pose {
    let heading_rad = pose.heading_rad;
    match steer {
        Steer::Straight => Pose::new(
            pose.x_m + length_m * heading_rad.cos(),
            pose.y_m + length_m * heading_rad.sin(),
            heading_rad,
        ),
        Steer::Left | Steer::Right => {
            let turn_rad = steer.curvature_sign() * length_m / turning_radius_m;
            let chord_m = 2.0 * turning_radius_m * (0.5 * length_m / turning_radius_m).sin();
            let mean_heading_rad = heading_rad + 0.5 * turn_rad;
            Pose::new(
                pose.x_m + chord_m * mean_heading_rad.cos(),
                pose.y_m + chord_m * mean_heading_rad.sin(),
                heading_rad + turn_rad,
            )
        }
    }
}

/// Segments shorter than this, in units of the turning radius, are rounding noise of the
/// closed-form solutions (a true zero computed as `1e-16`, possibly with the wrong sign) and
/// are left out of paths, so that e.g. driving straight ahead is one segment and has no
/// spurious reverse part. Dropping them moves the end pose by at most this much.
const NEGLIGIBLE_LENGTH: f64 = 1e-12;

/// The segment of `steer` and `normalized_length` (in units of the turning radius) scaled to
/// metres, or `None` when its length is negligible.
pub(crate) fn scaled_segment(
    steer: Steer,
    normalized_length: f64,
    turning_radius_m: f64,
) -> Option<Segment> {
    (normalized_length.abs() > NEGLIGIBLE_LENGTH).then_some(Segment {
        steer,
        length_m: normalized_length * turning_radius_m,
    })
}

/// `pose` with its heading wrapped into `(-pi, pi]`.
fn wrapped(pose: Pose) -> Pose {
    Pose::new(pose.x_m, pose.y_m, wrap_angle_rad(pose.heading_rad))
}

/// Asserts the turning radius contract shared by every public entry point of the
/// Reeds-Shepp and Dubins solvers.
///
/// # Panics
///
/// If `turning_radius_m` is not finite and strictly positive.
pub(crate) fn check_turning_radius(turning_radius_m: f64) {
    assert!(
        turning_radius_m > 0.0 && turning_radius_m.is_finite(),
        "turning radius must be finite and > 0 m, got {turning_radius_m}"
    );
}

/// Test tolerance of the curve controllers, in metres and radians.
#[cfg(test)]
pub(crate) const TOLERANCE: f64 = 1e-9;

/// Test helper of the curve controllers: `actual` and `expected` agree to [`TOLERANCE`] in
/// position and heading (headings compared modulo a full turn).
#[cfg(test)]
pub(crate) fn assert_pose_close(actual: &Pose, expected: &Pose) {
    assert!(
        (actual.x_m - expected.x_m).abs() < TOLERANCE
            && (actual.y_m - expected.y_m).abs() < TOLERANCE
            && wrap_angle_rad(actual.heading_rad - expected.heading_rad).abs() < TOLERANCE,
        "{actual:?} != {expected:?}"
    );
}
