//! The quick proof of unreachability: closed chains of overlapping disks (the outside of
//! the field counting as one more obstacle) that the segment from start to goal crosses an
//! odd number of times.

use std::ops::ControlFlow;

use super::parity_union_find::ParityUnionFind;
use crate::geometry::{Disk, Field, Point};

/// Overlap (or wall crossing) a barrier needs before the unreachability test trusts it, in
/// metres: far above [`FREE_TOLERANCE_M`](super::FREE_TOLERANCE_M), so no path within
/// tolerance slips through.
const BARRIER_MARGIN_M: f64 = 1e-6;

/// `(b - a) x (c - a)`.
fn orient(a: &Point, b: &Point, c: &Point) -> f64 {
    let (u, v) = (b - a, c - a);
    u.x * v.y - u.y * v.x
}

/// Whether segment `p`-`q` crosses segment `s`-`t`, counting a vertex on the line `s`-`t`
/// as lying on its non-positive side (so crossings of a closed polygon have the right
/// parity). Assumes `s` and `t` are not on `p`-`q`.
pub(super) fn crosses(s: &Point, t: &Point, p: &Point, q: &Point) -> bool {
    let (dp, dq) = (orient(s, t, p), orient(s, t, q));
    if (dp > 0.0) == (dq > 0.0) {
        return false;
    }
    let x = p + (dp / (dp - dq)) * (q - p);
    let st = t - s;
    let mu = (x - s).dot(&st) / st.norm_squared();
    mu > 0.0 && mu < 1.0
}

/// Every barrier edge among `disks`: a pair of disks `i < j` that overlap by more than
/// [`BARRIER_MARGIN_M`], with the segment between their centres, and a disk crossing a field
/// edge by more than that margin, joined to vertex `disks.len()` (the outside of the field)
/// by the segment from its centre to a point beyond that edge. Every such segment lies in
/// the obstacle (the union of the disks and the outside of the field) with a depth far above
/// [`FREE_TOLERANCE_M`](super::FREE_TOLERANCE_M). Stops when `visit` breaks.
pub(super) fn visit_barrier_edges(
    field: &Field,
    disks: &[Disk],
    mut visit: impl FnMut(usize, usize, &Point, &Point) -> ControlFlow<()>,
) -> ControlFlow<()> {
    let outside = disks.len();
    let r_max = disks.iter().map(|d| d.radius_m).fold(0.0, f64::max);
    let mut order: Vec<usize> = (0..disks.len()).collect();
    order.sort_by(|&a, &b| disks[a].centre.x.total_cmp(&disks[b].centre.x));
    for (pos, &i) in order.iter().enumerate() {
        let di = &disks[i];
        for &j in &order[pos + 1..] {
            let dj = &disks[j];
            if dj.centre.x - di.centre.x >= di.radius_m + r_max {
                break;
            }
            let reach = di.radius_m + dj.radius_m - BARRIER_MARGIN_M;
            if (dj.centre - di.centre).norm() < reach {
                visit(i, j, &di.centre, &dj.centre)?;
            }
        }
        let (c, r, m) = (di.centre, di.radius_m, BARRIER_MARGIN_M);
        let (w, h) = (field.width_m, field.height_m);
        let exits = [
            (c.x < r - m, Point::new(c.x.min(0.0) - 1.0, c.y)),
            (c.x > w - r + m, Point::new(c.x.max(w) + 1.0, c.y)),
            (c.y < r - m, Point::new(c.x, c.y.min(0.0) - 1.0)),
            (c.y > h - r + m, Point::new(c.x, c.y.max(h) + 1.0)),
        ];
        for (crosses_edge, beyond) in exits {
            if crosses_edge {
                visit(i, outside, &c, &beyond)?;
            }
        }
    }
    ControlFlow::Continue(())
}

/// Whether some closed chain of overlapping `disks` (the outside of the field counting as
/// one more obstacle) separates `s` from `t`.
///
/// The segment between the centres of two disks that overlap lies inside their union, and
/// so does the segment from the centre of a disk crossing a field edge to a point beyond
/// that edge; joining such segments gives closed curves made of obstacle
/// ([`visit_barrier_edges`]). A curve crossed an odd number of times by the segment `s`-`t`
/// separates them, which shows as a cycle of odd parity in a union-find with parities.
/// Overlaps must exceed [`BARRIER_MARGIN_M`], so `s` and `t` (free within
/// [`FREE_TOLERANCE_M`](super::FREE_TOLERANCE_M)) never lie on these curves and no path
/// within tolerance passes. Sound, not complete: `false` means "not shown".
pub(super) fn separated(field: &Field, s: &Point, t: &Point, disks: &[Disk]) -> bool {
    let mut uf = ParityUnionFind::new(disks.len() + 1);
    visit_barrier_edges(field, disks, |i, j, p, q| {
        if uf.union(i, j, crosses(s, t, p, q)) {
            ControlFlow::Continue(())
        } else {
            ControlFlow::Break(())
        }
    })
    .is_break()
}

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use super::*;

    #[test]
    fn barrier_test_finds_closed_rings_only() {
        let field = Field::new(20.0, 20.0);
        let ring: Vec<Disk> = (0..12)
            .map(|i| {
                let a = i as f64 * TAU / 12.0;
                Disk::new(10.0 + 3.0 * a.cos(), 10.0 + 3.0 * a.sin(), 1.0)
            })
            .collect();
        let (inside, outside) = (Point::new(10.0, 10.0), Point::new(1.0, 2.0));
        assert!(separated(&field, &inside, &outside, &ring));
        assert!(separated(&field, &outside, &inside, &ring));
        assert!(!separated(&field, &outside, &Point::new(18.0, 3.0), &ring));
        assert!(!separated(&field, &inside, &Point::new(10.5, 9.0), &ring));
        let open: Vec<Disk> = ring.iter().copied().skip(1).collect();
        assert!(!separated(&field, &inside, &outside, &open));
        // A barrier closed through the outside of the field (two wall crossings).
        let corner = vec![
            Disk::new(0.0, 3.0, 1.0),
            Disk::new(1.5, 1.5, 1.3),
            Disk::new(3.0, 0.0, 1.0),
        ];
        assert!(separated(
            &field,
            &Point::new(0.3, 0.3),
            &Point::new(8.0, 8.0),
            &corner
        ));
        assert!(!separated(
            &field,
            &Point::new(8.0, 0.3),
            &Point::new(8.0, 8.0),
            &corner
        ));
        // A wall across the whole field.
        let wall: Vec<Disk> = (0..12)
            .map(|i| Disk::new(10.0, 1.8 * i as f64, 1.0))
            .collect();
        assert!(separated(
            &field,
            &Point::new(2.0, 5.0),
            &Point::new(18.0, 15.0),
            &wall
        ));
        assert!(!separated(
            &field,
            &Point::new(2.0, 5.0),
            &Point::new(2.0, 15.0),
            &wall
        ));
    }

    #[test]
    fn barrier_parity_handles_vertices_on_the_segment_line() {
        // s on the horizontal line through a disk centre crossing the left wall.
        let field = Field::new(10.0, 10.0);
        let disks = vec![Disk::new(0.5, 5.0, 1.0)];
        assert!(!separated(
            &field,
            &Point::new(3.0, 5.0),
            &Point::new(3.0, 8.0),
            &disks
        ));
        assert!(!separated(
            &field,
            &Point::new(3.0, 5.0),
            &Point::new(8.0, 5.0),
            &disks
        ));
    }
}
