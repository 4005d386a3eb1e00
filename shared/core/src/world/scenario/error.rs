//! Why a scenario was refused: one error type, displayed as `FILE: FIELD: REASON`.

/// Why a scenario was rejected. Every variant displays as `FILE: FIELD: REASON`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read (missing, a directory, not UTF-8, ...).
    #[error("{file}: (file): {reason}")]
    Read {
        /// The file as given.
        file: String,
        /// What went wrong.
        reason: String,
    },
    /// The text is not a scenario: TOML syntax, an unknown field, a missing field or a
    /// value of the wrong type.
    #[error("{file}: {field}: {reason}")]
    Parse {
        /// The file as given.
        file: String,
        /// Dotted path of the offending field, or `line L, column C` for syntax errors.
        field: String,
        /// What went wrong.
        reason: String,
    },
    /// The values are well-formed but not a legal scenario (NaN, a negative size, an
    /// obstacle outside the field, overlapping slots, a blocked start, no path, ...).
    #[error("{file}: {field}: {reason}")]
    Invalid {
        /// The file as given.
        file: String,
        /// Dotted path of the offending field.
        field: String,
        /// What went wrong.
        reason: String,
    },
}

impl ScenarioError {
    /// The field the error names (`(file)` for read errors).
    pub fn field(&self) -> &str {
        match self {
            Self::Read { .. } => "(file)",
            Self::Parse { field, .. } | Self::Invalid { field, .. } => field,
        }
    }
}
