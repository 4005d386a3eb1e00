//! The formation figure (the paper's Fig. 7): every agent at its slot with the formation
//! centre at the start pose, each agent's safety circle, and slot labels.

use plotters::style::text_anchor::{HPos, Pos, VPos};
use shared::geometry::Point;

use super::canvas::Backend;
use super::data::RunData;
use super::font;
use super::geom::{View, Xy};
use super::header::{self, Header, LegendItem, Swatch};
use super::layout::MapLayout;
use super::map_figure::{MapFigure, map_layout};
use super::palette;
use super::scene::{self, Painter, alpha, fmt_m, line, solid};

/// Largest plotting area of the formation figure, in pixels.
pub const MAX_PLOT_PX: (u32, u32) = (900, 680);
/// Up to this many agents, each label gives the slot's polar coordinates.
const FULL_LABELS_UP_TO: usize = 12;
/// Up to this many agents, a dashed line joins the centre to each slot.
const SPOKES_UP_TO: usize = 24;
/// Up to this many agents, each circle is labelled with the agent's index.
const INDEX_LABELS_UP_TO: usize = 64;

/// The formation figure of a run.
pub struct FormationFigure<'a> {
    data: &'a RunData,
    header: Header,
    layout: MapLayout,
    margin_m: f64,
    /// Each agent's position at the start pose.
    positions: Vec<Point>,
}

impl<'a> FormationFigure<'a> {
    /// Lay out the formation figure of `data`.
    pub fn new(data: &'a RunData) -> Self {
        let s = &data.scenario;
        let start = s.path.start;
        let positions: Vec<Point> = s
            .agents
            .iter()
            .map(|a| a.slot.ideal_position(&start))
            .collect();
        // The view: every safety circle and the centre, with room for labels.
        let (mut x0, mut x1, mut y0, mut y1) = (start.x_m, start.x_m, start.y_m, start.y_m);
        for (p, a) in positions.iter().zip(&s.agents) {
            x0 = x0.min(p.x - a.radius_m);
            x1 = x1.max(p.x + a.radius_m);
            y0 = y0.min(p.y - a.radius_m);
            y1 = y1.max(p.y + a.radius_m);
        }
        let extent = (x1 - x0).max(y1 - y0).max(2.0);
        let pad = if s.agents.len() <= FULL_LABELS_UP_TO {
            0.3 * extent
        } else {
            0.1 * extent
        };
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let half_w = ((x1 - x0) / 2.0 + pad).max(extent * 0.4);
        let half_h = ((y1 - y0) / 2.0 + pad).max(extent * 0.3);

        let (margin_m, obstacle_items) = header::obstacle_legend(s);
        let mut legend = vec![
            LegendItem::new(
                Swatch::Disk {
                    fill: alpha(palette::AGENT, 0.45),
                    edge: Some(solid(palette::AGENT_EDGE)),
                    dashed: false,
                },
                "agent safety circle",
            ),
            LegendItem::new(
                Swatch::Arrow {
                    color: solid(palette::CENTRE_PATH),
                },
                "formation centre and heading",
            ),
        ];
        let n = s.agents.len();
        if n <= SPOKES_UP_TO {
            legend.push(LegendItem::new(
                Swatch::Line {
                    color: solid(palette::TEXT_MUTED),
                    width: 1,
                    dashed: true,
                },
                "slot offset",
            ));
        }
        let view = View {
            x0: cx - half_w,
            x1: cx + half_w,
            y0: cy - half_h,
            y1: cy + half_h,
        };
        if s.obstacles
            .iter()
            .any(|o| view.touches_disk((o.centre.x, o.centre.y), o.radius_m + margin_m))
        {
            legend.extend(obstacle_items);
        }
        let labels = if n <= FULL_LABELS_UP_TO {
            "labels: agent (r, θ) of its slot"
        } else if n <= INDEX_LABELS_UP_TO {
            "labels: agent index"
        } else {
            "too many agents to label"
        };
        let header = Header {
            title: header::title(format!("{}: formation at the start pose", s.name), s),
            subtitle: Some(format!(
                "{n} agents around the centre ({}, {}) m, heading {}°; {labels}{}",
                fmt_m(start.x_m),
                fmt_m(start.y_m),
                fmt_m(start.heading_rad.to_degrees()),
                if s.agents.iter().any(|a| a.kinematics.has_heading()) {
                    "; a tick to the rim: where the agent faces"
                } else {
                    ""
                },
            )),
            legend,
        };
        let layout = map_layout(
            cx - half_w..cx + half_w,
            cy - half_h..cy + half_h,
            MAX_PLOT_PX,
            super::field::MIN_WIDTH_PX,
            &header,
        );
        Self {
            data,
            header,
            layout,
            margin_m,
            positions,
        }
    }

    /// The figure's layout.
    pub fn layout(&self) -> &MapLayout {
        &self.layout
    }

    /// Each agent's position at the start pose, in metres.
    pub fn positions(&self) -> &[Point] {
        &self.positions
    }
}

impl MapFigure for FormationFigure<'_> {
    fn header(&self) -> &Header {
        &self.header
    }

    fn map_layout(&self) -> &MapLayout {
        &self.layout
    }

    fn paint<DB: Backend>(&self, p: &Painter<'_, '_, DB>) -> anyhow::Result<()> {
        let s = &self.data.scenario;
        let start = s.path.start;
        let centre: Xy = (start.x_m, start.y_m);
        p.obstacles(&s.obstacles, self.margin_m)?;
        p.polygons(&s.polygons, self.margin_m)?;
        let n = s.agents.len();
        for (pos, a) in self.positions.iter().zip(&s.agents) {
            if n <= SPOKES_UP_TO && a.slot.r_m > 0.0 {
                p.dashed(
                    &[centre, (pos.x, pos.y)],
                    5,
                    4,
                    line(alpha(palette::TEXT_MUTED, 0.7), 1),
                )?;
            }
        }
        let px_per_m = self.layout.px_per_m;
        let labelled = |r_m: f64| n <= INDEX_LABELS_UP_TO && r_m * px_per_m >= 9.0;
        for (pos, a) in self.positions.iter().zip(&s.agents) {
            let edge = if a.radius_m * px_per_m >= 12.0 { 2 } else { 1 };
            p.disk(
                (pos.x, pos.y),
                a.radius_m,
                Some(scene::fill(alpha(palette::AGENT, 0.45))),
                Some(line(solid(palette::AGENT_EDGE), edge)),
            )?;
            if !labelled(a.radius_m) {
                p.marker((pos.x, pos.y), 1.5, scene::fill(solid(palette::BLACK)))?;
            }
            // An agent with a heading: where it faces at the start, from beside its
            // label out to its rim.
            if a.kinematics.has_heading() {
                p.heading_tick(
                    (pos.x, pos.y),
                    a.radius_m,
                    start.heading_rad + a.heading_offset_rad,
                    0.5,
                    line(solid(palette::AGENT_EDGE), edge + 1),
                )?;
            }
        }
        p.arrow(
            centre,
            start.heading_rad,
            56.0,
            solid(palette::CENTRE_PATH),
            3,
        )?;
        p.marker(centre, 3.5, scene::fill(solid(palette::CENTRE_PATH)))?;

        for (i, (pos, a)) in self.positions.iter().zip(&s.agents).enumerate() {
            if labelled(a.radius_m) {
                let size = (a.radius_m * px_per_m * 0.9).clamp(11.0, 18.0);
                let style = font::text(size).pos(Pos::new(HPos::Center, VPos::Center));
                p.text(&i.to_string(), (pos.x, pos.y), &style)?;
            }
            if n <= FULL_LABELS_UP_TO {
                // Outward from the centre, beyond the circle (below for the centre slot).
                let dir = if a.slot.r_m > 1e-9 {
                    a.slot.theta_rad + start.heading_rad
                } else {
                    -std::f64::consts::FRAC_PI_2
                };
                let (sn, cs) = dir.sin_cos();
                let reach = a.radius_m + p.m(8.0);
                let at = (pos.x + reach * cs, pos.y + reach * sn);
                let label = format!(
                    "{i}: ({} m, {}°)",
                    fmt_m(a.slot.r_m),
                    fmt_m(a.slot.theta_rad.to_degrees())
                );
                p.text(
                    &label,
                    at,
                    &font::text(15.0).pos(scene::anchor_towards(dir)),
                )?;
            }
        }
        Ok(())
    }
}
