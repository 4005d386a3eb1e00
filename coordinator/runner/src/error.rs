//! The coordinator's errors and their exit codes (`docs/outputs.md`): 2 for bad input,
//! 1 for anything else.

use shared::world::maps::MapError;
use shared::world::scenario::ScenarioError;

/// Why a command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The scenario file is unreadable or invalid (exit code 2).
    #[error("{0}")]
    Scenario(#[from] ScenarioError),
    /// A map (its YAML file or its image) is unreadable or invalid (exit code 2).
    #[error("{0}")]
    Map(#[from] MapError),
    /// A command-line value is invalid (exit code 2).
    #[error("{0}")]
    Usage(String),
    /// Anything else: I/O, a process, shared memory (exit code 1).
    #[error("{0:#}")]
    Other(#[from] anyhow::Error),
}

impl CliError {
    /// The process exit code for this error.
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Scenario(_) | Self::Map(_) | Self::Usage(_) => 2,
            Self::Other(_) => 1,
        }
    }
}
