//! What the render tests share: a scratch folder, and decoding what was drawn (PNG, GIF,
//! SVG) to look at its pixels.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use tools::render::layout::MapLayout;

/// A fresh, empty directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("render-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

/// An RGB image decoded from a PNG file.
pub struct Rgb {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u8>,
}

impl Rgb {
    pub fn at(&self, (x, y): (i32, i32)) -> [u8; 3] {
        assert!(x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height);
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }
}

pub fn decode_png(path: &Path) -> Rgb {
    let file = BufReader::new(File::open(path).expect("open png"));
    let mut reader = png::Decoder::new(file).read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("png buffer size")];
    let info = reader.next_frame(&mut buf).expect("png data");
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
    buf.truncate(info.buffer_size());
    Rgb {
        width: info.width,
        height: info.height,
        pixels: buf,
    }
}

/// Every frame of a GIF composed onto the canvas, as RGB images.
pub fn decode_gif(path: &Path) -> Vec<Rgb> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(BufReader::new(File::open(path).expect("open gif")))
        .expect("gif header");
    let (w, h) = (usize::from(decoder.width()), usize::from(decoder.height()));
    let mut canvas = vec![0u8; w * h * 3];
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().expect("gif frame") {
        let (fw, fh) = (usize::from(frame.width), usize::from(frame.height));
        for y in 0..fh {
            for x in 0..fw {
                let src = (y * fw + x) * 4;
                if frame.buffer[src + 3] == 0 {
                    continue; // transparent: the previous frame shows through
                }
                let dst = ((usize::from(frame.top) + y) * w + usize::from(frame.left) + x) * 3;
                canvas[dst..dst + 3].copy_from_slice(&frame.buffer[src..src + 3]);
            }
        }
        frames.push(Rgb {
            width: w as u32,
            height: h as u32,
            pixels: canvas.clone(),
        });
    }
    frames
}

pub fn assert_svg(path: &Path, (w, h): (u32, u32)) {
    let text = std::fs::read_to_string(path).expect("read svg");
    let doc = roxmltree::Document::parse(&text).expect("svg is XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg", "{}", path.display());
    assert_eq!(root.attribute("width"), Some(w.to_string().as_str()));
    assert_eq!(root.attribute("height"), Some(h.to_string().as_str()));
}

/// Orange of the agents' safety circles, translucent over white.
pub fn is_agent(c: [u8; 3]) -> bool {
    let [r, g, b] = c.map(i32::from);
    r > 215 && (150..235).contains(&g) && b < 175 && r - b > 60
}

pub fn px(layout: &MapLayout, x: f64, y: f64) -> (i32, i32) {
    layout.to_px(x, y)
}
