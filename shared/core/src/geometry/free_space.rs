//! The free space a point agent moves in.

use std::ops::ControlFlow;

use super::{Disk, DiskGrid, Field, InflatedPolygon, Point, PolygonLayer, RegionGrid, Vector};

/// The free space a point agent moves in: the field minus the union of one or more
/// indexed disk layers (static obstacles, other agents) and of grown polygons, every
/// obstacle already inflated.
///
/// A point is *free* when it lies in the field, at distance `>= radius` from every disk
/// centre and at distance `>= radius` from every polygon (the boundary is free: touching
/// is allowed, overlapping is not).
#[derive(Clone, Copy, Debug)]
pub struct FreeSpace<'a> {
    /// The playing field.
    pub field: Field,
    /// The blocking disks, in layers (for example static obstacles and other agents).
    pub layers: &'a [&'a DiskGrid],
    /// The blocking polygons, already grown by the agent's radius, if any.
    pub polygons: Option<&'a PolygonLayer>,
    /// The regions a map's blocked cells close off from each other, for this agent's
    /// clearance, if the polygons come from a map: a quick proof that a goal is
    /// unreachable.
    pub regions: Option<&'a RegionGrid>,
}

impl<'a> FreeSpace<'a> {
    /// Free space in `field` outside every disk of `layers`.
    pub fn new(field: Field, layers: &'a [&'a DiskGrid]) -> Self {
        Self {
            field,
            layers,
            polygons: None,
            regions: None,
        }
    }

    /// The same space, also outside every grown polygon of `polygons`.
    pub fn with_polygons(self, polygons: &'a PolygonLayer) -> Self {
        Self {
            polygons: Some(polygons),
            ..self
        }
    }

    /// The same space, whose map closes off `regions` from each other.
    pub fn with_regions(self, regions: Option<&'a RegionGrid>) -> Self {
        Self { regions, ..self }
    }

    /// Whether `a` and `b` are surely in different components of the free space, by the
    /// map's regions (`false` says nothing).
    pub fn surely_apart(&self, a: &Point, b: &Point) -> bool {
        self.regions.is_some_and(|r| r.apart(a, b))
    }

    /// Largest disk or polygon radius over all layers.
    pub fn max_radius_m(&self) -> f64 {
        self.layers
            .iter()
            .map(|g| g.max_radius_m())
            .chain(
                self.polygons
                    .map_or(&[][..], PolygonLayer::polygons)
                    .iter()
                    .map(InflatedPolygon::radius_m),
            )
            .fold(0.0, f64::max)
    }

    /// Visit every grown polygon whose bounding box meets `[min, max]`, with its index.
    pub fn visit_polygons_box<B>(
        &self,
        min: &Point,
        max: &Point,
        visit: impl FnMut(usize, &InflatedPolygon) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        match self.polygons {
            Some(layer) => layer.visit_box(min, max, visit),
            None => ControlFlow::Continue(()),
        }
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

    /// Smallest signed distance from `p` to any obstacle boundary (negative inside an
    /// obstacle), looking only at obstacles within `reach_m`; `f64::INFINITY` if none is
    /// that close.
    pub fn clearance_m(&self, p: &Point, reach_m: f64) -> f64 {
        let mut best = f64::INFINITY;
        let _ = self.visit_near(p, reach_m, |_, d| {
            best = best.min(d.signed_distance_m(p));
            ControlFlow::<()>::Continue(())
        });
        let d = Vector::new(reach_m, reach_m);
        let _ = self.visit_polygons_box(&(p - d), &(p + d), |_, polygon| {
            best = best.min(polygon.signed_distance_m(p));
            ControlFlow::<()>::Continue(())
        });
        best
    }

    /// How deep `p` lies inside the obstacles: the largest depth below any one obstacle
    /// boundary, 0 when it is in none. No free point is nearer to `p` than this.
    pub fn depth_m(&self, p: &Point) -> f64 {
        let mut depth_m: f64 = 0.0;
        let _ = self.visit_near(p, 0.0, |_, disk| {
            depth_m = depth_m.max(-disk.signed_distance_m(p));
            ControlFlow::<()>::Continue(())
        });
        let _ = self.visit_polygons_box(p, p, |_, polygon| {
            depth_m = depth_m.max(-polygon.signed_distance_m(p));
            ControlFlow::<()>::Continue(())
        });
        depth_m
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
            && self
                .visit_polygons_box(p, p, |_, polygon| {
                    if polygon.signed_distance_m(p) < -tolerance_m {
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
            && self
                .visit_polygons_box(&min, &max, |_, polygon| {
                    // The box holds the grown polygon: a segment that misses it is clear.
                    if polygon.segment_meets_box(a, b)
                        && polygon.signed_distance_to_segment_m(a, b) < -tolerance_m
                    {
                        ControlFlow::Break(())
                    } else {
                        ControlFlow::Continue(())
                    }
                })
                .is_continue()
    }
}
