//! The header every figure carries above its plot (title, subtitle, legend), the legend
//! entries of the maps, and the titles naming what a run's model adds to the paper's.

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::{RGBAColor, TextStyle};
use shared::control::vocabulary::TurnMode;
use shared::world::scenario::Scenario;

use super::canvas::Backend;
use super::font;
use super::geom;
use super::palette;
use super::scene::{alpha, fill, fmt_m, line, solid};

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
            "unknown to the controller",
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
pub fn obstacle_legend(scenario: &shared::world::scenario::Scenario) -> (f64, Vec<LegendItem>) {
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
    match s.turns {
        TurnMode::Parallel => parts.push("parallel turns".to_string()),
        TurnMode::Simultaneous => parts.push("simultaneous turns".to_string()),
        TurnMode::Sequential => {}
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
