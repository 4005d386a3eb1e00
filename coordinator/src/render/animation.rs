//! The animation of a whole run (the paper's video, and its Fig. 8 at every step): the
//! obstacles, the centre path, every agent with its safety circle, its ideal slot and the
//! path it took to its best point, and the current step. Long runs are subsampled to at
//! most [`MAX_FRAMES`] frames so the GIF stays a few megabytes.

use std::io::Write;

use plotters::coord::Shift;
use plotters::prelude::{BitMapBackend, DrawingArea, IntoDrawingArea, Text};

use super::canvas::{self, Backend, Figure};
use super::data::RunData;
use super::geom::Xy;
use super::gif_writer::GifWriter;
use super::layout::{MapLayout, Margins};
use super::metrics::StepMetrics;
use super::palette;
use super::scene::{
    self, Header, LegendItem, MAP_BOTTOM_PX, MAP_LEFT_PX, MAP_RIGHT_PX, Painter, Swatch, alpha,
    fill, line, solid,
};
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
    layout: MapLayout,
    margin_m: f64,
    frames: Vec<usize>,
}

impl<'a> Animation<'a> {
    /// Lay out the animation of `data` (`metrics` from [`super::metrics::per_step`]).
    pub fn new(data: &'a RunData, metrics: &'a [StepMetrics]) -> Self {
        let s = &data.scenario;
        let (margin_m, mut legend) = scene::obstacle_legend(s);
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
            title: format!("{}: formation run", s.name),
            // Written per frame; reserve its row.
            subtitle: Some(String::new()),
            legend,
        };
        let layout = MapLayout::fit(
            0.0..s.field.width_m,
            0.0..s.field.height_m,
            MAX_PLOT_PX,
            super::field::MIN_WIDTH_PX,
            |w| Margins {
                top: header.height_px(w),
                left: MAP_LEFT_PX,
                bottom: MAP_BOTTOM_PX,
                right: MAP_RIGHT_PX,
            },
        );
        Self {
            data,
            metrics,
            header,
            layout,
            margin_m,
            frames: frame_indices(data.steps.len(), MAX_FRAMES),
        }
    }

    /// The frames' layout.
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

    fn size_px(&self) -> (u32, u32) {
        (self.layout.width_px, self.layout.height_px)
    }

    /// What changes from frame to frame.
    fn draw_frame<DB: Backend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        k: usize,
    ) -> anyhow::Result<()> {
        let chart = scene::map_chart_bare(root, &self.layout)?;
        let p = Painter::new(&chart, &self.layout);
        let steps = &self.data.steps;
        let Some(&at) = self.frames.get(k) else {
            anyhow::bail!("no frame {k}");
        };
        let step = &steps[at];

        // The centre so far.
        let travelled: Vec<Xy> = self
            .data
            .centre
            .iter()
            .take_while(|c| c.step <= step.step)
            .map(|c| (c.pose.x_m, c.pose.y_m))
            .collect();
        p.polyline(&travelled, line(solid(palette::CENTRE_PATH), 2))?;

        let px = self.layout.px_per_m;
        let radii: Vec<f64> = self
            .data
            .scenario
            .agents
            .iter()
            .map(|a| a.radius_m)
            .collect();
        let small = radii.iter().fold(f64::INFINITY, |m, &r| m.min(r)) * px < 3.0;
        // Each agent's path to its best point in this step.
        let move_width = if small { 1 } else { 2 };
        for a in &step.agents {
            if a.path.len() > 1 {
                let pts: Vec<Xy> = a.path.iter().map(|q| (q.x, q.y)).collect();
                p.polyline(&pts, line(solid(palette::MOVE), move_width))?;
            }
        }
        // Ideal slots.
        for (a, &r) in step.agents.iter().zip(&radii) {
            if !a.alive {
                continue;
            }
            let c = (a.slot.x, a.slot.y);
            if small {
                p.marker(c, 1.0, fill(alpha(palette::SLOT, 0.8)))?;
            } else {
                p.disk(c, r, None, Some(line(solid(palette::SLOT), 1)))?;
            }
        }
        // Agents with their safety circles.
        for (a, &r) in step.agents.iter().zip(&radii) {
            let c = (a.position.x, a.position.y);
            let (body, edge) = if a.alive {
                (alpha(palette::AGENT, 0.6), solid(palette::AGENT_EDGE))
            } else {
                (solid(palette::AGENT_DEAD), solid(palette::BLACK))
            };
            if small {
                p.disk(
                    c,
                    r.max(p.m(1.5)),
                    Some(fill(solid(if a.alive {
                        palette::AGENT
                    } else {
                        palette::AGENT_DEAD
                    }))),
                    None,
                )?;
            } else {
                p.disk(c, r, Some(fill(body)), Some(line(edge, 1)))?;
            }
        }
        // The centre's pose now.
        if let Some(pose) = self.data.centre_at(step.step) {
            p.arrow(
                (pose.x_m, pose.y_m),
                pose.heading_rad,
                22.0,
                solid(palette::CENTRE_PATH),
                2,
            )?;
        }

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
        let text = format!(
            "step {} of {}   mean deviation {mean}   min clearance {clear}{}",
            step.step,
            self.data.last_step(),
            if dead > 0 {
                format!("   {dead} dead")
            } else {
                String::new()
            }
        );
        let (origin, style) = Header::subtitle_place();
        root.draw(&Text::new(text, origin, style))?;
        Ok(())
    }
}

/// The static layer of every frame: header, axes, obstacles, the whole centre path, the
/// start and goal.
struct Background<'b, 'a>(&'b Animation<'a>);

impl Figure for Background<'_, '_> {
    fn size_px(&self) -> (u32, u32) {
        self.0.size_px()
    }

    fn draw<DB: Backend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let a = self.0;
        root.fill(&palette::WHITE)?;
        a.header.draw(root)?;
        let chart = scene::map_chart(root, &a.layout)?;
        let p = Painter::new(&chart, &a.layout);
        let s = &a.data.scenario;
        p.obstacles(&s.obstacles, a.margin_m)?;
        let path: Vec<Xy> = a
            .data
            .centre
            .iter()
            .map(|c| (c.pose.x_m, c.pose.y_m))
            .collect();
        p.polyline(&path, line(alpha(palette::CENTRE_PATH, 0.3), 2))?;
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
