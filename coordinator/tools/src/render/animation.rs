//! The animation of a whole run (the paper's video, and its Fig. 8 at every step): the
//! obstacles, the centre path, every agent with its safety circle, its ideal slot and the
//! path it took to its best point, and the current step. In a changing world also each
//! moving obstacle where it stands during the frame's step (its route thin behind it),
//! and each obstacle unknown at the start as a dashed outline until the step it became
//! known, filled and hatched from then on. Long runs are subsampled to at most
//! [`MAX_FRAMES`] frames so the GIF stays a few megabytes.

use std::io::Write;

use plotters::coord::Shift;
use plotters::prelude::{BitMapBackend, DrawingArea, IntoDrawingArea, Text};

use super::canvas::{self, Backend, Figure};
use super::data::RunData;
use super::geom::Xy;
use super::gif_writer::GifWriter;
use super::header::{self, Header, LegendItem, Swatch};
use super::layout::{MapLayout, Margins};
use super::map_figure::map_layout;
use super::metrics::StepMetrics;
use super::palette;
use super::scene::{self, MAP_BOTTOM_PX, MAP_RIGHT_PX, Painter, alpha, fill, line, solid};
use super::text::TextSetter;

/// Most frames in an animation.
pub const MAX_FRAMES: usize = 150;
/// Largest plotting area of a frame, in pixels.
pub const MAX_PLOT_PX: (u32, u32) = (840, 600);
/// How long the last frame stays, in hundredths of a second.
const HOLD_LAST_CS: u16 = 250;

/// The steps shown: every step when there are at most `max_frames`, otherwise an even
/// subsample that always holds the first and the last (indices into the steps).
pub fn frame_indices(steps: usize, max_frames: usize) -> Vec<usize> {
    if steps == 0 {
        return Vec::new();
    }
    if steps <= max_frames.max(2) {
        return (0..steps).collect();
    }
    let stride = (steps - 1).div_ceil(max_frames.max(3) - 2);
    let mut frames: Vec<usize> = (0..steps).step_by(stride).collect();
    if frames.last() != Some(&(steps - 1)) {
        frames.push(steps - 1);
    }
    frames
}

/// The animation of a run.
pub struct Animation<'a> {
    data: &'a RunData,
    metrics: &'a [StepMetrics],
    header: Header,
    /// The whole field, at the left of the canvas.
    layout: MapLayout,
    /// The close-up panel right of the field, centred on the formation centre (its
    /// ranges are moved every frame; its pixel geometry stays).
    close_up: MapLayout,
    /// Half the side of the close-up window, in metres.
    close_up_half_m: f64,
    margin_m: f64,
    frames: Vec<usize>,
    /// Each live agent's sensing radius as a faint circle.
    sensing_circles: bool,
}

/// Opacity of the sensing circles: faint, so a swarm's overlapping circles stay a haze
/// behind the agents.
const SENSING_ALPHA: f64 = 0.4;

/// Side of the close-up panel's plot, at most, in pixels.
const CLOSE_UP_MAX_PX: u32 = 440;
/// Room left of the close-up plot for its y labels, in pixels.
const CLOSE_UP_LEFT_PX: u32 = 56;

impl<'a> Animation<'a> {
    /// Lay out the animation of `data` (`metrics` from [`super::metrics::per_step`]).
    pub fn new(data: &'a RunData, metrics: &'a [StepMetrics]) -> Self {
        Self::with_sensing_circles(data, metrics, false)
    }

    /// [`Animation::new`], drawing each live agent's sensing radius as a faint circle
    /// when `sensing_circles` is set and the scenario has one.
    pub fn with_sensing_circles(
        data: &'a RunData,
        metrics: &'a [StepMetrics],
        sensing_circles: bool,
    ) -> Self {
        let s = &data.scenario;
        let sensing_circles =
            sensing_circles && s.agents.iter().any(|a| a.sensing_radius_m.is_some());
        let (margin_m, mut legend) = header::obstacle_legend(s);
        legend.extend(header::changing_world_legend(s, true));
        legend.extend([
            LegendItem::new(
                Swatch::Disk {
                    fill: alpha(palette::AGENT, 0.6),
                    edge: Some(solid(palette::AGENT_EDGE)),
                    dashed: false,
                },
                "agent (safety circle)",
            ),
            LegendItem::new(
                Swatch::Disk {
                    fill: alpha(palette::WHITE, 0.0),
                    edge: Some(solid(palette::SLOT)),
                    dashed: false,
                },
                "ideal slot",
            ),
            LegendItem::new(
                Swatch::Line {
                    color: solid(palette::MOVE),
                    width: 2,
                    dashed: false,
                },
                "path to best point",
            ),
            LegendItem::new(
                Swatch::Line {
                    color: solid(palette::CENTRE_PATH),
                    width: 2,
                    dashed: false,
                },
                "centre path",
            ),
        ]);
        if sensing_circles {
            legend.push(LegendItem::new(
                Swatch::Disk {
                    fill: alpha(palette::WHITE, 0.0),
                    edge: Some(alpha(palette::SENSING, SENSING_ALPHA)),
                    dashed: false,
                },
                "sensing radius",
            ));
        }
        if data
            .steps
            .iter()
            .any(|st| st.agents.iter().any(|a| !a.alive))
        {
            legend.push(LegendItem::new(
                Swatch::Disk {
                    fill: solid(palette::AGENT_DEAD),
                    edge: None,
                    dashed: false,
                },
                "dead agent",
            ));
        }
        let header = Header {
            title: header::title(format!("{}: formation run", s.name), s),
            // Written per frame; reserve its row.
            subtitle: Some(String::new()),
            legend,
        };
        let layout = map_layout(
            0.0..s.field.width_m,
            0.0..s.field.height_m,
            MAX_PLOT_PX,
            super::field::MIN_WIDTH_PX,
            &header,
        );
        // The close-up shows the formation's whole extent around its centre.
        let reach = s
            .agents
            .iter()
            .map(|a| a.slot.r_m + a.radius_m)
            .fold(0.0, f64::max);
        let close_up_half_m = (reach * 1.15 + 0.75).max(2.0);
        let side = layout.plot_height_px.clamp(200, CLOSE_UP_MAX_PX);
        let top = layout.margins.top;
        let close_up = MapLayout::fit(
            -close_up_half_m..close_up_half_m,
            -close_up_half_m..close_up_half_m,
            (side, side),
            0,
            |_| Margins {
                top,
                left: CLOSE_UP_LEFT_PX,
                bottom: MAP_BOTTOM_PX,
                right: MAP_RIGHT_PX,
            },
        );
        Self {
            data,
            metrics,
            header,
            layout,
            close_up,
            close_up_half_m,
            margin_m,
            frames: frame_indices(data.steps.len(), MAX_FRAMES),
            sensing_circles,
        }
    }

    /// Whether the sensing circles are drawn.
    pub fn draws_sensing_circles(&self) -> bool {
        self.sensing_circles
    }

    /// The close-up's layout around `centre` (metres).
    fn close_up_at(&self, centre: Xy) -> MapLayout {
        let h = self.close_up_half_m;
        MapLayout {
            x_m: centre.0 - h..centre.0 + h,
            y_m: centre.1 - h..centre.1 + h,
            ..self.close_up.clone()
        }
    }

    /// The layout of the whole-field map at the left of every frame (the canvas is
    /// wider: the close-up panel is on the right, see [`Animation::size_px`]).
    pub fn layout(&self) -> &MapLayout {
        &self.layout
    }

    /// The steps shown, as indices into the run's steps.
    pub fn frames(&self) -> &[usize] {
        &self.frames
    }

    /// Time each frame stays, in hundredths of a second: about 12 s in all, between
    /// 0.05 s and 0.25 s a frame.
    pub fn delay_cs(&self) -> u16 {
        (1200 / self.frames.len().max(1)).clamp(5, 25) as u16
    }

    /// Write the animation as a GIF into `out`.
    pub fn write_gif<W: Write>(&self, out: W) -> anyhow::Result<W> {
        super::font::ensure_registered()?;
        let (w, h) = self.size_px();
        let base = canvas::render_rgb(&Background(self))?;
        let mut gif = GifWriter::new(out, w, h)?;
        let delay = self.delay_cs();
        for k in 0..self.frames.len() {
            let frame = self.frame_rgb(&base, k)?;
            let last = k + 1 == self.frames.len();
            gif.push(&frame, if last { HOLD_LAST_CS } else { delay })?;
        }
        gif.finish()
    }

    /// Frame `k` as RGB, drawn over the static `base`.
    pub fn frame_rgb(&self, base: &[u8], k: usize) -> anyhow::Result<Vec<u8>> {
        let (w, h) = self.size_px();
        let mut rgb = base.to_vec();
        {
            let root =
                TextSetter::new(BitMapBackend::with_buffer(&mut rgb, (w, h))).into_drawing_area();
            self.draw_frame(&root, k)?;
            root.present()?;
        }
        Ok(rgb)
    }

    /// Size of every frame (the field map and the close-up side by side), in pixels.
    pub fn size_px(&self) -> (u32, u32) {
        (
            self.layout.width_px + self.close_up.width_px,
            self.layout.height_px.max(self.close_up.height_px),
        )
    }

    /// What changes from frame to frame.
    fn draw_frame<DB: Backend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        k: usize,
    ) -> anyhow::Result<()> {
        let Some(&at) = self.frames.get(k) else {
            anyhow::bail!("no frame {k}");
        };
        let step = &self.data.steps[at];
        let (left, right) = root.split_horizontally(self.layout.width_px);
        let centre = self
            .data
            .centre_at(step.step)
            .map_or((0.0, 0.0), |c| (c.x_m, c.y_m));

        let chart = scene::map_chart_bare(&left, &self.layout)?;
        let p = Painter::new(&chart, &self.layout);
        self.draw_world(&p, at, false)?;
        // Where the close-up looks.
        let h = self.close_up_half_m;
        let (x0, x1, y0, y1) = (centre.0 - h, centre.0 + h, centre.1 - h, centre.1 + h);
        p.dashed(
            &[(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
            4,
            3,
            line(solid(palette::BLACK), 1),
        )?;

        let close_up = self.close_up_at(centre);
        // The panel is shorter than the canvas: keep its plot square.
        let (panel, _) = right.split_vertically(close_up.height_px);
        let chart = scene::map_chart(&panel, &close_up)?;
        let p = Painter::new(&chart, &close_up);
        p.obstacles(&self.data.scenario.obstacles, self.margin_m)?;
        p.polygons(&self.data.scenario.polygons, self.margin_m)?;
        p.faint_centre_path(&self.data.centre)?;
        self.draw_world(&p, at, true)?;
        right.draw(&Text::new(
            "close-up around the formation centre",
            (CLOSE_UP_LEFT_PX as i32, close_up.margins.top as i32 - 24),
            super::font::text(15.0),
        ))?;

        let m = self.metrics.get(at).filter(|m| m.step == step.step);
        let mean = m
            .and_then(|m| m.mean_deviation_m)
            .map_or("-".to_string(), |v| format!("{v:.3} m"));
        let clear = m
            .and_then(|m| match (m.agent_clearance_m, m.obstacle_clearance_m) {
                (Some(a), Some(o)) => Some(a.min(o)),
                (a, o) => a.or(o),
            })
            .map_or("-".to_string(), |v| format!("{v:.4} m"));
        let dead = step.agents.iter().filter(|a| !a.alive).count();
        let found = if self.data.unknown.is_empty() {
            String::new()
        } else {
            let known = self
                .data
                .unknown
                .iter()
                .filter(|u| u.known_at(step.step))
                .count();
            format!("   {known} of {} unknown found", self.data.unknown.len())
        };
        let text = format!(
            "step {} of {}   mean deviation {mean}   min clearance {clear}{}{found}",
            step.step,
            self.data.last_step(),
            if dead > 0 {
                format!("   {dead} dead")
            } else {
                String::new()
            }
        );
        let (origin, style) = self.header.subtitle_place(self.layout.width_px);
        root.draw(&Text::new(text, origin, style))?;
        Ok(())
    }

    /// The moving part of the world at step index `at`: the centre path travelled so
    /// far, each agent's path to its best point, the slots, the agents and the centre.
    fn draw_world<DB: Backend>(
        &self,
        p: &Painter<'_, '_, DB>,
        at: usize,
        close_up: bool,
    ) -> anyhow::Result<()> {
        let step = &self.data.steps[at];
        // The changing world under the formation: each unknown obstacle as the centre's
        // controller knew it during this step, each moving obstacle where it stands.
        for u in &self.data.unknown {
            p.unknown_obstacle(u, u.known_at(step.step), self.margin_m)?;
        }
        if let Some(positions) = self.data.moving_at(step.step) {
            for (q, m) in positions.iter().zip(&self.data.scenario.moving) {
                p.moving_obstacle(*q, m.radius_m, self.margin_m)?;
            }
        }
        let travelled: Vec<Xy> = self
            .data
            .centre
            .iter()
            .take_while(|c| c.step <= step.step)
            .map(|c| (c.pose.x_m, c.pose.y_m))
            .collect();
        p.polyline(&travelled, line(solid(palette::CENTRE_PATH), 2))?;

        let radii: Vec<f64> = self
            .data
            .scenario
            .agents
            .iter()
            .map(|a| a.radius_m)
            .collect();
        let small = radii.iter().fold(f64::INFINITY, |m, &r| m.min(r)) < p.m(3.0);
        let move_width = if small { 1 } else { 2 };
        for a in &step.agents {
            if a.waypoints.len() > 1 {
                let pts: Vec<Xy> = a.waypoints.iter().map(|q| (q.x, q.y)).collect();
                p.polyline(&pts, line(solid(palette::MOVE), move_width))?;
            }
        }
        for (a, &r) in step.agents.iter().zip(&radii) {
            if !a.alive {
                continue;
            }
            let c = (a.slot.x, a.slot.y);
            if small {
                p.marker(c, 1.0, fill(alpha(palette::SLOT, 0.8)))?;
            } else {
                let width = if close_up { 2 } else { 1 };
                p.disk(c, r, None, Some(line(solid(palette::SLOT), width)))?;
            }
        }
        if self.sensing_circles {
            let edge = line(alpha(palette::SENSING, SENSING_ALPHA), 1);
            for (a, spec) in step.agents.iter().zip(&self.data.scenario.agents) {
                if let (true, Some(r)) = (a.alive, spec.sensing_radius_m) {
                    p.disk((a.position.x, a.position.y), r, None, Some(edge))?;
                }
            }
        }
        for (a, &r) in step.agents.iter().zip(&radii) {
            let c = (a.position.x, a.position.y);
            let (body, edge) = if a.alive {
                (alpha(palette::AGENT, 0.6), solid(palette::AGENT_EDGE))
            } else {
                (solid(palette::AGENT_DEAD), solid(palette::BLACK))
            };
            if small {
                let color = if a.alive {
                    palette::AGENT
                } else {
                    palette::AGENT_DEAD
                };
                p.disk(c, r.max(p.m(1.5)), Some(fill(solid(color))), None)?;
            } else {
                p.disk(c, r, Some(fill(body)), Some(line(edge, 1)))?;
            }
            // An agent with a heading shows where it faces: centre to rim, at least a few
            // pixels long on a small disk.
            if let Some(heading_rad) = a.heading_rad {
                let width = if close_up { 2 } else { 1 };
                p.heading_tick(c, r.max(p.m(4.0)), heading_rad, 0.0, line(edge, width))?;
            }
        }
        if let Some(pose) = self.data.centre_at(step.step) {
            p.centre_arrow(pose, 22.0)?;
        }
        Ok(())
    }
}

/// The static layer of every frame: header, axes, obstacles, the moving obstacles'
/// routes, the whole centre path, the start and goal.
struct Background<'b, 'a>(&'b Animation<'a>);

impl Figure for Background<'_, '_> {
    fn size_px(&self) -> (u32, u32) {
        self.0.size_px()
    }

    fn draw<DB: Backend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let a = self.0;
        root.fill(&palette::WHITE)?;
        let (left, _) = root.split_horizontally(a.layout.width_px);
        a.header.draw(&left)?;
        let chart = scene::map_chart(&left, &a.layout)?;
        let p = Painter::new(&chart, &a.layout);
        let s = &a.data.scenario;
        p.obstacles(&s.obstacles, a.margin_m)?;
        p.polygons(&s.polygons, a.margin_m)?;
        for m in &s.moving {
            p.route(m)?;
        }
        p.faint_centre_path(&a.data.centre)?;
        for (pose, color) in [(s.path.start, palette::START), (s.path.goal, palette::GOAL)] {
            p.marker((pose.x_m, pose.y_m), 6.0, fill(solid(color)))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_hold_first_and_last_within_budget() {
        assert_eq!(frame_indices(0, 150), Vec::<usize>::new());
        assert_eq!(frame_indices(5, 150), vec![0, 1, 2, 3, 4]);
        for n in [151, 171, 239, 1000, 200_001] {
            let f = frame_indices(n, 150);
            assert!(f.len() <= 150, "{n}: {}", f.len());
            assert!(f.len() >= 75, "{n}: {}", f.len());
            assert_eq!(f[0], 0);
            assert_eq!(f.last(), Some(&(n - 1)));
            assert!(f.windows(2).all(|w| w[0] < w[1]));
        }
    }
}
