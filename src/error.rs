//! Errors of the scene and CLI layer.

use std::path::PathBuf;

/// A scene file that cannot be used: which file, which key, what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{file}: cannot read: {source}")]
    Read {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}: {message}")]
    Parse { file: PathBuf, message: String },
    #[error("{file}: key `{key}`: {message}")]
    Invalid {
        file: PathBuf,
        key: String,
        message: String,
    },
}

/// Anything the command-line tool can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Run(#[from] crate::run::RunError),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A chain built in code (not from a scene) that the builder rejects.
    #[error(transparent)]
    Chain(#[from] crate::chain::ChainError),
    /// A CSV file or table (`what` names it).
    #[error("{what}: {source}")]
    Csv { what: String, source: csv::Error },
    /// JSON output (summaries, the units table).
    #[error("writing JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// Anything else, said in words (failed figures, missing data of a figure, plotting).
    #[error("{0}")]
    Other(String),
}

impl Error {
    /// Exit code: 2 for bad input, 1 for a failed run or output.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Scene(_) => 2,
            _ => 1,
        }
    }
}
