//! Drawing the world in metres: the map chart (equal scale, axes in metres), obstacles
//! with their safety margins, circles, polylines and arrows clipped to the view, and the
//! header (title, subtitle, legend) that every figure carries above its plot.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::{
    Cartesian2d, ChartBuilder, ChartContext, DrawingArea, PathElement, Polygon, Rectangle, Text,
};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, RGBAColor, RGBColor, ShapeStyle, TextStyle};
use shared::geometry::{Disk, Point};
use shared::scenario::Scenario;
use shared::vocabulary::TurnMode;

use super::canvas::Backend;
use super::data::UnknownRecord;
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
    pub fn route(&self, m: &shared::moving_obstacle::MovingObstacle) -> anyhow::Result<()> {
        let mut pts: Vec<Xy> = m.waypoints_m.iter().map(|p| (p.x, p.y)).collect();
        if m.route == shared::moving_obstacle::Route::Loop {
            pts = geom::closed(pts);
        }
        self.polyline(&pts, line(alpha(palette::MOVING_OBSTACLE, 0.8), 1))
    }
}

/// Legend entries for what a changing world adds to a map: moving obstacles (with their
/// routes when `routes`) and obstacles unknown at the start; none for a static world.
pub fn changing_world_legend(scenario: &Scenario, routes: bool) -> Vec<LegendItem> {
    let mut legend = Vec::new();
    if !scenario.moving.is_empty() {
        legend.push(LegendItem::new(
            Swatch::Disk {
                fill: alpha(palette::MOVING_OBSTACLE, 0.85),
                edge: Some(solid(palette::BLACK)),
                dashed: false,
            },
            "moving obstacle",
        ));
        if routes {
            legend.push(LegendItem::new(
                Swatch::Line {
                    color: alpha(palette::MOVING_OBSTACLE, 0.8),
                    width: 1,
                    dashed: false,
                },
                "its route",
            ));
        }
    }
    if !scenario.unknown.is_empty() {
        legend.push(LegendItem::new(
            Swatch::Disk {
                fill: alpha(palette::WHITE, 0.0),
                edge: Some(solid(palette::UNKNOWN_OBSTACLE)),
                dashed: true,
            },
            "unknown to the planner",
        ));
        legend.push(LegendItem::new(
            Swatch::Disk {
                fill: alpha(palette::OBSTACLE, 0.55),
                edge: Some(solid(palette::UNKNOWN_OBSTACLE)),
                dashed: false,
            },
            "found on the way",
        ));
    }
    legend
}

/// What a legend entry shows beside its label.
#[derive(Clone, Copy, Debug)]
pub enum Swatch {
    /// A line (dashed or not).
    Line {
        /// Colour.
        color: RGBAColor,
        /// Width, in pixels.
        width: u32,
        /// Whether it is dashed.
        dashed: bool,
    },
    /// A disk with a fill and an edge.
    Disk {
        /// Fill.
        fill: RGBAColor,
        /// Edge.
        edge: Option<RGBAColor>,
        /// Whether the edge is dashed.
        dashed: bool,
    },
    /// An arrow pointing right.
    Arrow {
        /// Colour.
        color: RGBAColor,
    },
    /// A translucent band.
    Band {
        /// Colour.
        color: RGBAColor,
    },
}

/// A legend entry.
#[derive(Clone, Debug)]
pub struct LegendItem {
    /// The swatch.
    pub swatch: Swatch,
    /// The label.
    pub label: String,
}

impl LegendItem {
    /// An entry.
    pub fn new(swatch: Swatch, label: impl Into<String>) -> Self {
        Self {
            swatch,
            label: label.into(),
        }
    }
}

/// The header above a plot: a title, an optional subtitle and a legend that wraps.
#[derive(Clone, Debug)]
pub struct Header {
    /// The title (names the scenario).
    pub title: String,
    /// A line under the title.
    pub subtitle: Option<String>,
    /// The legend.
    pub legend: Vec<LegendItem>,
}

const PAD_PX: i32 = 16;
const TITLE_ROW_PX: u32 = 36;
/// Every further line of a title too long for one, in pixels.
const TITLE_MORE_ROW_PX: u32 = 28;
const SUBTITLE_ROW_PX: u32 = 22;
const LEGEND_ROW_PX: u32 = 24;
const SWATCH_W_PX: i32 = 30;

fn title_style() -> TextStyle<'static> {
    font::text(22.0)
}

fn small_style() -> TextStyle<'static> {
    font::text(15.0)
}

impl Header {
    /// The title in lines that fit a canvas `width_px` wide (broken between words; a
    /// single word too long stays on its line).
    fn title_lines(&self, width_px: u32) -> Vec<String> {
        let style = title_style();
        let limit = (width_px as i32 - 2 * PAD_PX).max(0) as u32;
        let mut lines: Vec<String> = Vec::new();
        for word in self.title.split(' ') {
            match lines.last_mut() {
                Some(last) if font::measure(&format!("{last} {word}"), &style).0 <= limit => {
                    last.push(' ');
                    last.push_str(word);
                }
                _ => lines.push(word.to_string()),
            }
        }
        if lines.is_empty() {
            lines.push(String::new());
        }
        lines
    }

    /// Height of the title on a canvas `width_px` wide, in pixels.
    fn title_px(&self, width_px: u32) -> u32 {
        TITLE_ROW_PX + (self.title_lines(width_px).len() as u32 - 1) * TITLE_MORE_ROW_PX
    }

    /// Where each legend entry goes (x, row) for a canvas `width_px` wide.
    fn places(&self, width_px: u32) -> Vec<(i32, u32)> {
        let style = small_style();
        let mut x = PAD_PX;
        let mut row = 0;
        let limit = width_px as i32 - PAD_PX;
        self.legend
            .iter()
            .map(|item| {
                let w = SWATCH_W_PX + 6 + font::measure(&item.label, &style).0 as i32 + 26;
                if x > PAD_PX && x + w > limit {
                    x = PAD_PX;
                    row += 1;
                }
                let place = (x, row);
                x += w;
                place
            })
            .collect()
    }

    /// Where the subtitle starts (its top-left corner) on a canvas `width_px` wide, in
    /// pixels, and its style: for figures that write a changing subtitle themselves.
    pub fn subtitle_place(&self, width_px: u32) -> ((i32, i32), TextStyle<'static>) {
        (
            (PAD_PX, self.title_px(width_px) as i32),
            small_style().color(&palette::TEXT_MUTED),
        )
    }

    /// Height of the header on a canvas `width_px` wide, in pixels.
    pub fn height_px(&self, width_px: u32) -> u32 {
        let rows = self.places(width_px).last().map_or(0, |&(_, r)| r + 1);
        self.title_px(width_px)
            + self.subtitle.as_ref().map_or(0, |_| SUBTITLE_ROW_PX)
            + rows * LEGEND_ROW_PX
            + 8
    }

    /// Draw the header at the top of `root`.
    pub fn draw<DB: Backend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let (width_px, _) = root.dim_in_pixel();
        for (k, text) in self.title_lines(width_px).into_iter().enumerate() {
            let y = 10 + (k as u32 * TITLE_MORE_ROW_PX) as i32;
            root.draw(&Text::new(text, (PAD_PX, y), title_style()))?;
        }
        let mut top = self.title_px(width_px) as i32;
        if let Some(sub) = &self.subtitle {
            root.draw(&Text::new(
                sub.clone(),
                (PAD_PX, top),
                small_style().color(&palette::TEXT_MUTED),
            ))?;
            top += SUBTITLE_ROW_PX as i32;
        }
        for (item, (x, row)) in self.legend.iter().zip(self.places(width_px)) {
            let y = top + (row * LEGEND_ROW_PX) as i32 + 9;
            draw_swatch(root, item.swatch, x, y)?;
            root.draw(&Text::new(
                item.label.clone(),
                (x + SWATCH_W_PX + 6, y - 8),
                small_style(),
            ))?;
        }
        Ok(())
    }
}

/// Draw `swatch` with its left end at `x` and its middle at `y`.
fn draw_swatch<DB: Backend>(
    root: &DrawingArea<DB, Shift>,
    swatch: Swatch,
    x: i32,
    y: i32,
) -> anyhow::Result<()> {
    let circle = |r: f64| -> Vec<(i32, i32)> {
        geom::circle((f64::from(x + SWATCH_W_PX / 2), f64::from(y)), r, 1.0)
            .into_iter()
            .map(|(a, b)| (a.round() as i32, b.round() as i32))
            .collect()
    };
    match swatch {
        Swatch::Line {
            color,
            width,
            dashed,
        } => {
            let pts = vec![(x, y), (x + SWATCH_W_PX, y)];
            if dashed {
                root.draw(&DashedPathElement::new(pts, 5, 3, line(color, width)))?;
            } else {
                root.draw(&PathElement::new(pts, line(color, width)))?;
            }
        }
        Swatch::Disk {
            fill: f,
            edge,
            dashed,
        } => {
            root.draw(&Polygon::new(circle(7.0), fill(f)))?;
            if let Some(e) = edge {
                let ring = geom::closed(circle(7.0));
                if dashed {
                    root.draw(&DashedPathElement::new(ring, 3, 2, line(e, 1)))?;
                } else {
                    root.draw(&PathElement::new(ring, line(e, 2)))?;
                }
            }
        }
        Swatch::Arrow { color } => {
            root.draw(&PathElement::new(
                vec![(x, y), (x + SWATCH_W_PX - 8, y)],
                line(color, 2),
            ))?;
            root.draw(&Polygon::new(
                vec![
                    (x + SWATCH_W_PX, y),
                    (x + SWATCH_W_PX - 10, y - 5),
                    (x + SWATCH_W_PX - 10, y + 5),
                ],
                fill(color),
            ))?;
        }
        Swatch::Band { color } => {
            root.draw(&Rectangle::new(
                [(x, y - 6), (x + SWATCH_W_PX, y + 6)],
                fill(color),
            ))?;
        }
    }
    Ok(())
}

/// The margin obstacles are grown by on maps (the largest agent radius) and the legend
/// entries for obstacles and their margins.
pub fn obstacle_legend(scenario: &shared::scenario::Scenario) -> (f64, Vec<LegendItem>) {
    let radii = scenario.agents.iter().map(|a| a.radius_m);
    let max = radii.clone().fold(0.0, f64::max);
    let min = radii.fold(f64::INFINITY, f64::min);
    let margin_label = if (max - min).abs() < 1e-12 {
        format!("safety margin (+{} m agent radius)", fmt_m(max))
    } else {
        format!("safety margin (+{} m, largest agent radius)", fmt_m(max))
    };
    let legend = vec![
        LegendItem::new(
            Swatch::Disk {
                fill: solid(palette::OBSTACLE),
                edge: None,
                dashed: false,
            },
            "obstacle",
        ),
        LegendItem::new(
            Swatch::Disk {
                fill: alpha(palette::SAFETY_MARGIN, 0.16),
                edge: Some(solid(palette::SAFETY_MARGIN)),
                dashed: true,
            },
            margin_label,
        ),
    ];
    (max, legend)
}

/// What a run's model adds to the paper's, for titles: the top speed (when the
/// scenario has one), the sensing radius (when it has one) and parallel turns; `None`
/// for the paper's model. For example `top speed 0.6 m/step, sensing 4 m, parallel
/// turns`.
pub fn model_note(s: &Scenario) -> Option<String> {
    let mut parts = Vec::new();
    let speeds: Vec<f64> = s.agents.iter().filter_map(|a| a.max_step_m).collect();
    if !speeds.is_empty() {
        let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = speeds.iter().copied().fold(0.0, f64::max);
        let range = if lo == hi {
            fmt_m(lo)
        } else {
            format!("{}-{}", fmt_m(lo), fmt_m(hi))
        };
        let unlimited = s.agents.len() - speeds.len();
        parts.push(if unlimited == 0 {
            format!("top speed {range} m/step")
        } else {
            let agents = if unlimited == 1 { "agent" } else { "agents" };
            format!("top speed {range} m/step ({unlimited} {agents} unlimited)")
        });
    }
    let sensing: Vec<f64> = s.agents.iter().filter_map(|a| a.sensing_radius_m).collect();
    if !sensing.is_empty() {
        let lo = sensing.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = sensing.iter().copied().fold(0.0, f64::max);
        parts.push(if lo == hi {
            format!("sensing {} m", fmt_m(lo))
        } else {
            format!("sensing {}-{} m", fmt_m(lo), fmt_m(hi))
        });
    }
    if s.turns == TurnMode::Parallel {
        parts.push("parallel turns".to_string());
    }
    (!parts.is_empty()).then(|| parts.join(", "))
}

/// `base` with the run's [`model_note`] after it, in parentheses, when there is one.
pub fn title(base: String, s: &Scenario) -> String {
    match model_note(s) {
        Some(note) => format!("{base} ({note})"),
        None => base,
    }
}

/// A length in metres, shortest form up to millimetres (`0.25`, `2`, `1.125`).
pub fn fmt_m(v: f64) -> String {
    let s = format!("{v:.3}");
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
    use super::*;

    #[test]
    fn the_model_note_names_what_the_scenario_adds() {
        let paper = Scenario::paper();
        assert_eq!(model_note(&paper), None);
        assert_eq!(title("t".into(), &paper), "t");
        let mut s = paper.clone();
        for a in &mut s.agents {
            a.max_step_m = Some(0.5);
        }
        assert_eq!(model_note(&s).as_deref(), Some("top speed 0.5 m/step"));
        s.agents[1].max_step_m = Some(0.3);
        s.turns = TurnMode::Parallel;
        assert_eq!(
            title("t".into(), &s),
            "t (top speed 0.3-0.5 m/step, parallel turns)"
        );
        s.agents[2].max_step_m = None;
        for a in &mut s.agents {
            a.sensing_radius_m = Some(4.0);
        }
        s.turns = TurnMode::Sequential;
        assert_eq!(
            model_note(&s).as_deref(),
            Some("top speed 0.3-0.5 m/step (1 agent unlimited), sensing 4 m")
        );
    }
}
