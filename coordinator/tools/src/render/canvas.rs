//! Output targets: one figure drawn twice, onto a bitmap (saved as PNG) and onto SVG.

use std::path::{Path, PathBuf};

use anyhow::Context;
use plotters::coord::Shift;
use plotters::prelude::{BitMapBackend, DrawingArea, DrawingBackend, IntoDrawingArea, SVGBackend};

use super::text::TextSetter;
use runner::output::write_atomically;

/// A plotters backend whose errors can travel in an [`anyhow::Error`].
pub trait Backend: DrawingBackend<ErrorType: 'static> {}

impl<T: DrawingBackend<ErrorType: 'static>> Backend for T {}

/// A figure that can draw itself onto any backend.
pub trait Figure {
    /// Canvas size (width, height), in pixels.
    fn size_px(&self) -> (u32, u32);
    /// Draw the whole figure onto `root` (already the canvas size).
    fn draw<DB: Backend>(&self, root: &DrawingArea<DB, Shift>) -> anyhow::Result<()>;
}

/// Draw `figure` into an RGB buffer (3 bytes a pixel, rows top to bottom).
pub fn render_rgb(figure: &impl Figure) -> anyhow::Result<Vec<u8>> {
    let (w, h) = figure.size_px();
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    {
        let root =
            TextSetter::new(BitMapBackend::with_buffer(&mut rgb, (w, h))).into_drawing_area();
        figure.draw(&root)?;
        root.present()?;
    }
    Ok(rgb)
}

/// Draw `figure` as an SVG document.
pub fn render_svg(figure: &impl Figure) -> anyhow::Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, figure.size_px()).into_drawing_area();
        figure.draw(&root)?;
        root.present()?;
    }
    Ok(svg)
}

/// Encode an RGB buffer of `w` by `h` pixels as PNG.
pub fn encode_png(rgb: &[u8], w: u32, h: u32) -> anyhow::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Balanced);
    let mut writer = encoder.write_header().context("encoding PNG")?;
    writer.write_image_data(rgb).context("encoding PNG")?;
    writer.finish().context("encoding PNG")?;
    Ok(out)
}

/// Write `figure` as `dir/stem.png` and `dir/stem.svg`; returns both paths.
pub fn write_figure(dir: &Path, stem: &str, figure: &impl Figure) -> anyhow::Result<Vec<PathBuf>> {
    let (w, h) = figure.size_px();
    let rgb = render_rgb(figure).with_context(|| format!("drawing {stem}.png"))?;
    let png_path = dir.join(format!("{stem}.png"));
    write_atomically(&png_path, &encode_png(&rgb, w, h)?)?;
    let svg = render_svg(figure).with_context(|| format!("drawing {stem}.svg"))?;
    let svg_path = dir.join(format!("{stem}.svg"));
    write_atomically(&svg_path, svg.as_bytes())?;
    Ok(vec![png_path, svg_path])
}
