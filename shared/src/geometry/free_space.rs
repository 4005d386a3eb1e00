//! The free space a point agent moves in.

use std::ops::ControlFlow;

use super::{Disk, DiskGrid, Field, Point, Vector};

/// The free space a point agent moves in: the field minus the union of one or more
/// indexed disk layers (static obstacles, other agents), every disk already inflated.
///
/// A point is *free* when it lies in the field and at distance `>= radius` from every
/// disk centre (the boundary is free: touching is allowed, overlapping is not).
#[derive(Clone, Copy, Debug)]
pub struct FreeSpace<'a> {
    /// The playing field.
    pub field: Field,
    /// The blocking disks, in layers (for example static obstacles and other agents).
    pub layers: &'a [&'a DiskGrid],
}

impl<'a> FreeSpace<'a> {
    /// Free space in `field` outside every disk of `layers`.
    pub fn new(field: Field, layers: &'a [&'a DiskGrid]) -> Self {
        Self { field, layers }
    }

    /// Largest disk radius over all layers.
    pub fn max_radius_m(&self) -> f64 {
        self.layers
            .iter()
            .map(|g| g.max_radius_m())
            .fold(0.0, f64::max)
    }

    /// Visit every disk of every layer whose box meets `[min, max]`; the index passed is
    /// `(layer, index in layer)`.
    pub fn visit_box<B>(
        &self,
        min: &Point,
        max: &Point,
        mut visit: impl FnMut((usize, usize), &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        for (layer, grid) in self.layers.iter().enumerate() {
            grid.visit_box(min, max, |i, d| visit((layer, i), d))?;
        }
        ControlFlow::Continue(())
    }

    /// Visit every disk of every layer that may come within `reach_m` of `p`.
    pub fn visit_near<B>(
        &self,
        p: &Point,
        reach_m: f64,
        visit: impl FnMut((usize, usize), &Disk) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        let d = Vector::new(reach_m, reach_m);
        self.visit_box(&(p - d), &(p + d), visit)
    }

    /// Smallest signed distance from `p` to any disk boundary (negative inside a disk),
    /// looking only at disks within `reach_m`; `f64::INFINITY` if none is that close.
    pub fn clearance_m(&self, p: &Point, reach_m: f64) -> f64 {
        let mut best = f64::INFINITY;
        let _ = self.visit_near(p, reach_m, |_, d| {
            best = best.min(d.signed_distance_m(p));
            ControlFlow::<()>::Continue(())
        });
        best
    }

    /// Whether `p` is free, allowing it to sit up to `tolerance_m` inside a disk or
    /// outside the field.
    pub fn is_free(&self, p: &Point, tolerance_m: f64) -> bool {
        if !self.field.contains(p, tolerance_m) {
            return false;
        }
        self.visit_near(p, 0.0, |_, d| {
            if d.signed_distance_m(p) < -tolerance_m {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .is_continue()
    }

    /// Whether the whole segment `a`-`b` is free, with the same tolerance as
    /// [`FreeSpace::is_free`].
    pub fn is_segment_free(&self, a: &Point, b: &Point, tolerance_m: f64) -> bool {
        if !self.field.contains(a, tolerance_m) || !self.field.contains(b, tolerance_m) {
            return false;
        }
        let min = Point::new(a.x.min(b.x), a.y.min(b.y));
        let max = Point::new(a.x.max(b.x), a.y.max(b.y));
        self.visit_box(&min, &max, |_, d| {
            if d.signed_distance_to_segment_m(a, b) < -tolerance_m {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .is_continue()
    }
}
