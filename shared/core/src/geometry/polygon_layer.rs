//! Grown polygons with a box index ([`PolygonLayer`]): the polygon obstacles of a free
//! space, few drawn by hand or thousands cut from a map.

use std::ops::ControlFlow;

use super::{BoxIndex, InflatedPolygon, Point};

/// Polygons grown by the agent's radius, indexed by their bounding boxes so that a
/// question about one place looks only at the polygons near it.
///
/// ```
/// use std::ops::ControlFlow;
/// use shared::geometry::{InflatedPolygon, Point, PolygonLayer};
/// let square = |x: f64| {
///     let v = vec![Point::new(x, 0.0), Point::new(x + 1.0, 0.0), Point::new(x + 1.0, 1.0), Point::new(x, 1.0)];
///     InflatedPolygon::new(v, 0.5).unwrap()
/// };
/// let layer = PolygonLayer::new((0..100).map(|k| square(3.0 * k as f64)).collect());
/// let mut near = Vec::new();
/// let _ = layer.visit_box(&Point::new(7.0, 0.5), &Point::new(7.0, 0.5), |i, _| {
///     near.push(i);
///     ControlFlow::<()>::Continue(())
/// });
/// assert_eq!(near, [2]); // the square from 6 to 7 m, grown to 5.5..7.5 m
/// ```
#[derive(Clone, Debug, Default)]
pub struct PolygonLayer {
    polygons: Vec<InflatedPolygon>,
    index: BoxIndex,
}

impl PolygonLayer {
    /// The layer of `polygons`, indexed.
    pub fn new(polygons: Vec<InflatedPolygon>) -> Self {
        let boxes: Vec<(Point, Point)> =
            polygons.iter().map(InflatedPolygon::bounding_box).collect();
        Self {
            index: BoxIndex::new(&boxes),
            polygons,
        }
    }

    /// The polygons, in the order given.
    pub fn polygons(&self) -> &[InflatedPolygon] {
        &self.polygons
    }

    /// Whether it has no polygon.
    pub fn is_empty(&self) -> bool {
        self.polygons.is_empty()
    }

    /// Visit, once each, every polygon whose bounding box meets `[min, max]`, with its
    /// index; stops at the first `Break`.
    pub fn visit_box<B>(
        &self,
        min: &Point,
        max: &Point,
        mut visit: impl FnMut(usize, &InflatedPolygon) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        self.index.visit(min, max, |i| visit(i, &self.polygons[i]))
    }
}
