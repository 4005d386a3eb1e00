//! Streaming RGB frames into an animated GIF that stays small: one global palette built
//! from the figures' own colours (exact inks, their blends towards white and black, and a
//! grey ramp), and each frame after the first stored as the rectangle that changed, its
//! unchanged pixels transparent so they compress to almost nothing.

use std::borrow::Cow;
use std::io::Write;

use anyhow::Context;
use gif::{DisposalMethod, Encoder, Frame, Repeat};

use super::palette;

/// The palette index left transparent (never a colour).
const TRANSPARENT: u8 = 255;
/// Bits per channel of the colour lookup table's key.
const LUT_BITS: u32 = 6;
const UNSET: u8 = 0;

/// The global palette: up to 255 colours; entry 255 is transparent.
struct Palette {
    rgb: Vec<[u8; 3]>,
    /// Nearest palette index + 1 for each quantized colour, `UNSET` until first asked.
    lut: Vec<u8>,
}

impl Palette {
    fn new() -> Self {
        let mut rgb: Vec<[u8; 3]> = Vec::with_capacity(255);
        let mut push = |c: [u8; 3]| {
            if rgb.len() < 255 && !rgb.contains(&c) {
                rgb.push(c);
            }
        };
        // The inks first so they are exact.
        for ink in palette::INKS {
            push([ink.0, ink.1, ink.2]);
        }
        for g in 0..32u32 {
            let v = (g * 255 / 31) as u8;
            push([v, v, v]);
        }
        let blend =
            |a: u8, b: u8, t: f64| (f64::from(a) + (f64::from(b) - f64::from(a)) * t).round() as u8;
        for ink in palette::INKS {
            // Towards white: translucent fills and antialiased edges on the background.
            for k in 1..16 {
                let t = f64::from(k) / 16.0;
                push([
                    blend(ink.0, 255, t),
                    blend(ink.1, 255, t),
                    blend(ink.2, 255, t),
                ]);
            }
            // Towards black: edges against outlines and text.
            for k in 1..5 {
                let t = f64::from(k) / 5.0;
                push([blend(ink.0, 0, t), blend(ink.1, 0, t), blend(ink.2, 0, t)]);
            }
        }
        Self {
            rgb,
            lut: vec![UNSET; 1 << (3 * LUT_BITS)],
        }
    }

    /// The palette index closest to `c` (weighted RGB distance).
    fn index(&mut self, c: [u8; 3]) -> u8 {
        let shift = 8 - LUT_BITS;
        let key = (usize::from(c[0] >> shift) << (2 * LUT_BITS))
            | (usize::from(c[1] >> shift) << LUT_BITS)
            | usize::from(c[2] >> shift);
        let cached = self.lut[key];
        if cached != UNSET {
            return cached - 1;
        }
        let mut best = (u32::MAX, 0u8);
        for (i, p) in self.rgb.iter().enumerate() {
            let d = |a: u8, b: u8| {
                let x = i32::from(a) - i32::from(b);
                (x * x) as u32
            };
            let dist = 2 * d(c[0], p[0]) + 4 * d(c[1], p[1]) + 3 * d(c[2], p[2]);
            if dist < best.0 {
                best = (dist, i as u8);
            }
        }
        self.lut[key] = best.1 + 1;
        best.1
    }

    /// The palette as GIF wants it: 256 RGB triples.
    fn bytes(&self) -> Vec<u8> {
        let mut out: Vec<u8> = self.rgb.iter().flatten().copied().collect();
        out.resize(256 * 3, 255);
        out
    }
}

/// Writes RGB frames of one size as an endlessly looping GIF.
pub struct GifWriter<W: Write> {
    encoder: Encoder<W>,
    palette: Palette,
    width: u16,
    height: u16,
    previous: Option<Vec<u8>>,
}

impl<W: Write> GifWriter<W> {
    /// A GIF of `width` by `height` pixels written to `out`.
    pub fn new(out: W, width: u32, height: u32) -> anyhow::Result<Self> {
        let w = u16::try_from(width).context("GIF wider than 65535 pixels")?;
        let h = u16::try_from(height).context("GIF taller than 65535 pixels")?;
        let palette = Palette::new();
        let mut encoder = Encoder::new(out, w, h, &palette.bytes()).context("starting the GIF")?;
        encoder
            .set_repeat(Repeat::Infinite)
            .context("starting the GIF")?;
        Ok(Self {
            encoder,
            palette,
            width: w,
            height: h,
            previous: None,
        })
    }

    /// Add a frame (`rgb`: 3 bytes a pixel, rows top to bottom) shown for `delay_cs`
    /// hundredths of a second.
    pub fn push(&mut self, rgb: &[u8], delay_cs: u16) -> anyhow::Result<()> {
        let (w, h) = (usize::from(self.width), usize::from(self.height));
        anyhow::ensure!(rgb.len() == w * h * 3, "frame is not {w} x {h} RGB");
        let changed = match &self.previous {
            None => Some((0, 0, w, h)),
            Some(prev) => changed_rect(prev, rgb, w, h),
        };
        let frame = match changed {
            Some((x0, y0, x1, y1)) => {
                let mut buffer = Vec::with_capacity((x1 - x0) * (y1 - y0));
                for y in y0..y1 {
                    for x in x0..x1 {
                        let at = (y * w + x) * 3;
                        let c = [rgb[at], rgb[at + 1], rgb[at + 2]];
                        let same = self.previous.as_ref().is_some_and(|p| p[at..at + 3] == c);
                        buffer.push(if same {
                            TRANSPARENT
                        } else {
                            self.palette.index(c)
                        });
                    }
                }
                Frame {
                    left: x0 as u16,
                    top: y0 as u16,
                    width: (x1 - x0) as u16,
                    height: (y1 - y0) as u16,
                    buffer: Cow::Owned(buffer),
                    ..Frame::default()
                }
            }
            // Nothing changed: a single transparent pixel carries the delay.
            None => Frame {
                width: 1,
                height: 1,
                buffer: Cow::Owned(vec![TRANSPARENT]),
                ..Frame::default()
            },
        };
        let frame = Frame {
            delay: delay_cs,
            dispose: DisposalMethod::Keep,
            transparent: Some(TRANSPARENT),
            ..frame
        };
        self.encoder
            .write_frame(&frame)
            .context("encoding a GIF frame")?;
        match &mut self.previous {
            Some(prev) => prev.copy_from_slice(rgb),
            None => self.previous = Some(rgb.to_vec()),
        }
        Ok(())
    }

    /// Finish the file and hand back the writer.
    pub fn finish(self) -> anyhow::Result<W> {
        self.encoder.into_inner().context("finishing the GIF")
    }
}

/// The smallest rectangle `[x0, x1) x [y0, y1)` holding every pixel that differs.
fn changed_rect(a: &[u8], b: &[u8], w: usize, h: usize) -> Option<(usize, usize, usize, usize)> {
    let row = |y: usize| y * w * 3..(y + 1) * w * 3;
    let y0 = (0..h).find(|&y| a[row(y)] != b[row(y)])?;
    let y1 = (y0..h).rev().find(|&y| a[row(y)] != b[row(y)])? + 1;
    let (mut x0, mut x1) = (w, 0);
    for y in y0..y1 {
        let (ra, rb) = (&a[row(y)], &b[row(y)]);
        if let Some(first) = (0..w).find(|&x| ra[x * 3..x * 3 + 3] != rb[x * 3..x * 3 + 3]) {
            x0 = x0.min(first);
            let last = (first..w)
                .rev()
                .find(|&x| ra[x * 3..x * 3 + 3] != rb[x * 3..x * 3 + 3])
                .unwrap_or(first);
            x1 = x1.max(last + 1);
        }
    }
    Some((x0, y0, x1, y1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inks_are_exact_and_changed_rect_is_tight() {
        let mut p = Palette::new();
        assert!(p.rgb.len() <= 255);
        let o = palette::ORANGE;
        let i = p.index([o.0, o.1, o.2]);
        assert_eq!(p.rgb[usize::from(i)], [o.0, o.1, o.2]);
        let w = 5;
        let a = vec![0u8; w * 4 * 3];
        let mut b = a.clone();
        b[(2 * w + 3) * 3] = 9;
        b[(w + 1) * 3 + 2] = 9;
        assert_eq!(changed_rect(&a, &b, w, 4), Some((1, 1, 4, 3)));
        assert_eq!(changed_rect(&a, &a, w, 4), None);
    }
}
