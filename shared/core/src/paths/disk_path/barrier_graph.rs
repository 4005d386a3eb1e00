//! The barrier test of [`separated`](super::barrier::separated) prepared once for many
//! goals: the barrier edges around a start, reduced to what can close a curve.

use std::ops::ControlFlow;

use super::barrier::{crosses, visit_barrier_edges};
use super::tolerance::FREE_TOLERANCE_M;
use crate::geometry::{FreeSpace, Point, Vector};

/// One barrier edge: a segment through obstacle from vertex `u` to vertex `v`, with its
/// bounding box.
#[derive(Clone, Copy, Debug)]
struct BarrierEdge {
    u: u32,
    v: u32,
    p: Point,
    q: Point,
    min: Point,
    max: Point,
}

impl BarrierEdge {
    fn new(u: usize, v: usize, p: &Point, q: &Point) -> Self {
        Self {
            u: u as u32,
            v: v as u32,
            p: *p,
            q: *q,
            min: Point::new(p.x.min(q.x), p.y.min(q.y)),
            max: Point::new(p.x.max(q.x), p.y.max(q.y)),
        }
    }

    /// [`crosses`] `s`-`t`, with `[min, max]` the box of `s`-`t` grown by a slack far
    /// above rounding (an edge whose box misses it cannot cross).
    fn crosses(&self, s: &Point, t: &Point, min: &Point, max: &Point) -> bool {
        self.max.x >= min.x
            && self.min.x <= max.x
            && self.max.y >= min.y
            && self.min.y <= max.y
            && crosses(s, t, &self.p, &self.q)
    }
}

/// The barrier edges ([`visit_barrier_edges`]) of the disks that meet a ball around a start,
/// reduced to what can close a curve, for the test of
/// [`separated`](super::barrier::separated) against many goals.
///
/// A goal is separated from the start iff some cycle of the graph is crossed an odd number
/// of times by the segment between them. Only the 2-core of the graph (what is left after
/// repeatedly removing vertices of degree at most one) holds cycles, and the cycle space is
/// spanned by the fundamental cycles of a spanning forest: with `parity(v)` the parity of
/// the crossings along the forest path from its root to `v`, some cycle is odd iff some edge
/// off the forest has `parity(u) ^ parity(v) ^ crosses(edge)` set. One pass, no sorting.
#[derive(Debug)]
pub(super) struct BarrierGraph {
    /// Radius of the ball around the start: the graph holds every disk that meets it.
    pub(super) reach_m: f64,
    /// Forest edges, parent `u` to child `v`, each parent reached before its children.
    forest: Vec<BarrierEdge>,
    /// The other edges of the 2-core, each closing one fundamental cycle.
    chords: Vec<BarrierEdge>,
    /// Scratch: crossing parity of the forest path from the root to each vertex.
    parity: Vec<bool>,
}

impl BarrierGraph {
    pub(super) fn new(space: &FreeSpace, from: &Point, reach_m: f64) -> Self {
        let field = &space.field;
        let r_max = space.max_radius_m();
        let grow = Vector::new(reach_m + r_max, reach_m + r_max);
        let mut disks = Vec::new();
        let _ = space.visit_box(&(from - grow), &(from + grow), |_, d| {
            let usable = d.radius_m > 0.0 && d.radius_m.is_finite();
            if usable
                && (field.clamp(&d.centre) - d.centre).norm() <= d.radius_m
                && (d.centre - from).norm() <= reach_m + d.radius_m
            {
                disks.push(*d);
            }
            ControlFlow::<()>::Continue(())
        });
        let vertices = disks.len() + 1;
        let mut edges = Vec::new();
        let _ = visit_barrier_edges(field, &disks, |u, v, p, q| {
            edges.push(BarrierEdge::new(u, v, p, q));
            ControlFlow::Continue(())
        });

        // Adjacency (edge indices per vertex, in edge order).
        let mut degree = vec![0usize; vertices];
        for e in &edges {
            degree[e.u as usize] += 1;
            degree[e.v as usize] += 1;
        }
        let mut first = Vec::with_capacity(vertices + 1);
        let mut total = 0;
        for d in &degree {
            first.push(total);
            total += d;
        }
        first.push(total);
        let mut fill = first.clone();
        let mut incident = vec![0usize; total];
        for (k, e) in edges.iter().enumerate() {
            for w in [e.u as usize, e.v as usize] {
                incident[fill[w]] = k;
                fill[w] += 1;
            }
        }
        let other = |k: usize, w: usize| {
            let e = &edges[k];
            if e.u as usize == w {
                e.v as usize
            } else {
                e.u as usize
            }
        };

        // 2-core: peel vertices of degree <= 1.
        let mut removed = vec![false; vertices];
        let mut peel: Vec<usize> = (0..vertices).filter(|&w| degree[w] <= 1).collect();
        while let Some(w) = peel.pop() {
            if removed[w] {
                continue;
            }
            removed[w] = true;
            for &k in &incident[first[w]..first[w + 1]] {
                let x = other(k, w);
                if !removed[x] {
                    degree[x] -= 1;
                    if degree[x] <= 1 {
                        peel.push(x);
                    }
                }
            }
        }

        // Spanning forest of the 2-core, breadth first, roots in vertex order.
        let mut used = vec![false; edges.len()];
        let mut seen = removed.clone();
        let mut forest = Vec::new();
        let mut queue = std::collections::VecDeque::new();
        for root in 0..vertices {
            if seen[root] {
                continue;
            }
            seen[root] = true;
            queue.push_back(root);
            while let Some(w) = queue.pop_front() {
                for &k in &incident[first[w]..first[w + 1]] {
                    let x = other(k, w);
                    if seen[x] {
                        continue;
                    }
                    seen[x] = true;
                    used[k] = true;
                    let e = &edges[k];
                    forest.push(BarrierEdge {
                        u: w as u32,
                        v: x as u32,
                        ..*e
                    });
                    queue.push_back(x);
                }
            }
        }
        let chords = edges
            .iter()
            .zip(&used)
            .filter(|&(e, &in_forest)| {
                !in_forest && !removed[e.u as usize] && !removed[e.v as usize]
            })
            .map(|(e, _)| *e)
            .collect();
        Self {
            reach_m,
            forest,
            chords,
            parity: vec![false; vertices],
        }
    }

    /// Whether a cycle of the graph separates `s` from `t` (sound, as
    /// [`separated`](super::barrier::separated)).
    pub(super) fn separates(&mut self, s: &Point, t: &Point) -> bool {
        if self.chords.is_empty() {
            return false;
        }
        let slack_m = FREE_TOLERANCE_M * (1.0 + s.x.abs() + s.y.abs() + t.x.abs() + t.y.abs());
        let min = Point::new(s.x.min(t.x) - slack_m, s.y.min(t.y) - slack_m);
        let max = Point::new(s.x.max(t.x) + slack_m, s.y.max(t.y) + slack_m);
        // Roots keep `false`; every other vertex is set after its parent.
        for e in &self.forest {
            self.parity[e.v as usize] = self.parity[e.u as usize] ^ e.crosses(s, t, &min, &max);
        }
        let parity = &self.parity;
        self.chords
            .iter()
            .any(|e| parity[e.u as usize] ^ parity[e.v as usize] ^ e.crosses(s, t, &min, &max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Disk, DiskGrid};
    use crate::paths::disk_path::barrier::separated;
    use crate::paths::disk_path::tests::packed_block;

    #[test]
    fn barrier_graph_agrees_with_the_barrier_test() {
        let (field, mut disks) = packed_block();
        // An open pocket, and disks crossing the field edges (barriers through the outside).
        disks.remove(30);
        disks.push(Disk::new(0.2, 6.0, 0.8));
        disks.push(Disk::new(13.5, 11.5, 1.0));
        let grid = DiskGrid::new(disks.clone());
        let layers = [&grid];
        let space = FreeSpace::new(field, &layers);
        let s = Point::new(5.5, 4.5);
        let mut graph = BarrierGraph::new(&space, &s, 100.0);
        let (mut separated_count, mut free_count) = (0, 0);
        for i in 0..=56 {
            for j in 0..=48 {
                let t = Point::new(0.25 * i as f64, 0.25 * j as f64);
                if !space.is_free(&t, 0.0) {
                    continue;
                }
                free_count += 1;
                let expected = separated(&field, &s, &t, &disks);
                assert_eq!(graph.separates(&s, &t), expected, "{t:?}");
                separated_count += usize::from(expected);
            }
        }
        assert!(separated_count > 0 && separated_count < free_count);
    }
}
