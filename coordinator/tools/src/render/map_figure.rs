//! A figure that is one map under a header (the field and formation figures).

use std::ops::Range;

use plotters::coord::Shift;
use plotters::prelude::DrawingArea;

use super::canvas::{Backend, Figure};
use super::header::Header;
use super::layout::{MapLayout, Margins};
use super::palette;
use super::scene::{MAP_BOTTOM_PX, MAP_LEFT_PX, MAP_RIGHT_PX, Painter, map_chart};

/// A figure that is one map under a header: it says its header and layout, and paints
/// the map; the white canvas, the header and the axes are drawn for it.
pub trait MapFigure {
    /// The header above the map.
    fn header(&self) -> &Header;
    /// The canvas and the map's place on it.
    fn map_layout(&self) -> &MapLayout;
    /// Paint the map's content.
    fn paint<DB: Backend>(&self, p: &Painter<'_, '_, DB>) -> anyhow::Result<()>;
}

impl<T: MapFigure> Figure for T {
    fn size_px(&self) -> (u32, u32) {
        let layout = self.map_layout();
        (layout.width_px, layout.height_px)
    }

    fn draw<DB: Backend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        root.fill(&palette::WHITE)?;
        self.header().draw(root)?;
        let chart = map_chart(root, self.map_layout())?;
        self.paint(&Painter::new(&chart, self.map_layout()))
    }
}

/// The layout of a map of `x_m` by `y_m` with `header` above it and the map's margins
/// (axes on the left and at the bottom): as large as fits `max_plot_px`, at least
/// `min_width_px` wide.
pub fn map_layout(
    x_m: Range<f64>,
    y_m: Range<f64>,
    max_plot_px: (u32, u32),
    min_width_px: u32,
    header: &Header,
) -> MapLayout {
    MapLayout::fit(x_m, y_m, max_plot_px, min_width_px, |w| Margins {
        top: header.height_px(w),
        left: MAP_LEFT_PX,
        bottom: MAP_BOTTOM_PX,
        right: MAP_RIGHT_PX,
    })
}
