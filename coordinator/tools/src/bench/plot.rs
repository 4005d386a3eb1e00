//! The benchmark's latency histogram (SVG): one panel per formation size, log-spaced
//! bins, each series normalised to a fraction of its own samples so that a few thousand
//! turns and a few thousand round trips compare at a glance.

use anyhow::Context;
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::{
    ChartBuilder, ChartContext, Circle, DrawingArea, IntoDrawingArea, IntoLogRange, LineSeries,
    PathElement, SVGBackend, SeriesLabelPosition,
};
use plotters::style::{Color, IntoFont, RGBColor, WHITE};

use crate::render::font;
use runner::stats::Distribution;

/// One series of a panel.
pub struct Series<'a> {
    /// Legend text.
    pub label: String,
    /// Samples, microseconds.
    pub values_us: &'a [f64],
    /// Colour.
    pub color: RGBColor,
}

/// One panel: a title and its series.
pub struct Panel<'a> {
    /// Panel title.
    pub title: String,
    /// The series drawn.
    pub series: Vec<Series<'a>>,
}

/// Okabe-Ito colours.
pub const GREY: RGBColor = RGBColor(120, 120, 120);
/// Okabe-Ito blue.
pub const BLUE: RGBColor = RGBColor(0, 114, 178);
/// Okabe-Ito bluish green.
pub const GREEN: RGBColor = RGBColor(0, 158, 115);
/// Okabe-Ito vermillion.
pub const VERMILLION: RGBColor = RGBColor(213, 94, 0);
/// Okabe-Ito orange.
pub const ORANGE: RGBColor = RGBColor(230, 159, 0);
/// Okabe-Ito sky blue.
pub const SKY: RGBColor = RGBColor(86, 180, 233);
/// Okabe-Ito reddish purple.
pub const PURPLE: RGBColor = RGBColor(204, 121, 167);

const BINS: usize = 60;
const PANEL_W: u32 = 960;
const PANEL_H: u32 = 340;

/// Draw `panels` as one SVG document.
pub fn histogram_svg(panels: &[Panel<'_>]) -> anyhow::Result<String> {
    stacked_svg(panels, |panel, area| draw_panel(panel, area))
}

/// `items` drawn one above the other by `draw`, each in a [`PANEL_W`] x [`PANEL_H`]
/// area, as one SVG document.
fn stacked_svg<T>(
    items: &[T],
    draw: impl Fn(&T, &DrawingArea<SVGBackend<'_>, Shift>) -> anyhow::Result<()>,
) -> anyhow::Result<String> {
    font::ensure_registered()?;
    let mut svg = String::new();
    {
        let height = PANEL_H * items.len().max(1) as u32;
        let root = SVGBackend::with_string(&mut svg, (PANEL_W, height)).into_drawing_area();
        root.fill(&WHITE).context("filling the background")?;
        let areas = root.split_evenly((items.len().max(1), 1));
        for (item, area) in items.iter().zip(&areas) {
            draw(item, area)?;
        }
        root.present().context("finishing the SVG")?;
    }
    Ok(svg)
}

fn draw_panel<DB: plotters::prelude::DrawingBackend>(
    panel: &Panel<'_>,
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    // Range: from the smallest sample to the largest p99.9 (the far tail is cut off;
    // the table and the JSON give the maximum).
    let lo = panel
        .series
        .iter()
        .flat_map(|s| s.values_us.iter().copied())
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    let hi = panel
        .series
        .iter()
        .map(|s| Distribution::of(s.values_us).p999)
        .fold(0.0, f64::max);
    if !lo.is_finite() || hi <= lo {
        return Ok(());
    }
    let (lo, hi) = (lo * 0.9, hi * 1.1);
    let edges: Vec<f64> = (0..=BINS)
        .map(|k| lo * (hi / lo).powf(k as f64 / BINS as f64))
        .collect();
    let histograms: Vec<Vec<(f64, f64)>> = panel
        .series
        .iter()
        .map(|s| step_outline(&edges, s.values_us))
        .collect();
    let ymax = histograms
        .iter()
        .flatten()
        .map(|p| p.1)
        .fold(0.0, f64::max)
        .max(1e-3)
        * 1.1;
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (font::FAMILY, 18).into_font())
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((lo..hi).log_scale(), 0.0..ymax)
        .context("laying out the chart")?;
    chart
        .configure_mesh()
        .x_labels(16)
        .x_label_formatter(&|v| format!("{v:.0}"))
        .x_desc("latency, microseconds (log scale)")
        .y_desc("fraction of samples")
        .label_style((font::FAMILY, 13).into_font())
        .axis_desc_style((font::FAMILY, 14).into_font())
        .light_line_style(WHITE)
        .draw()
        .context("drawing the axes")?;
    for (s, points) in panel.series.iter().zip(histograms) {
        let color = s.color;
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))
            .with_context(|| format!("drawing {}", s.label))?
            .label(&s.label)
            .legend(legend_line(color));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
}

/// A legend entry: a short line in `color`.
fn legend_line(color: RGBColor) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
}

/// Draw `chart`'s legend at `position`, the same in every plot of the bench.
fn draw_legend<'a, DB: plotters::prelude::DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .position(position)
        .label_font((font::FAMILY, 13).into_font())
        .background_style(WHITE.mix(0.85))
        .border_style(GREY)
        .draw()
        .context("drawing the legend")
}

/// One curve of a plot against the number of agents.
pub struct Curve {
    /// Legend text.
    pub label: String,
    /// (agents, value) points, in the order measured.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
}

/// A chart of `curves` against the number of agents, both axes logarithmic: `title`
/// above, `y_desc` along the value axis.
pub struct ScaleChart {
    /// Chart title.
    pub title: String,
    /// What the values are, with their unit.
    pub y_desc: String,
    /// The curves.
    pub curves: Vec<Curve>,
}

/// Draw `charts` one above the other as one SVG document (the bench's `--scale` plot).
#[allow(
    clippy::redundant_closure,
    reason = "the function itself is not general enough over the SVG backend's lifetime"
)]
pub fn scale_svg(charts: &[ScaleChart]) -> anyhow::Result<String> {
    stacked_svg(charts, |chart, area| draw_scale_chart(chart, area))
}

fn draw_scale_chart<DB: plotters::prelude::DrawingBackend>(
    c: &ScaleChart,
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let positive = || {
        c.curves
            .iter()
            .flat_map(|k| k.points.iter().copied())
            .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
    };
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (x, y) in positive() {
        (x_lo, x_hi, y_lo, y_hi) = (x_lo.min(x), x_hi.max(x), y_lo.min(y), y_hi.max(y));
    }
    if !x_lo.is_finite() || !y_lo.is_finite() {
        return Ok(());
    }
    let mut chart = ChartBuilder::on(area)
        .caption(&c.title, (font::FAMILY, 18).into_font())
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x_lo * 0.8..x_hi * 1.25).log_scale(),
            (y_lo * 0.7..y_hi * 1.5).log_scale(),
        )
        .context("laying out the chart")?;
    chart
        .configure_mesh()
        .x_desc("agents (log scale)")
        .y_desc(&c.y_desc)
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.3}"))
        .label_style((font::FAMILY, 13).into_font())
        .axis_desc_style((font::FAMILY, 14).into_font())
        .light_line_style(WHITE)
        .draw()
        .context("drawing the axes")?;
    for k in &c.curves {
        let color = k.color;
        let points: Vec<(f64, f64)> = k
            .points
            .iter()
            .copied()
            .filter(|(x, y)| *x > 0.0 && *y > 0.0 && y.is_finite())
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
            .with_context(|| format!("drawing {}", k.label))?
            .label(&k.label)
            .legend(legend_line(color));
        chart
            .draw_series(
                points
                    .into_iter()
                    .map(|p| Circle::new(p, 4, color.filled())),
            )
            .with_context(|| format!("drawing the points of {}", k.label))?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// The histogram of `values` over `edges` as a step outline: fraction of all values per
/// bin (values outside the edges count in the total but are not drawn).
fn step_outline(edges: &[f64], values: &[f64]) -> Vec<(f64, f64)> {
    let bins = edges.len() - 1;
    let mut counts = vec![0usize; bins];
    for &v in values {
        if let Some(k) = edges.windows(2).position(|w| v >= w[0] && v < w[1]) {
            counts[k] += 1;
        }
    }
    let total = values.len().max(1) as f64;
    let mut points = Vec::with_capacity(2 * bins + 2);
    points.push((edges[0], 0.0));
    for (k, &c) in counts.iter().enumerate() {
        let f = c as f64 / total;
        points.push((edges[k], f));
        points.push((edges[k + 1], f));
    }
    points.push((edges[bins], 0.0));
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_outline_holds_every_value_in_range() {
        let edges = [1.0, 2.0, 4.0, 8.0];
        let pts = step_outline(&edges, &[1.5, 3.0, 3.5, 100.0]);
        assert_eq!(pts.len(), 8);
        assert_eq!(pts[1], (1.0, 0.25));
        assert_eq!(pts[3], (2.0, 0.5));
    }

    #[test]
    fn a_scale_chart_draws_every_curve() {
        let svg = scale_svg(&[ScaleChart {
            title: "test".into(),
            y_desc: "seconds".into(),
            curves: vec![
                Curve {
                    label: "start-up".into(),
                    points: vec![(100.0, 0.3), (300.0, 0.9), (1000.0, 2.8)],
                    color: BLUE,
                },
                Curve {
                    label: "floor".into(),
                    points: vec![(100.0, 0.07), (300.0, 0.2), (1000.0, 0.7)],
                    color: GREY,
                },
            ],
        }])
        .unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..200]);
        assert_eq!(svg.matches("<circle").count(), 6, "a marker per point");
        assert!(svg.contains("start-up") && svg.contains("floor"));
    }

    #[test]
    fn an_svg_document_is_drawn() {
        let a: Vec<f64> = (1..500).map(|k| 10.0 + f64::from(k % 37)).collect();
        let b: Vec<f64> = (1..500).map(|k| 30.0 + f64::from(k % 11)).collect();
        let svg = histogram_svg(&[Panel {
            title: "test".into(),
            series: vec![
                Series {
                    label: "a".into(),
                    values_us: &a,
                    color: BLUE,
                },
                Series {
                    label: "b".into(),
                    values_us: &b,
                    color: VERMILLION,
                },
            ],
        }])
        .unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("polyline"),
            "{}",
            &svg[..200]
        );
    }
}
