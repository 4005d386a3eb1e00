//! Evenly spaced poses along a planned path, and its length.

use crate::geometry::{Pose, wrap_angle_rad};

/// Poses every `step_m` of arc length along `path` (read as the polyline through its
/// poses): the first is `path[0]`, the last is the last pose of `path` exactly, the last
/// step may be shorter. Positions are interpolated linearly, headings along the shorter
/// way round. A `step_m` that is not positive and finite returns `path` unchanged.
pub fn resample(path: &[Pose], step_m: f64) -> Vec<Pose> {
    let (Some(first), Some(last)) = (path.first(), path.last()) else {
        return Vec::new();
    };
    if !(step_m.is_finite() && step_m > 0.0) || path.len() == 1 {
        return path.to_vec();
    }
    let total_m = path_length_m(path);
    let mut out = vec![*first];
    // Arc length of the next pose to emit, and of the start of the current segment.
    let mut k = 1usize;
    let mut travelled_m = 0.0;
    for pair in path.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let length_m = (b.position() - a.position()).norm();
        if length_m == 0.0 {
            continue;
        }
        loop {
            let target_m = k as f64 * step_m;
            // Stop before the end: the last pose is always `last` itself.
            if target_m > travelled_m + length_m || target_m >= total_m - 1e-9 {
                break;
            }
            let t = ((target_m - travelled_m) / length_m).clamp(0.0, 1.0);
            let dh = wrap_angle_rad(b.heading_rad - a.heading_rad);
            out.push(Pose::new(
                a.x_m + t * (b.x_m - a.x_m),
                a.y_m + t * (b.y_m - a.y_m),
                wrap_angle_rad(a.heading_rad + t * dh),
            ));
            k += 1;
        }
        travelled_m += length_m;
    }
    out.push(*last);
    out
}

/// Length of the polyline through the poses of `path`, in metres.
pub fn path_length_m(path: &[Pose]) -> f64 {
    path.windows(2)
        .map(|w| (w[1].position() - w[0].position()).norm())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resample_keeps_endpoints_and_spacing() {
        let path: Vec<Pose> = (0..=10).map(|i| Pose::new(i as f64, 0.0, 0.0)).collect();
        let out = resample(&path, 3.0);
        let xs: Vec<f64> = out.iter().map(|p| p.x_m).collect();
        assert_eq!(xs, vec![0.0, 3.0, 6.0, 9.0, 10.0]);
        let out = resample(&path, 2.5);
        let xs: Vec<f64> = out.iter().map(|p| p.x_m).collect();
        assert_eq!(xs, vec![0.0, 2.5, 5.0, 7.5, 10.0]);
    }
}
