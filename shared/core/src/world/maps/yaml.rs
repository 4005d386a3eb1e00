//! The map_server YAML file: where the image is, how large a pixel is, where the map lies
//! and how a pixel's shade becomes a cell's occupancy.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::MapError;
use crate::input_file::{Links, read_input_text};

/// How a pixel's shade becomes a cell (the map_server's `mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapMode {
    /// Occupied above `occupied_thresh`, free below `free_thresh`, unknown between (the
    /// default). With an alpha channel, alpha is averaged in with the colour channels as
    /// the map_server does.
    Trinary,
    /// As trinary, but a pixel that is not fully opaque is unknown; the map_server's
    /// graded cells between the thresholds are unknown here (a cell is an obstacle or
    /// not).
    Scale,
    /// The pixel value is the occupancy in percent: above `occupied_thresh` x 100
    /// occupied, below `free_thresh` x 100 free, else (values above 100 too) unknown.
    Raw,
}

/// A map_server YAML file, checked: every key of the format, no other.
#[derive(Debug, Clone, PartialEq)]
pub struct MapYaml {
    /// The image file, resolved against the YAML file's folder when relative.
    pub image: PathBuf,
    /// Side of a cell (a pixel), metres.
    pub resolution_m: f64,
    /// Position of the lower-left corner of the lower-left pixel, metres (`origin` x, y;
    /// its yaw must be 0).
    pub origin_m: [f64; 2],
    /// Whether white means occupied (`negate: 1`).
    pub negate: bool,
    /// Occupancy above which a cell is occupied, in [0, 1].
    pub occupied_thresh: f64,
    /// Occupancy below which a cell is free, in [0, 1], below `occupied_thresh`.
    pub free_thresh: f64,
    /// How shades become cells.
    pub mode: MapMode,
}

/// Most bytes of a map YAML file (real ones are a few hundred).
pub const MAX_MAP_YAML_BYTES: u64 = 64 * 1024;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct YamlFile {
    image: Option<String>,
    resolution: Option<f64>,
    origin: Option<Vec<f64>>,
    negate: Option<Negate>,
    occupied_thresh: Option<f64>,
    free_thresh: Option<f64>,
    mode: Option<String>,
}

/// `negate` is an integer (0 or 1) in the map_server's files; a boolean is taken too.
#[derive(Deserialize)]
#[serde(untagged)]
enum Negate {
    Int(i64),
    Bool(bool),
}

impl MapYaml {
    /// Read and check the YAML file at `path`.
    pub fn load(path: &Path) -> Result<Self, MapError> {
        let file = path.display().to_string();
        let read = |reason: String| MapError::Read {
            file: file.clone(),
            reason,
        };
        let text = read_input_text(path, MAX_MAP_YAML_BYTES, Links::Follow)
            .map_err(|e| read(e.to_string()))?;
        let folder = path.parent().unwrap_or(Path::new(""));
        Self::parse(&text, &file, folder)
    }

    /// Parse and check the text of a map YAML file; `file` names it in errors and a
    /// relative `image` is taken relative to `folder`.
    ///
    /// ```
    /// use std::path::Path;
    /// use shared::world::maps::{MapMode, MapYaml};
    /// let text = "image: depot.pgm\nresolution: 0.05\norigin: [1.0, 2.0, 0]\n\
    ///             negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n";
    /// let map = MapYaml::parse(text, "maps/depot.yaml", Path::new("maps")).unwrap();
    /// assert_eq!(map.image, Path::new("maps/depot.pgm"));
    /// assert_eq!((map.origin_m, map.mode), ([1.0, 2.0], MapMode::Trinary));
    /// let bad = text.replace("free_thresh: 0.25", "free_thresh: 0.7");
    /// let e = MapYaml::parse(&bad, "maps/depot.yaml", Path::new("maps")).unwrap_err();
    /// assert_eq!(
    ///     e.to_string(),
    ///     "maps/depot.yaml: free_thresh: 0.7 must be below occupied_thresh 0.65"
    /// );
    /// ```
    pub fn parse(text: &str, file: &str, folder: &Path) -> Result<Self, MapError> {
        let raw: YamlFile = serde_saphyr::from_str(text).map_err(|e| {
            // The reader's message without its own `error: line L column C:` prefix.
            let text = e.to_string();
            let first = text.lines().next().unwrap_or_default();
            let first = first.strip_prefix("error: ").unwrap_or(first);
            let reason = match first.split_once(": ") {
                Some((at, rest)) if at.starts_with("line ") => rest,
                _ => first,
            }
            .to_string();
            MapError::Parse {
                file: file.into(),
                field: e
                    .location()
                    .map_or_else(|| "(yaml)".into(), |at| format!("line {}", at.line())),
                reason,
            }
        })?;
        let missing = |field: &str| MapError::Parse {
            file: file.into(),
            field: field.into(),
            reason: "missing: a map_server map needs image, resolution, origin, negate, \
                     occupied_thresh and free_thresh"
                .into(),
        };
        let invalid = |field: &str, reason: String| MapError::Invalid {
            file: file.into(),
            field: field.into(),
            reason,
        };
        let image = raw.image.ok_or_else(|| missing("image"))?;
        if image.trim().is_empty() {
            return Err(invalid("image", "is empty".into()));
        }
        let image = folder.join(image);
        let resolution_m = raw.resolution.ok_or_else(|| missing("resolution"))?;
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(invalid(
                "resolution",
                format!("must be a positive number of metres, got {resolution_m}"),
            ));
        }
        let origin = raw.origin.ok_or_else(|| missing("origin"))?;
        let [x_m, y_m, yaw_rad] = origin[..] else {
            return Err(invalid(
                "origin",
                format!("must be [x, y, yaw], got {} numbers", origin.len()),
            ));
        };
        if !(x_m.is_finite() && y_m.is_finite() && yaw_rad.is_finite()) {
            return Err(invalid("origin", format!("{origin:?} must be finite")));
        }
        if yaw_rad != 0.0 {
            return Err(invalid(
                "origin",
                format!("a rotated map (yaw {yaw_rad} rad) is not supported: the yaw must be 0"),
            ));
        }
        let negate = match raw.negate.ok_or_else(|| missing("negate"))? {
            Negate::Bool(b) => b,
            Negate::Int(0) => false,
            Negate::Int(1) => true,
            Negate::Int(n) => return Err(invalid("negate", format!("must be 0 or 1, got {n}"))),
        };
        let occupied_thresh = raw
            .occupied_thresh
            .ok_or_else(|| missing("occupied_thresh"))?;
        let free_thresh = raw.free_thresh.ok_or_else(|| missing("free_thresh"))?;
        for (field, t) in [
            ("occupied_thresh", occupied_thresh),
            ("free_thresh", free_thresh),
        ] {
            if !(0.0..=1.0).contains(&t) {
                return Err(invalid(field, format!("must be within [0, 1], got {t}")));
            }
        }
        if free_thresh >= occupied_thresh {
            return Err(invalid(
                "free_thresh",
                format!("{free_thresh} must be below occupied_thresh {occupied_thresh}"),
            ));
        }
        let mode = match raw.mode.as_deref() {
            None | Some("trinary") => MapMode::Trinary,
            Some("scale") => MapMode::Scale,
            Some("raw") => MapMode::Raw,
            Some(other) => {
                return Err(invalid(
                    "mode",
                    format!("{other:?} is not one of \"trinary\", \"scale\", \"raw\""),
                ));
            }
        };
        Ok(Self {
            image,
            resolution_m,
            origin_m: [x_m, y_m],
            negate,
            occupied_thresh,
            free_thresh,
            mode,
        })
    }
}
