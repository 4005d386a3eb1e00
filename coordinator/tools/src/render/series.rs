//! Time series over the steps: each agent's deviation with the formation's mean (the
//! paper's Fig. 9), and the smallest agent-agent and agent-obstacle clearances against
//! the zero line (the safety proof at a glance). Faults are marked on the step axis.

use plotters::coord::Shift;
use plotters::prelude::{ChartBuilder, DrawingArea, PathElement, Rectangle, Text};
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{Backend, Figure};
use super::data::{FaultRecord, RunData};
use super::font;
use super::geom::{View, Xy};
use super::header::{self, Header, LegendItem, Swatch};
use super::metrics::{self, StepMetrics};
use super::palette;
use super::scene::{alpha, fill, fmt_m, line, solid};

/// Canvas width of a time series, in pixels.
pub const WIDTH_PX: u32 = 1200;
/// Plotting area height of a time series, in pixels.
const PLOT_HEIGHT_PX: u32 = 420;
const LEFT_PX: u32 = 78;
const BOTTOM_PX: u32 = 50;
const RIGHT_PX: u32 = 30;
/// At most this many faults are labelled on the axis (all are marked).
const FAULT_LABELS: usize = 12;

/// One curve: points (step, value) in metres, broken where there is no value.
struct Curve {
    points: Vec<Option<Xy>>,
    color: plotters::style::RGBAColor,
    width: u32,
}

/// A time series figure over the steps of a run.
pub struct SeriesFigure<'a> {
    header: Header,
    y_desc: &'static str,
    x_range: (f64, f64),
    y_range: (f64, f64),
    curves: Vec<Curve>,
    /// Draw the zero line and the shaded region below it.
    zero_line: bool,
    faults: &'a [FaultRecord],
}

fn fault_legend(faults: &[FaultRecord]) -> Option<LegendItem> {
    (!faults.is_empty()).then(|| {
        LegendItem::new(
            Swatch::Line {
                color: solid(palette::FAULT),
                width: 2,
                dashed: true,
            },
            format!("faults ({})", faults.len()),
        )
    })
}

fn x_range(data: &RunData) -> (f64, f64) {
    (0.0, (data.last_step() as f64).max(1.0))
}

impl<'a> SeriesFigure<'a> {
    /// The deviation figure: each live agent's distance from its slot, and the mean.
    pub fn deviation(data: &'a RunData, metrics: &[StepMetrics]) -> Self {
        let n = data.scenario.agents.len();
        let (agent_alpha, agent_width) = match n {
            0..=8 => (0.85, 2),
            9..=30 => (0.6, 1),
            _ => (0.3, 1),
        };
        let mut curves: Vec<Curve> = (0..n)
            .map(|i| Curve {
                points: data
                    .steps
                    .iter()
                    .map(|s| {
                        let a = &s.agents[i];
                        (a.alive && a.deviation_m.is_finite())
                            .then_some((s.step as f64, a.deviation_m))
                    })
                    .collect(),
                color: alpha(palette::DEVIATION_AGENT, agent_alpha),
                width: agent_width,
            })
            .collect();
        curves.push(Curve {
            points: metrics
                .iter()
                .map(|m| m.mean_deviation_m.map(|v| (m.step as f64, v)))
                .collect(),
            color: solid(palette::DEVIATION_MEAN),
            width: 3,
        });
        let max = curves
            .iter()
            .flat_map(|c| c.points.iter().flatten().map(|p| p.1))
            .fold(0.0, f64::max);
        let worst = data
            .steps
            .iter()
            .flat_map(|s| {
                s.agents
                    .iter()
                    .enumerate()
                    .map(move |(i, a)| (s.step, i, a))
            })
            .filter(|(_, _, a)| a.alive)
            .max_by(|a, b| a.2.deviation_m.total_cmp(&b.2.deviation_m));
        let mean_of_means = {
            let v: Vec<f64> = metrics.iter().filter_map(|m| m.mean_deviation_m).collect();
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let mut legend = vec![
            LegendItem::new(
                Swatch::Line {
                    color: alpha(palette::DEVIATION_AGENT, agent_alpha.max(0.6)),
                    width: 2,
                    dashed: false,
                },
                format!("each agent ({n})"),
            ),
            LegendItem::new(
                Swatch::Line {
                    color: solid(palette::DEVIATION_MEAN),
                    width: 3,
                    dashed: false,
                },
                "formation mean",
            ),
        ];
        legend.extend(fault_legend(&data.faults));
        let header = Header {
            title: header::title(
                format!("{}: deviation from the formation slots", data.scenario.name),
                &data.scenario,
            ),
            subtitle: Some(format!(
                "distance ||x_i - x_i*|| of each live agent from its ideal slot; mean over the run {} m{}",
                fmt_m4(mean_of_means),
                worst.map_or(String::new(), |(step, i, a)| format!(
                    ", largest {} m (agent {i}, step {step})",
                    fmt_m4(a.deviation_m)
                )),
            )),
            legend,
        };
        Self {
            header,
            y_desc: "deviation (m)",
            x_range: x_range(data),
            y_range: (0.0, (max * 1.08).max(0.05)),
            curves,
            zero_line: false,
            faults: &data.faults,
        }
    }

    /// The clearance figure: the smallest agent-agent and agent-obstacle clearance at
    /// every step, with the zero line below which bodies would overlap.
    pub fn clearance(data: &'a RunData, metrics: &[StepMetrics]) -> Self {
        let agents = Curve {
            points: metrics
                .iter()
                .map(|m| m.agent_clearance_m.map(|v| (m.step as f64, v)))
                .collect(),
            color: solid(palette::CLEARANCE_AGENTS),
            width: 2,
        };
        let obstacles = Curve {
            points: metrics
                .iter()
                .map(|m| m.obstacle_clearance_m.map(|v| (m.step as f64, v)))
                .collect(),
            color: solid(palette::CLEARANCE_OBSTACLES),
            width: 2,
        };
        let values = || {
            [&agents, &obstacles]
                .into_iter()
                .flat_map(|c| c.points.iter().flatten().map(|p| p.1))
        };
        let max = values().fold(0.0, f64::max);
        let min = values().fold(f64::INFINITY, f64::min);
        // Far-away obstacles would squash the interesting part near zero: cut the axis
        // at a few agent diameters (the curves' minima are in the legend in any case).
        let diameter = 2.0
            * data
                .scenario
                .agents
                .iter()
                .map(|a| a.radius_m)
                .fold(0.0, f64::max);
        let cap = (8.0 * diameter).max(1.0);
        let hi = (max * 1.05).clamp(0.1, cap.max(min * 2.0));
        let lo = if min.is_finite() {
            (min - 0.05 * hi).min(-0.06 * hi)
        } else {
            -0.06 * hi
        };
        let describe =
            |name: &str, f: fn(&StepMetrics) -> Option<f64>| match metrics::lowest(metrics, f) {
                Some((step, v)) => format!("{name}: min {} m (step {step})", fmt_m4(v)),
                None => format!("{name}: none"),
            };
        let mut legend = vec![
            LegendItem::new(
                Swatch::Line {
                    color: solid(palette::CLEARANCE_AGENTS),
                    width: 2,
                    dashed: false,
                },
                describe("agent-agent", |m| m.agent_clearance_m),
            ),
            LegendItem::new(
                Swatch::Line {
                    color: solid(palette::CLEARANCE_OBSTACLES),
                    width: 2,
                    dashed: false,
                },
                describe("agent-obstacle", |m| m.obstacle_clearance_m),
            ),
            LegendItem::new(
                Swatch::Band {
                    color: alpha(palette::COLLISION, 0.18),
                },
                "overlap (< 0)",
            ),
        ];
        legend.extend(fault_legend(&data.faults));
        let overlaps = metrics
            .iter()
            .filter(|m| {
                m.agent_clearance_m.is_some_and(|v| v < 0.0)
                    || m.obstacle_clearance_m.is_some_and(|v| v < 0.0)
            })
            .count();
        let header = Header {
            title: header::title(
                format!("{}: minimum clearance per step", data.scenario.name),
                &data.scenario,
            ),
            subtitle: Some(format!(
                "distance minus both radii, from the recorded positions; {}{}",
                if overlaps == 0 {
                    "never below zero: no two bodies overlapped".to_string()
                } else {
                    format!("below zero in {overlaps} steps")
                },
                if max * 1.05 > hi {
                    format!("; axis cut at {} m", fmt_m(hi))
                } else {
                    String::new()
                },
            )),
            legend,
        };
        Self {
            header,
            y_desc: "clearance (m)",
            x_range: x_range(data),
            y_range: (lo, hi),
            curves: vec![agents, obstacles],
            zero_line: true,
            faults: &data.faults,
        }
    }
}

/// A length to 4 decimals (clearances near zero need them).
fn fmt_m4(v: f64) -> String {
    format!("{v:.4}")
}

impl Figure for SeriesFigure<'_> {
    fn size_px(&self) -> (u32, u32) {
        (
            WIDTH_PX,
            self.header.height_px(WIDTH_PX) + PLOT_HEIGHT_PX + BOTTOM_PX,
        )
    }

    fn draw<DB: Backend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        root.fill(&palette::WHITE)?;
        self.header.draw(root)?;
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range;
        let mut chart = ChartBuilder::on(root)
            .margin_top(self.header.height_px(WIDTH_PX))
            .margin_right(RIGHT_PX)
            .y_label_area_size(LEFT_PX)
            .x_label_area_size(BOTTOM_PX)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("step")
            .y_desc(self.y_desc)
            .label_style(font::text(14.0))
            .axis_desc_style(font::text(15.0))
            .bold_line_style(line(solid(palette::GRID), 1))
            .light_line_style(line(alpha(palette::GRID, 0.0), 0))
            .axis_style(line(solid(palette::TEXT_MUTED), 1))
            .x_labels((x1 as usize + 1).min(12))
            .y_labels(8)
            // Steps are whole numbers: no label on a fractional tick.
            .x_label_formatter(&|v| {
                if v.fract() == 0.0 {
                    format!("{v:.0}")
                } else {
                    String::new()
                }
            })
            .draw()?;
        let area = chart.plotting_area();
        let view = View { x0, x1, y0, y1 };
        if self.zero_line {
            area.draw(&Rectangle::new(
                [(x0, y0), (x1, 0.0f64.min(y1))],
                fill(alpha(palette::COLLISION, 0.18)),
            ))?;
        }
        for (k, f) in self.faults.iter().enumerate() {
            let x = f.step as f64;
            if x < x0 || x > x1 {
                continue;
            }
            area.draw(&plotters::element::DashedPathElement::new(
                vec![(x, y0), (x, y1)],
                6,
                4,
                line(solid(palette::FAULT), 2),
            ))?;
            if k < FAULT_LABELS {
                let label = if k + 1 == FAULT_LABELS && self.faults.len() > FAULT_LABELS {
                    format!("… +{} more", self.faults.len() - k)
                } else {
                    format!("agent {} {}", f.agent, f.kind)
                };
                let dy = (y1 - y0) * (0.03 + 0.055 * (k % 6) as f64);
                area.draw(&Text::new(
                    label,
                    (x + (x1 - x0) * 0.004, y1 - dy),
                    font::text(13.0)
                        .color(&palette::FAULT)
                        .pos(Pos::new(HPos::Left, VPos::Top)),
                ))?;
            }
        }
        if self.zero_line && y0 <= 0.0 && y1 >= 0.0 {
            area.draw(&PathElement::new(
                vec![(x0, 0.0), (x1, 0.0)],
                line(solid(palette::BLACK), 1),
            ))?;
        }
        for c in &self.curves {
            for run in c.points.split(Option::is_none) {
                let pts: Vec<Xy> = run.iter().flatten().copied().collect();
                for piece in view.clip_polyline(&pts) {
                    area.draw(&PathElement::new(piece, line(c.color, c.width)))?;
                }
            }
        }
        Ok(())
    }
}
