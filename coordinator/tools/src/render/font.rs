//! The embedded font. Plots draw text with Roboto Regular (Apache-2.0, see
//! `coordinator/tools/assets/fonts/`), compiled into the binary, so rendering needs no system
//! font library and looks the same on every machine.

use std::sync::OnceLock;

use plotters::style::{FontStyle, IntoFont, TextStyle, register_font};

use super::palette;

/// The font family every figure uses. SVG files name it as it stands, so a viewer uses
/// Roboto where it has it and a similar sans-serif face otherwise.
pub const FAMILY: &str = "Roboto, Helvetica, Arial, sans-serif";

/// Roboto Regular, embedded.
const ROBOTO_REGULAR: &[u8] = include_bytes!("../../assets/fonts/Roboto-Regular.ttf");

/// Register the embedded font with plotters (once per process; later calls are free).
pub fn ensure_registered() -> anyhow::Result<()> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            // Also as plain `sans-serif`, the family plotters falls back to.
            [FAMILY, "sans-serif"]
                .into_iter()
                .try_for_each(|family| register_font(family, FontStyle::Normal, ROBOTO_REGULAR))
                .map_err(|_| "the embedded font (Roboto-Regular.ttf) is not a valid font".into())
        })
        .clone()
        .map_err(anyhow::Error::msg)
}

/// Text of `size_px` pixels in the default colour.
pub fn text(size_px: f64) -> TextStyle<'static> {
    (FAMILY, size_px).into_font().color(&palette::BLACK)
}

/// Width and height of `s` in `style`, in pixels (0 when the font cannot measure it).
/// The font is registered first: a layout measured before anything was drawn in this
/// process is the layout drawn (unregistered, the font measured nothing, and a figure
/// sized then came out smaller than the one drawn).
pub fn measure(s: &str, style: &TextStyle<'_>) -> (u32, u32) {
    if ensure_registered().is_err() {
        return (0, 0);
    }
    style.font.box_size(s).unwrap_or((0, 0))
}

/// The embedded face, parsed once, for setting text on bitmaps ([`super::text`]).
pub fn face() -> anyhow::Result<&'static ab_glyph::FontRef<'static>> {
    static FACE: OnceLock<Option<ab_glyph::FontRef<'static>>> = OnceLock::new();
    FACE.get_or_init(|| ab_glyph::FontRef::try_from_slice(ROBOTO_REGULAR).ok())
        .as_ref()
        .ok_or_else(|| {
            anyhow::anyhow!("the embedded font (Roboto-Regular.ttf) is not a valid font")
        })
}
