//! The field figure (the paper's Figs. 2, 3 and 6): obstacles with their safety margins,
//! the start and goal poses, and the formation centre's Hybrid A* path with heading
//! arrows. In a changing world also: each moving obstacle's route, where it stood at step
//! 0 (dashed outline) and at the last step (filled); each obstacle unknown at the start
//! (hatched, labelled with the step it was found at); and, when the centre replanned,
//! every plan (the first and each replan taken, dashed and lighter, a dot where each
//! replan starts) under the path actually followed (solid).

use super::canvas::Backend;
use super::data::RunData;
use super::font;
use super::geom::{self, Xy};
use super::header::{self, Header, LegendItem, Swatch};
use super::layout::MapLayout;
use super::map_figure::{MapFigure, map_layout};
use super::palette;
use super::scene::{self, Painter, alpha, fmt_m, line, solid};

/// Largest plotting area of the field figure, in pixels.
pub const MAX_PLOT_PX: (u32, u32) = (1000, 720);
/// Narrowest canvas of a map figure, in pixels (room for the title and legend).
pub const MIN_WIDTH_PX: u32 = 760;
/// Distance between two heading arrows along the path, in pixels.
const ARROW_SPACING_PX: f64 = 55.0;

/// The field figure of a run.
pub struct FieldFigure<'a> {
    data: &'a RunData,
    header: Header,
    layout: MapLayout,
    margin_m: f64,
}

impl<'a> FieldFigure<'a> {
    /// Lay out the field figure of `data`.
    pub fn new(data: &'a RunData) -> Self {
        let s = &data.scenario;
        let (margin_m, mut legend) = header::obstacle_legend(s);
        legend.extend(header::changing_world_legend(s, true));
        if !s.moving.is_empty() {
            legend.push(LegendItem::new(
                Swatch::Disk {
                    fill: alpha(palette::WHITE, 0.0),
                    edge: Some(solid(palette::MOVING_OBSTACLE)),
                    dashed: true,
                },
                "moving obstacle at step 0",
            ));
        }
        if data.replanned() {
            legend.push(LegendItem::new(
                Swatch::Line {
                    color: alpha(palette::CENTRE_PATH, PLAN_ALPHA),
                    width: 2,
                    dashed: true,
                },
                match data.plans.len().saturating_sub(1) {
                    1 => "plans (first + 1 replan)".to_string(),
                    n => format!("plans (first + {n} replans)"),
                },
            ));
        }
        let path_label = if data.replanned() {
            "centre path followed"
        } else {
            "centre path (Hybrid A*)"
        };
        legend.extend([
            LegendItem::new(
                Swatch::Line {
                    color: solid(palette::CENTRE_PATH),
                    width: 2,
                    dashed: false,
                },
                path_label,
            ),
            LegendItem::new(
                Swatch::Arrow {
                    color: solid(palette::CENTRE_PATH),
                },
                "heading",
            ),
            LegendItem::new(pose_swatch(palette::START), "start pose"),
            LegendItem::new(pose_swatch(palette::GOAL), "goal pose"),
        ]);
        let header = Header {
            title: header::title(format!("{}: obstacle field and centre path", s.name), s),
            subtitle: Some(format!(
                "{} x {} m field, {} obstacles{}{}; {} centre steps of {} m, turning radius {} m{}",
                fmt_m(s.field.width_m),
                fmt_m(s.field.height_m),
                s.obstacles.len(),
                match s.polygons.len() {
                    0 => String::new(),
                    1 => " and 1 polygon".to_string(),
                    n => format!(" and {n} polygons"),
                },
                changing_note(data),
                data.centre.len().saturating_sub(1),
                fmt_m(s.path.step_m),
                fmt_m(s.path.turning_radius_m),
                if s.path.allow_reverse {
                    ", reverse allowed"
                } else {
                    ""
                },
            )),
            legend,
        };
        let layout = map_layout(
            0.0..s.field.width_m,
            0.0..s.field.height_m,
            MAX_PLOT_PX,
            MIN_WIDTH_PX,
            &header,
        );
        Self {
            data,
            header,
            layout,
            margin_m,
        }
    }

    /// The figure's layout.
    pub fn layout(&self) -> &MapLayout {
        &self.layout
    }
}

/// Opacity of the plans drawn under the path followed.
const PLAN_ALPHA: f64 = 0.45;
/// Most unknown obstacles labelled with the step they were found at.
const MAX_FOUND_LABELS: usize = 40;

/// What a changing world adds to the subtitle's obstacle count: `, 2 moving, 1 unknown`
/// (empty for a static world).
fn changing_note(data: &RunData) -> String {
    let s = &data.scenario;
    let mut note = String::new();
    if !s.moving.is_empty() {
        note.push_str(&format!(", {} moving", s.moving.len()));
    }
    if !s.unknown.is_empty() {
        let found = data
            .unknown
            .iter()
            .filter(|u| u.known_from_step.is_some())
            .count();
        note.push_str(&format!(", {} unknown ({found} found)", s.unknown.len()));
    }
    note
}

fn pose_swatch(color: plotters::style::RGBColor) -> Swatch {
    Swatch::Disk {
        fill: solid(color),
        edge: Some(solid(palette::WHITE)),
        dashed: false,
    }
}

impl FieldFigure<'_> {
    /// The unknown obstacles, the moving obstacles' routes and their first and last
    /// places, and the plans (when the centre replanned): nothing for a static world.
    fn draw_changing_world<DB: Backend>(&self, p: &Painter<'_, '_, DB>) -> anyhow::Result<()> {
        let data = self.data;
        let s = &data.scenario;
        let label_style = font::text(13.0).color(&palette::TEXT_MUTED);
        for (i, u) in data.unknown.iter().enumerate() {
            p.unknown_obstacle(u, u.known_from_step.is_some(), self.margin_m)?;
            if i < MAX_FOUND_LABELS {
                let text = u
                    .known_from_step
                    .map_or("never found".to_string(), |k| format!("found at step {k}"));
                let at = (
                    u.disk.centre.x,
                    u.disk.centre.y - u.disk.radius_m - self.margin_m - p.m(3.0),
                );
                let style = label_style.pos(scene::anchor_towards(-std::f64::consts::FRAC_PI_2));
                p.text(&text, at, &style)?;
            }
        }
        for m in &s.moving {
            p.route(m)?;
        }
        if let Some(first) = data.moving.first() {
            for (at, m) in first.positions.iter().zip(&s.moving) {
                p.dashed(
                    &geom::closed(geom::circle((at.x, at.y), m.radius_m, self.layout.px_per_m)),
                    4,
                    3,
                    line(solid(palette::MOVING_OBSTACLE), 1),
                )?;
            }
        }
        if let Some(last) = data.moving.last() {
            for (at, m) in last.positions.iter().zip(&s.moving) {
                p.moving_obstacle(*at, m.radius_m, self.margin_m)?;
            }
        }
        if data.replanned() {
            let style = line(alpha(palette::CENTRE_PATH, PLAN_ALPHA), 2);
            for plan in &data.plans {
                let pts: Vec<Xy> = plan.poses.iter().map(|q| (q.x_m, q.y_m)).collect();
                p.dashed(&pts, 6, 4, style)?;
            }
            for plan in data.plans.iter().skip(1) {
                if let Some(q) = plan.poses.first() {
                    p.marker(
                        (q.x_m, q.y_m),
                        3.5,
                        scene::fill(solid(palette::CENTRE_PATH)),
                    )?;
                }
            }
        }
        Ok(())
    }
}

impl MapFigure for FieldFigure<'_> {
    fn header(&self) -> &Header {
        &self.header
    }

    fn map_layout(&self) -> &MapLayout {
        &self.layout
    }

    fn paint<DB: Backend>(&self, p: &Painter<'_, '_, DB>) -> anyhow::Result<()> {
        let s = &self.data.scenario;
        p.obstacles(&s.obstacles, self.margin_m)?;
        p.polygons(&s.polygons, self.margin_m)?;
        self.draw_changing_world(p)?;

        let path: Vec<Xy> = self
            .data
            .centre
            .iter()
            .map(|c| (c.pose.x_m, c.pose.y_m))
            .collect();
        p.polyline(&path, line(solid(palette::CENTRE_PATH), 2))?;
        // Heading arrows at even spacing along the path.
        let spacing_m = p.m(ARROW_SPACING_PX);
        let mut travelled = spacing_m * 0.5;
        for w in self.data.centre.windows(2) {
            let (a, b) = (w[0].pose, w[1].pose);
            travelled += (b.x_m - a.x_m).hypot(b.y_m - a.y_m);
            if travelled >= spacing_m {
                travelled = 0.0;
                p.centre_arrow(b, 18.0)?;
            }
        }
        for (pose, color, label) in [
            (s.path.start, palette::START, "start"),
            (s.path.goal, palette::GOAL, "goal"),
        ] {
            let at = (pose.x_m, pose.y_m);
            p.arrow(at, pose.heading_rad, 34.0, solid(color), 3)?;
            p.marker(at, 8.0, scene::fill(solid(palette::WHITE)))?;
            p.marker(at, 6.5, scene::fill(solid(color)))?;
            // The label sits to the right of the direction of travel, off the arrow.
            let side = pose.heading_rad - std::f64::consts::FRAC_PI_2;
            let off = p.m(13.0);
            let at_label = (at.0 + off * side.cos(), at.1 + off * side.sin());
            let style = font::text(16.0)
                .color(&color)
                .pos(scene::anchor_towards(side));
            p.text(label, at_label, &style)?;
        }
        Ok(())
    }
}
