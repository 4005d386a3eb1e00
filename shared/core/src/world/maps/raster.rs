//! The map's image: a binary or plain PGM (`P5`, `P2`) read here, or a PNG (the `png`
//! crate), as samples per pixel from the top row down, checked against its header.

use std::path::Path;

use super::{MAX_MAP_CELLS, MapError};
use crate::input_file::{Links, read_input};

/// Most bytes of a map image file (a plain PGM of [`MAX_MAP_CELLS`] takes up to six
/// bytes a cell).
pub const MAX_IMAGE_BYTES: u64 = 256 * 1024 * 1024;

/// An image as read: `channels` samples per pixel, rows from the top down.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Raster {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The value of a full sample (PGM's maxval; 255 or 65535 for a PNG).
    pub max_value: u16,
    /// Samples per pixel: 1 grey, 2 grey and alpha, 3 RGB, 4 RGBA.
    pub channels: usize,
    /// `width * height * channels` samples, row by row from the top one.
    pub samples: Vec<u16>,
}

impl Raster {
    /// Whether the last sample of each pixel is an alpha channel.
    pub fn has_alpha(&self) -> bool {
        self.channels == 2 || self.channels == 4
    }

    /// The samples of the pixel in column `x` of row `row` (row 0 the top one).
    pub fn pixel(&self, x: usize, row: usize) -> &[u16] {
        let at = (row * self.width + x) * self.channels;
        &self.samples[at..at + self.channels]
    }

    /// Read the PGM or PNG file at `path` (told apart by their first bytes).
    pub fn read(path: &Path) -> Result<Self, MapError> {
        let file = path.display().to_string();
        let fail = |reason: String| MapError::Image {
            file: file.clone(),
            reason,
        };
        let bytes =
            read_input(path, MAX_IMAGE_BYTES, Links::Follow).map_err(|e| fail(e.to_string()))?;
        Self::decode(&bytes).map_err(fail)
    }

    /// Decode a PGM or PNG image held in memory; the error is the reason alone.
    ///
    /// ```
    /// use shared::world::maps::Raster;
    /// let pgm = b"P5\n# two by one\n2 1\n255\n\x00\xfe";
    /// let r = Raster::decode(pgm).unwrap();
    /// assert_eq!((r.width, r.height, r.samples.as_slice()), (2, 1, &[0u16, 254][..]));
    /// // A header that promises more than the data holds is refused.
    /// assert!(Raster::decode(b"P5 3 1 255\n\x00\xfe").unwrap_err().contains("3 x 1"));
    /// ```
    pub fn decode(bytes: &[u8]) -> Result<Self, String> {
        match bytes {
            [b'P', b'5', ..] | [b'P', b'2', ..] => decode_pgm(bytes),
            [0x89, b'P', b'N', b'G', ..] => decode_png(bytes),
            _ => Err("not a PGM (P5 or P2) or PNG image".into()),
        }
    }
}

/// Width and height checked against [`MAX_MAP_CELLS`] before anything is allocated.
fn check_size(width: usize, height: usize) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("a {width} x {height} image holds no cell"));
    }
    match width.checked_mul(height) {
        Some(cells) if cells <= MAX_MAP_CELLS => Ok(()),
        _ => Err(format!(
            "{width} x {height} pixels exceed the limit of {MAX_MAP_CELLS} cells for a map"
        )),
    }
}

/// The PGM header's tokens and the plain format's samples: decimal numbers between
/// whitespace and `#` comments.
struct Tokens<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Tokens<'_> {
    fn skip_blanks(&mut self) {
        while let Some(&b) = self.bytes.get(self.at) {
            if b == b'#' {
                while self
                    .bytes
                    .get(self.at)
                    .is_some_and(|&b| b != b'\n' && b != b'\r')
                {
                    self.at += 1;
                }
            } else if b.is_ascii_whitespace() {
                self.at += 1;
            } else {
                break;
            }
        }
    }

    /// The next decimal number, named `what` in errors.
    fn number(&mut self, what: &str) -> Result<u64, String> {
        self.skip_blanks();
        let start = self.at;
        while self.bytes.get(self.at).is_some_and(u8::is_ascii_digit) {
            self.at += 1;
        }
        if start == self.at {
            return Err(match self.bytes.get(self.at) {
                None => format!("the PGM ends before its {what}"),
                Some(b) => format!("the PGM's {what} is not a number (byte {b:#04x})"),
            });
        }
        std::str::from_utf8(&self.bytes[start..self.at])
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| format!("the PGM's {what} is too large"))
    }
}

fn decode_pgm(bytes: &[u8]) -> Result<Raster, String> {
    let plain = bytes[1] == b'2';
    let mut tokens = Tokens { bytes, at: 2 };
    if !tokens.bytes.get(2).is_some_and(u8::is_ascii_whitespace) {
        return Err("the PGM's magic number is not followed by whitespace".into());
    }
    let width = tokens.number("width")?;
    let height = tokens.number("height")?;
    let max_value = tokens.number("maxval")?;
    let (width, height) = (
        usize::try_from(width).unwrap_or(usize::MAX),
        usize::try_from(height).unwrap_or(usize::MAX),
    );
    check_size(width, height)?;
    let max_value = match u16::try_from(max_value) {
        Ok(m) if m > 0 => m,
        _ => {
            return Err(format!(
                "the PGM's maxval {max_value} is not within 1..=65535"
            ));
        }
    };
    let cells = width * height;
    let samples = if plain {
        let mut samples = Vec::with_capacity(cells);
        for i in 0..cells {
            let v = tokens
                .number("samples")
                .map_err(|e| format!("{e} ({i} of the {width} x {height} samples read)"))?;
            samples.push(sample(v, max_value)?);
        }
        tokens.skip_blanks();
        if tokens.at < bytes.len() {
            return Err(format!(
                "{} bytes follow the {width} x {height} samples",
                bytes.len() - tokens.at
            ));
        }
        samples
    } else {
        // Exactly one whitespace byte after maxval, then the raster.
        if !bytes.get(tokens.at).is_some_and(u8::is_ascii_whitespace) {
            return Err("the PGM's maxval is not followed by whitespace".into());
        }
        let data = &bytes[tokens.at + 1..];
        let wide = max_value > 255;
        let need = cells * if wide { 2 } else { 1 };
        if data.len() != need {
            return Err(format!(
                "the header says {width} x {height} pixels ({need} bytes) but {} bytes follow it",
                data.len()
            ));
        }
        if wide {
            data.chunks_exact(2)
                .map(|b| sample(u64::from(u16::from_be_bytes([b[0], b[1]])), max_value))
                .collect::<Result<_, _>>()?
        } else {
            data.iter()
                .map(|&b| sample(u64::from(b), max_value))
                .collect::<Result<_, _>>()?
        }
    };
    Ok(Raster {
        width,
        height,
        max_value,
        channels: 1,
        samples,
    })
}

/// A sample checked against maxval.
fn sample(v: u64, max_value: u16) -> Result<u16, String> {
    match u16::try_from(v) {
        Ok(s) if s <= max_value => Ok(s),
        _ => Err(format!("a sample {v} exceeds the PGM's maxval {max_value}")),
    }
}

fn decode_png(bytes: &[u8]) -> Result<Raster, String> {
    let why = |e: png::DecodingError| format!("not a readable PNG: {e}");
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // Palettes and low bit depths expanded to 8 bits, transparency to an alpha channel.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(why)?;
    let (w, h) = reader.info().size();
    let (width, height) = (
        usize::try_from(w).unwrap_or(usize::MAX),
        usize::try_from(h).unwrap_or(usize::MAX),
    );
    check_size(width, height)?;
    let (color, depth) = reader.output_color_type();
    let channels = match color {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err("an indexed PNG that did not expand".into()),
    };
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("a {width} x {height} PNG too large to decode"))?;
    let mut buf = vec![0; size];
    let frame = reader.next_frame(&mut buf).map_err(why)?;
    let buf = &buf[..frame.buffer_size()];
    let (max_value, samples): (u16, Vec<u16>) = match depth {
        png::BitDepth::Sixteen => (
            u16::MAX,
            buf.chunks_exact(2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
                .collect(),
        ),
        _ => (255, buf.iter().map(|&b| u16::from(b)).collect()),
    };
    if samples.len() != width * height * channels {
        return Err(format!(
            "a {width} x {height} PNG decoded to {} samples",
            samples.len()
        ));
    }
    Ok(Raster {
        width,
        height,
        max_value,
        channels,
        samples,
    })
}
