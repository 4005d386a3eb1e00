//! Where a map (a figure in metres) goes on the canvas: equal scale on both axes, room
//! for the header (title and legend) and the axis labels, and the mapping from metres to
//! pixels that plotters applies.

use std::ops::Range;

/// Room around the plotting area, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Margins {
    /// Above the plot (title and legend).
    pub top: u32,
    /// Left of the plot (y tick labels and description).
    pub left: u32,
    /// Below the plot (x tick labels and description).
    pub bottom: u32,
    /// Right of the plot.
    pub right: u32,
}

/// The pixel layout of a map figure.
#[derive(Clone, Debug, PartialEq)]
pub struct MapLayout {
    /// Canvas width, in pixels.
    pub width_px: u32,
    /// Canvas height, in pixels.
    pub height_px: u32,
    /// The x range shown, in metres.
    pub x_m: Range<f64>,
    /// The y range shown, in metres.
    pub y_m: Range<f64>,
    /// Room around the plot.
    pub margins: Margins,
    /// Plotting area width, in pixels.
    pub plot_width_px: u32,
    /// Plotting area height, in pixels.
    pub plot_height_px: u32,
    /// Pixels per metre (the same along both axes).
    pub px_per_m: f64,
}

impl MapLayout {
    /// The largest equal-scale plot of `x_m` by `y_m` that fits in `max_plot_px`
    /// (width, height), with the margins `margins(canvas width)` around it. A canvas
    /// narrower than `min_width_px` is widened, the plot kept centred.
    pub fn fit(
        x_m: Range<f64>,
        y_m: Range<f64>,
        max_plot_px: (u32, u32),
        min_width_px: u32,
        margins: impl Fn(u32) -> Margins,
    ) -> Self {
        let dx = (x_m.end - x_m.start).max(1e-9);
        let dy = (y_m.end - y_m.start).max(1e-9);
        // Plotters maps a range onto pixels first..=last, so `n` pixels span `n - 1` steps.
        let span_w = f64::from(max_plot_px.0.max(2) - 1);
        let span_h = f64::from(max_plot_px.1.max(2) - 1);
        let px_per_m = (span_w / dx).min(span_h / dy);
        let plot_width_px = (dx * px_per_m).round() as u32 + 1;
        let plot_height_px = (dy * px_per_m).round() as u32 + 1;
        let mut m = margins(0);
        let natural = plot_width_px + m.left + m.right;
        if natural < min_width_px {
            let extra = min_width_px - natural;
            m.left += extra / 2;
            m.right += extra - extra / 2;
        }
        let width_px = plot_width_px + m.left + m.right;
        // The header may wrap differently once the width is known.
        let top = margins(width_px).top;
        m.top = top;
        Self {
            width_px,
            height_px: plot_height_px + m.top + m.bottom,
            x_m,
            y_m,
            margins: m,
            plot_width_px,
            plot_height_px,
            px_per_m,
        }
    }

    /// The pixel a point in metres lands on (plotters' own mapping, to the pixel).
    pub fn to_px(&self, x_m: f64, y_m: f64) -> (i32, i32) {
        let fx = (x_m - self.x_m.start) / (self.x_m.end - self.x_m.start);
        let fy = (y_m - self.y_m.start) / (self.y_m.end - self.y_m.start);
        let w = f64::from(self.plot_width_px - 1);
        let h = f64::from(self.plot_height_px - 1);
        let px = self.margins.left as i32 + (w * fx + 1e-3).floor() as i32;
        let py =
            (self.margins.top + self.plot_height_px - 1) as i32 - (h * fy + 1e-3).floor() as i32;
        (px, py)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_scale_and_corners() {
        let fixed = |_| Margins {
            top: 50,
            left: 60,
            bottom: 40,
            right: 20,
        };
        let l = MapLayout::fit(0.0..40.0, 0.0..30.0, (801, 801), 0, fixed);
        assert_eq!(l.plot_width_px, 801);
        assert_eq!(l.plot_height_px, 601);
        assert_eq!(l.width_px, 801 + 80);
        assert_eq!(l.height_px, 601 + 90);
        assert_eq!(l.to_px(0.0, 0.0), (60, 50 + 600));
        assert_eq!(l.to_px(40.0, 30.0), (60 + 800, 50));
        let narrow = MapLayout::fit(0.0..1.0, 0.0..10.0, (801, 801), 400, fixed);
        assert_eq!(narrow.width_px, 400);
        assert_eq!(narrow.margins.left - 60, (400 - 81 - 80) / 2);
    }
}
