//! Plane geometry for drawing: circles as polygons, arrows, and clipping to the view, so
//! that nothing spills out of a map's plotting area (plotters does not clip).

use std::f64::consts::TAU;

/// A point in metres, as plotters takes it.
pub type Xy = (f64, f64);

/// An axis-aligned view rectangle, in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Smallest x.
    pub x0: f64,
    /// Largest x.
    pub x1: f64,
    /// Smallest y.
    pub y0: f64,
    /// Largest y.
    pub y1: f64,
}

impl View {
    /// Whether the disk of radius `r` at `c` may show in the view.
    pub fn touches_disk(&self, c: Xy, r: f64) -> bool {
        c.0 + r >= self.x0 && c.0 - r <= self.x1 && c.1 + r >= self.y0 && c.1 - r <= self.y1
    }

    /// Whether `p` is inside the view (edges included).
    pub fn contains(&self, p: Xy) -> bool {
        p.0 >= self.x0 && p.0 <= self.x1 && p.1 >= self.y0 && p.1 <= self.y1
    }

    /// The parts of the polyline `points` inside the view.
    pub fn clip_polyline(&self, points: &[Xy]) -> Vec<Vec<Xy>> {
        let mut pieces: Vec<Vec<Xy>> = Vec::new();
        let mut current: Vec<Xy> = Vec::new();
        if points.len() == 1 && self.contains(points[0]) {
            return vec![points.to_vec()];
        }
        for w in points.windows(2) {
            match self.clip_segment(w[0], w[1]) {
                Some((a, b)) => {
                    if current.last() != Some(&a) {
                        if current.len() > 1 {
                            pieces.push(std::mem::take(&mut current));
                        }
                        current.clear();
                        current.push(a);
                    }
                    current.push(b);
                }
                None => {
                    if current.len() > 1 {
                        pieces.push(std::mem::take(&mut current));
                    }
                    current.clear();
                }
            }
        }
        if current.len() > 1 {
            pieces.push(current);
        }
        pieces
    }

    /// The part of segment `a`-`b` inside the view (Liang-Barsky).
    fn clip_segment(&self, a: Xy, b: Xy) -> Option<(Xy, Xy)> {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-dx, a.0 - self.x0),
            (dx, self.x1 - a.0),
            (-dy, a.1 - self.y0),
            (dy, self.y1 - a.1),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
            } else {
                let t = q / p;
                if p < 0.0 {
                    t0 = t0.max(t);
                } else {
                    t1 = t1.min(t);
                }
            }
        }
        if t0 > t1 {
            return None;
        }
        let at = |t: f64| (a.0 + t * dx, a.1 + t * dy);
        Some((at(t0), at(t1)))
    }

    /// The polygon `points` cut to the view (Sutherland-Hodgman); empty when outside.
    pub fn clip_polygon(&self, points: &[Xy]) -> Vec<Xy> {
        let mut poly = points.to_vec();
        // Each edge: inside test and intersection with the boundary line.
        type Inside = fn(&View, Xy) -> bool;
        type Cut = fn(&View, Xy, Xy) -> Xy;
        let edges: [(Inside, Cut); 4] = [
            (|v, p| p.0 >= v.x0, |v, a, b| lerp_x(a, b, v.x0)),
            (|v, p| p.0 <= v.x1, |v, a, b| lerp_x(a, b, v.x1)),
            (|v, p| p.1 >= v.y0, |v, a, b| lerp_y(a, b, v.y0)),
            (|v, p| p.1 <= v.y1, |v, a, b| lerp_y(a, b, v.y1)),
        ];
        for (inside, cut) in edges {
            if poly.is_empty() {
                break;
            }
            let input = std::mem::take(&mut poly);
            let mut prev = input[input.len() - 1];
            for &p in &input {
                match (inside(self, p), inside(self, prev)) {
                    (true, true) => poly.push(p),
                    (true, false) => {
                        poly.push(cut(self, prev, p));
                        poly.push(p);
                    }
                    (false, true) => poly.push(cut(self, prev, p)),
                    (false, false) => {}
                }
                prev = p;
            }
        }
        poly
    }
}

fn lerp_x(a: Xy, b: Xy, x: f64) -> Xy {
    let t = (x - a.0) / (b.0 - a.0);
    (x, a.1 + t * (b.1 - a.1))
}

fn lerp_y(a: Xy, b: Xy, y: f64) -> Xy {
    let t = (y - a.1) / (b.1 - a.1);
    (a.0 + t * (b.0 - a.0), y)
}

/// The circle of radius `r` around `c` as a closed polygon, with vertices about 3 pixels
/// apart at `px_per_m` (at least 12, at most 128).
pub fn circle(c: Xy, r: f64, px_per_m: f64) -> Vec<Xy> {
    let n = ((TAU * r * px_per_m / 3.0).ceil() as usize).clamp(12, 128);
    (0..n)
        .map(|k| {
            let a = TAU * k as f64 / n as f64;
            (c.0 + r * a.cos(), c.1 + r * a.sin())
        })
        .collect()
}

/// The same polygon closed (first vertex repeated at the end), for outlines.
pub fn closed<T: Copy>(mut poly: Vec<T>) -> Vec<T> {
    if let Some(&first) = poly.first() {
        poly.push(first);
    }
    poly
}

/// An arrow from `tail` along `heading_rad`, `len` long with a head `head` long: the
/// shaft (two points) and the head (a triangle).
pub fn arrow(tail: Xy, heading_rad: f64, len: f64, head: f64) -> ([Xy; 2], [Xy; 3]) {
    let (s, c) = heading_rad.sin_cos();
    let tip = (tail.0 + len * c, tail.1 + len * s);
    let base = (tip.0 - head * c, tip.1 - head * s);
    let half = head * 0.45;
    let left = (base.0 - half * s, base.1 + half * c);
    let right = (base.0 + half * s, base.1 - half * c);
    ([tail, base], [tip, left, right])
}

/// Hatching of the disk of radius `r` around `c`: chords at 45 degrees, `spacing` apart
/// (at most 64 of them), each as its two ends.
pub fn hatch(c: Xy, r: f64, spacing: f64) -> Vec<[Xy; 2]> {
    if !(r > 0.0 && spacing > 0.0) {
        return Vec::new();
    }
    let spacing = spacing.max(2.0 * r / 64.0);
    let (t, n) = (
        (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
        (
            -std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        ),
    );
    let k = (r / spacing).floor() as i64;
    (-k..=k)
        .filter_map(|i| {
            let d = i as f64 * spacing;
            let half = (r * r - d * d).sqrt();
            (half > 0.0).then(|| {
                let m = (c.0 + d * n.0, c.1 + d * n.1);
                [
                    (m.0 - half * t.0, m.1 - half * t.1),
                    (m.0 + half * t.0, m.1 + half * t.1),
                ]
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const V: View = View {
        x0: 0.0,
        x1: 10.0,
        y0: 0.0,
        y1: 10.0,
    };

    #[test]
    fn polyline_leaving_and_reentering_splits() {
        let pieces = V.clip_polyline(&[(5.0, 5.0), (15.0, 5.0), (15.0, 8.0), (5.0, 8.0)]);
        assert_eq!(
            pieces,
            vec![vec![(5.0, 5.0), (10.0, 5.0)], vec![(10.0, 8.0), (5.0, 8.0)]]
        );
        assert!(V.clip_polyline(&[(-5.0, -5.0), (-1.0, 20.0)]).is_empty());
    }

    #[test]
    fn polygon_is_cut_to_the_view() {
        let square = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)];
        let cut = V.clip_polygon(&square);
        assert!(cut.iter().all(|&p| V.contains(p)));
        assert!(cut.contains(&(5.0, 5.0)) && cut.contains(&(0.0, 0.0)));
        assert!(
            V.clip_polygon(&[(20.0, 20.0), (30.0, 20.0), (30.0, 30.0)])
                .is_empty()
        );
    }

    #[test]
    fn circle_and_arrow() {
        let c = circle((1.0, 2.0), 3.0, 10.0);
        assert!(c.len() >= 12);
        assert!(
            c.iter()
                .all(|p| ((p.0 - 1.0).hypot(p.1 - 2.0) - 3.0).abs() < 1e-12)
        );
        let (shaft, head) = arrow((0.0, 0.0), 0.0, 2.0, 0.5);
        assert_eq!(head[0], (2.0, 0.0));
        assert_eq!(shaft[1], (1.5, 0.0));
    }

    #[test]
    fn hatch_chords_end_on_the_circle() {
        let chords = hatch((1.0, 2.0), 3.0, 1.0);
        assert_eq!(
            chords.len(),
            5,
            "offsets -2 to 2 (±3 touch the circle only)"
        );
        for [a, b] in chords {
            for p in [a, b] {
                assert!(((p.0 - 1.0).hypot(p.1 - 2.0) - 3.0).abs() < 1e-9, "{p:?}");
            }
        }
        assert!(hatch((0.0, 0.0), 0.0, 1.0).is_empty());
    }
}
