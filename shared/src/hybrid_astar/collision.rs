//! Exact collision checks of points and primitives against the inflated obstacles and the
//! inset field.

use std::ops::ControlFlow;

use super::primitive::Piece;
use super::settings::HybridAStarSettings;
use crate::geometry::{Disk, DiskGrid, Field, Point, distance_point_segment};

/// Exact collision checks against the obstacles inflated by the clearance and the field
/// inset by it.
pub(super) struct Checker {
    pub(super) grid: DiskGrid,
    pub(super) min: Point,
    pub(super) max: Point,
    spacing_m: f64,
    candidates: Vec<Disk>,
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
        }
    }

    pub(super) fn in_field(&self, p: &Point) -> bool {
        p.x >= self.min.x && p.y >= self.min.y && p.x <= self.max.x && p.y <= self.max.y
    }

    pub(super) fn point_free(&self, p: &Point) -> bool {
        self.in_field(p)
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

    /// Whether the piece and every chord it is drawn with are free.
    pub(super) fn piece_free(&mut self, piece: &Piece) -> bool {
        let (min, max) = piece.bounding_box();
        if !(self.in_field(&min) && self.in_field(&max)) {
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
        let mut a = piece.start.position();
        for i in 1..=n {
            let b = if i == n {
                piece.end().position()
            } else {
                piece
                    .pose_at(piece.length_m * i as f64 / n as f64)
                    .position()
            };
            if self
                .candidates
                .iter()
                .any(|d| distance_point_segment(&d.centre, &a, &b) < d.radius_m)
            {
                return false;
            }
            a = b;
        }
        true
    }
}
