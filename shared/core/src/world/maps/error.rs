//! Why a map was refused: one error type, displayed as `FILE: FIELD: REASON` like a
//! scenario's.

/// Why a map_server map (its YAML file or its image) was refused. Every variant displays
/// as `FILE: FIELD: REASON`, `FILE` being the YAML file or the image as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MapError {
    /// A file could not be read (missing, a directory, too large, ...).
    #[error("{file}: (file): {reason}")]
    Read {
        /// The file as given.
        file: String,
        /// What went wrong.
        reason: String,
    },
    /// The YAML text is not a map description: syntax, an unknown key, a missing key or
    /// a value of the wrong type.
    #[error("{file}: {field}: {reason}")]
    Parse {
        /// The YAML file as given.
        file: String,
        /// The offending key, or `line L` for syntax errors.
        field: String,
        /// What went wrong.
        reason: String,
    },
    /// The values are well-formed but not a usable map (a resolution that is not
    /// positive, thresholds out of order, a rotated origin, ...).
    #[error("{file}: {field}: {reason}")]
    Invalid {
        /// The YAML file as given.
        file: String,
        /// The offending key.
        field: String,
        /// What went wrong.
        reason: String,
    },
    /// The image is not a PGM or PNG file this reader takes, or its header does not match
    /// its data, or it exceeds [`MAX_MAP_CELLS`](super::MAX_MAP_CELLS).
    #[error("{file}: (image): {reason}")]
    Image {
        /// The image file as resolved (relative to the YAML file).
        file: String,
        /// What went wrong.
        reason: String,
    },
}

impl MapError {
    /// The field the error names (`(file)` for read errors, `(image)` for image errors).
    pub fn field(&self) -> &str {
        match self {
            Self::Read { .. } => "(file)",
            Self::Image { .. } => "(image)",
            Self::Parse { field, .. } | Self::Invalid { field, .. } => field,
        }
    }
}
