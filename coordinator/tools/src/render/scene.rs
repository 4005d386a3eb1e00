//! Drawing the world in metres: the map chart (equal scale, axes in metres), obstacles
//! with their safety margins, circles, polylines and arrows clipped to the view. The
//! header above every plot is in `header.rs`.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::{
    Cartesian2d, ChartBuilder, ChartContext, DrawingArea, PathElement, Polygon, Text,
};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, RGBAColor, RGBColor, ShapeStyle, TextStyle};
use shared::geometry::{Disk, InflatedPolygon, Point, Polygon as PolygonObstacle, Pose};

use super::canvas::Backend;
use super::data::{CentrePose, UnknownRecord};
use super::font;
use super::geom::{self, View, Xy};
use super::layout::MapLayout;
use super::palette;

/// A chart whose both axes are in metres.
pub type MapChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Space for the y tick labels and description left of a map, in pixels.
pub const MAP_LEFT_PX: u32 = 64;
/// Space for the x tick labels and description below a map, in pixels.
pub const MAP_BOTTOM_PX: u32 = 50;
/// Space right of a map, in pixels.
pub const MAP_RIGHT_PX: u32 = 24;

/// A line style: `color` at `width` pixels.
pub fn line(color: RGBAColor, width: u32) -> ShapeStyle {
    ShapeStyle {
        color,
        filled: false,
        stroke_width: width,
    }
}

/// A fill style.
pub fn fill(color: RGBAColor) -> ShapeStyle {
    ShapeStyle {
        color,
        filled: true,
        stroke_width: 1,
    }
}

/// `color` at `alpha` opacity.
pub fn alpha(color: RGBColor, alpha: f64) -> RGBAColor {
    color.mix(alpha)
}

/// `color`, opaque.
pub fn solid(color: RGBColor) -> RGBAColor {
    color.to_rgba()
}

/// The map chart of `layout` on `root`, with its grid and axes in metres drawn.
pub fn map_chart<'a, DB: Backend>(
    root: &'a DrawingArea<DB, Shift>,
    layout: &MapLayout,
) -> anyhow::Result<MapChart<'a, DB>> {
    let mut chart = map_chart_bare(root, layout)?;
    chart
        .configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style(font::text(14.0))
        .axis_desc_style(font::text(15.0))
        .bold_line_style(line(solid(palette::GRID), 1))
        .light_line_style(line(alpha(palette::GRID, 0.0), 0))
        .axis_style(line(solid(palette::TEXT_MUTED), 1))
        .x_labels(10)
        .y_labels(8)
        .x_label_formatter(&|v| fmt_m(*v))
        .y_label_formatter(&|v| fmt_m(*v))
        .draw()?;
    Ok(chart)
}

/// The map chart of `layout` on `root`, drawing nothing (for layers over a drawn map).
pub fn map_chart_bare<'a, DB: Backend>(
    root: &'a DrawingArea<DB, Shift>,
    layout: &MapLayout,
) -> anyhow::Result<MapChart<'a, DB>> {
    let m = layout.margins;
    Ok(ChartBuilder::on(root)
        .margin_top(m.top)
        .margin_right(m.right)
        .y_label_area_size(m.left)
        .x_label_area_size(m.bottom)
        .build_cartesian_2d(layout.x_m.clone(), layout.y_m.clone())?)
}

/// The view rectangle of `layout`.
pub fn view_of(layout: &MapLayout) -> View {
    View {
        x0: layout.x_m.start,
        x1: layout.x_m.end,
        y0: layout.y_m.start,
        y1: layout.y_m.end,
    }
}

/// Draws clipped shapes in metres onto a map.
pub struct Painter<'c, 'a, DB: Backend> {
    chart: &'c MapChart<'a, DB>,
    view: View,
    px_per_m: f64,
}

impl<'c, 'a, DB: Backend> Painter<'c, 'a, DB> {
    /// A painter for `chart` laid out as `layout`.
    pub fn new(chart: &'c MapChart<'a, DB>, layout: &MapLayout) -> Self {
        Self {
            chart,
            view: view_of(layout),
            px_per_m: layout.px_per_m,
        }
    }

    /// Metres for `px` pixels.
    pub fn m(&self, px: f64) -> f64 {
        px / self.px_per_m
    }

    /// A filled polygon, clipped.
    pub fn polygon(&self, points: &[Xy], style: ShapeStyle) -> anyhow::Result<()> {
        let clipped = self.view.clip_polygon(points);
        if clipped.len() >= 3 {
            self.chart
                .plotting_area()
                .draw(&Polygon::new(clipped, style))?;
        }
        Ok(())
    }

    /// A polyline, clipped.
    pub fn polyline(&self, points: &[Xy], style: ShapeStyle) -> anyhow::Result<()> {
        for piece in self.view.clip_polyline(points) {
            self.chart
                .plotting_area()
                .draw(&PathElement::new(piece, style))?;
        }
        Ok(())
    }

    /// A dashed polyline, clipped: dashes of `dash_px` with gaps of `gap_px`.
    pub fn dashed(
        &self,
        points: &[Xy],
        dash_px: u32,
        gap_px: u32,
        style: ShapeStyle,
    ) -> anyhow::Result<()> {
        for piece in self.view.clip_polyline(points) {
            self.chart
                .plotting_area()
                .draw(&DashedPathElement::new(piece, dash_px, gap_px, style))?;
        }
        Ok(())
    }

    /// A disk of radius `r` metres: `fill_style` inside (if any), `edge` around (if any).
    pub fn disk(
        &self,
        c: Xy,
        r: f64,
        fill_style: Option<ShapeStyle>,
        edge: Option<ShapeStyle>,
    ) -> anyhow::Result<()> {
        if !self.view.touches_disk(c, r) {
            return Ok(());
        }
        let poly = geom::circle(c, r, self.px_per_m);
        if let Some(f) = fill_style {
            self.polygon(&poly, f)?;
        }
        if let Some(e) = edge {
            self.polyline(&geom::closed(poly), e)?;
        }
        Ok(())
    }

    /// A disk of `radius_px` pixels whatever the scale (a marker).
    pub fn marker(&self, c: Xy, radius_px: f64, style: ShapeStyle) -> anyhow::Result<()> {
        let r = self.m(radius_px);
        if !self.view.touches_disk(c, r) {
            return Ok(());
        }
        self.polygon(&geom::circle(c, r, self.px_per_m), style)
    }

    /// The formation centre at `pose`: an arrow `len_px` long in the centre path's colour.
    pub fn centre_arrow(&self, pose: Pose, len_px: f64) -> anyhow::Result<()> {
        let tail = (pose.x_m, pose.y_m);
        self.arrow(
            tail,
            pose.heading_rad,
            len_px,
            solid(palette::CENTRE_PATH),
            2,
        )
    }

    /// The centre's whole path, faint (the backdrop of a moving scene).
    pub fn faint_centre_path(&self, centre: &[CentrePose]) -> anyhow::Result<()> {
        let path: Vec<Xy> = centre.iter().map(|c| (c.pose.x_m, c.pose.y_m)).collect();
        self.polyline(&path, line(alpha(palette::CENTRE_PATH, 0.3), 2))
    }

    /// An arrow from `tail` along `heading_rad`, `len_px` long.
    pub fn arrow(
        &self,
        tail: Xy,
        heading_rad: f64,
        len_px: f64,
        color: RGBAColor,
        width: u32,
    ) -> anyhow::Result<()> {
        let head_px = (len_px * 0.45).clamp(6.0, 12.0);
        let (shaft, head) = geom::arrow(tail, heading_rad, self.m(len_px), self.m(head_px));
        self.polyline(&shaft, line(color, width))?;
        self.polygon(&head, fill(color))
    }

    /// Where a robot of radius `radius_m` at `c` faces: a line along `heading_rad` from
    /// `inner` times its radius out to its rim (`inner` 0: from its centre).
    pub fn heading_tick(
        &self,
        c: Xy,
        radius_m: f64,
        heading_rad: f64,
        inner: f64,
        style: ShapeStyle,
    ) -> anyhow::Result<()> {
        let (sn, cs) = heading_rad.sin_cos();
        let at = |f: f64| (c.0 + f * radius_m * cs, c.1 + f * radius_m * sn);
        self.polyline(&[at(inner), at(1.0)], style)
    }

    /// Text at `at` (metres), if it is inside the view.
    pub fn text(&self, s: &str, at: Xy, style: &TextStyle<'_>) -> anyhow::Result<()> {
        if self.view.contains(at) {
            self.chart
                .plotting_area()
                .draw(&Text::new(s.to_string(), at, style.clone()))?;
        }
        Ok(())
    }

    /// The obstacles, each with its safety margin (grown by `margin_m`, translucent, with
    /// a dashed edge when there are few enough to keep the file small).
    pub fn obstacles(&self, obstacles: &[Disk], margin_m: f64) -> anyhow::Result<()> {
        let dashed = obstacles.len() <= 400;
        for o in obstacles {
            let c = (o.centre.x, o.centre.y);
            let r = o.radius_m + margin_m;
            if !self.view.touches_disk(c, r) {
                continue;
            }
            let ring = geom::circle(c, r, self.px_per_m);
            self.polygon(&ring, fill(alpha(palette::SAFETY_MARGIN, 0.16)))?;
            if dashed {
                self.dashed(
                    &geom::closed(ring),
                    4,
                    3,
                    line(solid(palette::SAFETY_MARGIN), 1),
                )?;
            } else {
                self.polyline(
                    &geom::closed(ring),
                    line(alpha(palette::SAFETY_MARGIN, 0.7), 1),
                )?;
            }
        }
        for o in obstacles {
            self.disk(
                (o.centre.x, o.centre.y),
                o.radius_m,
                Some(fill(solid(palette::OBSTACLE))),
                None,
            )?;
        }
        Ok(())
    }

    /// The polygon obstacles, filled as the disks are, each with its safety margin (the
    /// polygon grown by `margin_m`: its offset sides and the arcs round its convex
    /// corners, dashed).
    pub fn polygons(&self, polygons: &[PolygonObstacle], margin_m: f64) -> anyhow::Result<()> {
        for polygon in polygons {
            let corners: Vec<Xy> = polygon.vertices().iter().map(|v| (v.x, v.y)).collect();
            self.polygon(&corners, fill(solid(palette::OBSTACLE)))?;
            if margin_m <= 0.0 {
                continue;
            }
            let grown = InflatedPolygon::from_polygon(polygon.clone(), margin_m);
            let edge = line(solid(palette::SAFETY_MARGIN), 1);
            for (a, b) in grown.offset_sides() {
                self.dashed(&[(a.x, a.y), (b.x, b.y)], 4, 3, edge)?;
            }
            let n = corners.len();
            let v = polygon.vertices();
            for i in polygon.convex_corners() {
                let (prev, here, next) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
                // Outward normals of the sides before and after the corner.
                let before = (here - prev).normalize();
                let after = (next - here).normalize();
                let from_rad = (-before.x).atan2(before.y);
                let mut to_rad = (-after.x).atan2(after.y);
                // Round a convex corner of an anticlockwise polygon the normal turns left.
                if to_rad < from_rad {
                    to_rad += std::f64::consts::TAU;
                }
                let steps = 12;
                let arc: Vec<Xy> = (0..=steps)
                    .map(|k| {
                        let t = from_rad + (to_rad - from_rad) * k as f64 / steps as f64;
                        (here.x + margin_m * t.cos(), here.y + margin_m * t.sin())
                    })
                    .collect();
                self.dashed(&arc, 4, 3, edge)?;
            }
        }
        Ok(())
    }

    /// The safety margin ring of one obstacle (translucent fill, dashed edge), as
    /// [`Self::obstacles`] draws it.
    fn margin_ring(&self, c: Xy, r: f64, edge: RGBColor) -> anyhow::Result<()> {
        if !self.view.touches_disk(c, r) {
            return Ok(());
        }
        let ring = geom::circle(c, r, self.px_per_m);
        self.polygon(&ring, fill(alpha(palette::SAFETY_MARGIN, 0.16)))?;
        self.dashed(&geom::closed(ring), 4, 3, line(alpha(edge, 0.8), 1))
    }

    /// An obstacle the centre's planner did not know at the start. Once `known`: like any
    /// obstacle (its safety margin grown by `margin_m`, its body filled) and hatched;
    /// before: only its body's dashed outline.
    pub fn unknown_obstacle(
        &self,
        u: &UnknownRecord,
        known: bool,
        margin_m: f64,
    ) -> anyhow::Result<()> {
        let c = (u.disk.centre.x, u.disk.centre.y);
        let r = u.disk.radius_m;
        if !self.view.touches_disk(c, r + margin_m) {
            return Ok(());
        }
        let edge = geom::closed(geom::circle(c, r, self.px_per_m));
        if known {
            self.margin_ring(c, r + margin_m, palette::SAFETY_MARGIN)?;
            self.disk(c, r, Some(fill(alpha(palette::OBSTACLE, 0.55))), None)?;
            for chord in geom::hatch(c, r, self.m(5.0)) {
                self.polyline(&chord, line(solid(palette::UNKNOWN_OBSTACLE), 1))?;
            }
            self.polyline(&edge, line(solid(palette::UNKNOWN_OBSTACLE), 1))
        } else {
            self.dashed(&edge, 4, 3, line(solid(palette::UNKNOWN_OBSTACLE), 1))
        }
    }

    /// A moving obstacle of radius `r` standing at `at`: its safety margin (grown by
    /// `margin_m`) and its body.
    pub fn moving_obstacle(&self, at: Point, r: f64, margin_m: f64) -> anyhow::Result<()> {
        let c = (at.x, at.y);
        self.margin_ring(c, r + margin_m, palette::MOVING_OBSTACLE)?;
        self.disk(
            c,
            r,
            Some(fill(alpha(palette::MOVING_OBSTACLE, 0.85))),
            Some(line(solid(palette::BLACK), 1)),
        )
    }

    /// A moving obstacle's route: its waypoints joined (closed for a loop), thin.
    pub fn route(&self, m: &shared::world::moving_obstacle::MovingObstacle) -> anyhow::Result<()> {
        let mut pts: Vec<Xy> = m.waypoints_m.iter().map(|p| (p.x, p.y)).collect();
        if m.route == shared::world::moving_obstacle::Route::Loop {
            pts = geom::closed(pts);
        }
        self.polyline(&pts, line(alpha(palette::MOVING_OBSTACLE, 0.8), 1))
    }
}

/// A length in metres, shortest form up to millimetres (`0.25`, `2`, `1.125`), with three
/// significant digits below 0.1 (`0.0066`, `0.055`).
pub fn fmt_m(v: f64) -> String {
    // Millimetres for ordinary lengths; three significant digits below 0.1 (a
    // GRITSbot's 0.0066 m step), so a small figure is never rounded away.
    let decimals = if v != 0.0 && v.abs() < 0.1 && v.is_finite() {
        (2 - v.abs().log10().floor() as i32).clamp(3, 12) as usize
    } else {
        3
    };
    let s = format!("{v:.decimals$}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// The text anchor that puts a label on the side of its point that `dir_rad` points to
/// (0: the label to the right of the point, pi/2: above it, ...).
pub fn anchor_towards(dir_rad: f64) -> Pos {
    let (sn, cs) = dir_rad.sin_cos();
    let h = if cs > 0.35 {
        HPos::Left
    } else if cs < -0.35 {
        HPos::Right
    } else {
        HPos::Center
    };
    let v = if sn > 0.35 {
        VPos::Bottom
    } else if sn < -0.35 {
        VPos::Top
    } else {
        VPos::Center
    };
    Pos::new(h, v)
}

#[cfg(test)]
mod tests {
    use super::fmt_m;

    #[test]
    fn lengths_keep_millimetres_and_small_ones_three_digits() {
        assert_eq!(fmt_m(0.25), "0.25");
        assert_eq!(fmt_m(2.0), "2");
        assert_eq!(fmt_m(1.1254), "1.125");
        assert_eq!(fmt_m(0.0066), "0.0066");
        assert_eq!(fmt_m(0.055), "0.055");
        assert_eq!(fmt_m(0.000_123_4), "0.000123");
        assert_eq!(fmt_m(-1e-17), "0");
        assert_eq!(fmt_m(0.0), "0");
    }
}
