//! Exact collision checks of points and primitives against the inflated obstacles and the
//! inset field.

use std::ops::ControlFlow;

use super::primitive::Piece;
use super::settings::HybridAStarSettings;
use crate::geometry::{
    Disk, DiskGrid, Field, InflatedPolygon, Point, Polygon, PolygonLayer, distance_point_segment,
};

/// Exact collision checks against the obstacles inflated by the clearance and the field
/// inset by it.
pub(super) struct Checker {
    pub(super) grid: DiskGrid,
    pub(super) min: Point,
    pub(super) max: Point,
    spacing_m: f64,
    candidates: Vec<Disk>,
    /// Polygon obstacles grown by the clearance, indexed (a map gives thousands).
    polygons: PolygonLayer,
}

impl Checker {
    pub(super) fn new(field: &Field, obstacles: &[Disk], settings: &HybridAStarSettings) -> Self {
        let c = settings.clearance_m;
        Self {
            grid: DiskGrid::new(obstacles.iter().map(|d| d.inflated(c)).collect()),
            min: Point::new(c, c),
            max: Point::new(field.width_m - c, field.height_m - c),
            spacing_m: settings.sample_spacing_m,
            candidates: Vec::new(),
            polygons: PolygonLayer::default(),
        }
    }

    /// The same checks, also against `polygons` grown by the clearance.
    pub(super) fn with_polygons(
        mut self,
        polygons: &[Polygon],
        settings: &HybridAStarSettings,
    ) -> Self {
        self.polygons = PolygonLayer::new(
            polygons
                .iter()
                .map(|p| InflatedPolygon::from_polygon(p.clone(), settings.clearance_m))
                .collect(),
        );
        self
    }

    /// Whether the segment `a`-`b` keeps `margin_m` beyond every grown polygon.
    fn segment_clear_of_polygons(&self, a: &Point, b: &Point, margin_m: f64) -> bool {
        let (min, max) = (
            Point::new(a.x.min(b.x) - margin_m, a.y.min(b.y) - margin_m),
            Point::new(a.x.max(b.x) + margin_m, a.y.max(b.y) + margin_m),
        );
        self.polygons
            .visit_box(&min, &max, |_, p| {
                if p.signed_distance_to_segment_m(a, b) >= margin_m {
                    ControlFlow::Continue(())
                } else {
                    ControlFlow::Break(())
                }
            })
            .is_continue()
    }

    pub(super) fn in_field(&self, p: &Point) -> bool {
        p.x >= self.min.x && p.y >= self.min.y && p.x <= self.max.x && p.y <= self.max.y
    }

    pub(super) fn point_free(&self, p: &Point) -> bool {
        self.in_field(p)
            && self.segment_clear_of_polygons(p, p, 0.0)
            && self
                .grid
                .visit_near(p, 0.0, |_, d| {
                    if (p - d.centre).norm() < d.radius_m {
                        ControlFlow::Break(())
                    } else {
                        ControlFlow::Continue(())
                    }
                })
                .is_continue()
    }

    /// Whether the piece and every chord it is drawn with stay clear of the polygons: a
    /// straight piece exactly; an arc through its chords, each kept clear by the most the
    /// arc bulges from it (its sagitta), so the arc is clear too.
    fn piece_clear_of_polygons(&self, piece: &Piece) -> bool {
        if piece.curvature_per_m == 0.0 {
            return self.segment_clear_of_polygons(
                &piece.start.position(),
                &piece.end().position(),
                0.0,
            );
        }
        let n = piece.chords(self.spacing_m);
        let radius_m = 1.0 / piece.curvature_per_m.abs();
        let half_angle_rad = 0.5 * piece.length_m.abs() / n as f64 / radius_m;
        let sagitta_m = radius_m * (1.0 - half_angle_rad.min(std::f64::consts::PI).cos());
        chords(piece, n).all(|(a, b)| self.segment_clear_of_polygons(&a, &b, sagitta_m))
    }

    /// Whether the piece and every chord it is drawn with are free.
    pub(super) fn piece_free(&mut self, piece: &Piece) -> bool {
        let (min, max) = piece.bounding_box();
        if !(self.in_field(&min) && self.in_field(&max)) {
            return false;
        }
        if !self.polygons.is_empty() && !self.piece_clear_of_polygons(piece) {
            return false;
        }
        self.candidates.clear();
        let candidates = &mut self.candidates;
        let _ = self.grid.visit_box(&min, &max, |_, d| {
            candidates.push(*d);
            ControlFlow::<()>::Continue(())
        });
        if self.candidates.is_empty() {
            return true;
        }
        if self
            .candidates
            .iter()
            .any(|d| piece.distance_m(&d.centre) < d.radius_m)
        {
            return false;
        }
        if piece.curvature_per_m == 0.0 {
            return true;
        }
        // The chords of the returned polyline cut inside the arc: check them too.
        let n = piece.chords(self.spacing_m);
        chords(piece, n).all(|(a, b)| {
            !self
                .candidates
                .iter()
                .any(|d| distance_point_segment(&d.centre, &a, &b) < d.radius_m)
        })
    }
}

/// The `n` chords `piece` is drawn with, each `(start, end)`, end to end from its start
/// pose to its end pose.
fn chords(piece: &Piece, n: usize) -> impl Iterator<Item = (Point, Point)> + '_ {
    let at = move |i: usize| {
        if i == n {
            piece.end().position()
        } else {
            piece
                .pose_at(piece.length_m * i as f64 / n as f64)
                .position()
        }
    };
    let mut a = piece.start.position();
    (1..=n).map(move |i| {
        let b = at(i);
        let chord = (a, b);
        a = b;
        chord
    })
}
