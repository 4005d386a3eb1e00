//! The field figure (the paper's Figs. 2, 3 and 6): obstacles with their safety margins,
//! the start and goal poses, and the formation centre's Hybrid A* path with heading
//! arrows.

use plotters::coord::Shift;
use plotters::prelude::DrawingArea;

use super::canvas::{Backend, Figure};
use super::data::RunData;
use super::font;
use super::geom::Xy;
use super::layout::{MapLayout, Margins};
use super::palette;
use super::scene::{
    self, Header, LegendItem, MAP_BOTTOM_PX, MAP_LEFT_PX, MAP_RIGHT_PX, Painter, Swatch, fmt_m,
    line, solid,
};

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
        let (margin_m, mut legend) = scene::obstacle_legend(s);
        legend.extend([
            LegendItem::new(
                Swatch::Line {
                    color: solid(palette::CENTRE_PATH),
                    width: 2,
                    dashed: false,
                },
                "centre path (Hybrid A*)",
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
            title: scene::title(format!("{}: obstacle field and centre path", s.name), s),
            subtitle: Some(format!(
                "{} x {} m field, {} obstacles; {} centre steps of {} m, turning radius {} m{}",
                fmt_m(s.field.width_m),
                fmt_m(s.field.height_m),
                s.obstacles.len(),
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
        let layout = MapLayout::fit(
            0.0..s.field.width_m,
            0.0..s.field.height_m,
            MAX_PLOT_PX,
            MIN_WIDTH_PX,
            |w| Margins {
                top: header.height_px(w),
                left: MAP_LEFT_PX,
                bottom: MAP_BOTTOM_PX,
                right: MAP_RIGHT_PX,
            },
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

fn pose_swatch(color: plotters::style::RGBColor) -> Swatch {
    Swatch::Disk {
        fill: solid(color),
        edge: Some(solid(palette::WHITE)),
        dashed: false,
    }
}

impl Figure for FieldFigure<'_> {
    fn size_px(&self) -> (u32, u32) {
        (self.layout.width_px, self.layout.height_px)
    }

    fn draw<DB: Backend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        root.fill(&palette::WHITE)?;
        self.header.draw(root)?;
        let chart = scene::map_chart(root, &self.layout)?;
        let p = Painter::new(&chart, &self.layout);
        let s = &self.data.scenario;
        p.obstacles(&s.obstacles, self.margin_m)?;

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
                p.arrow(
                    (b.x_m, b.y_m),
                    b.heading_rad,
                    18.0,
                    solid(palette::CENTRE_PATH),
                    2,
                )?;
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
