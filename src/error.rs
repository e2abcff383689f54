//! Errors of the scene and CLI layer.

use std::path::PathBuf;

/// A scene file that cannot be used: which file, which key, what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Read {
        /// The file, as given.
        file: PathBuf,
        /// Why it could not be read.
        source: std::io::Error,
    },
    /// The file is not valid TOML or does not fit the schema (a wrong type, an unknown key);
    /// `message` is the TOML parser's, with line and column.
    #[error("{file}: {message}")]
    Parse {
        /// The file, as given.
        file: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// The file parses but a value is not acceptable (out of range, inconsistent with another
    /// key, an unknown name).
    #[error("{file}: key `{key}`: {message}")]
    Invalid {
        /// The file, as given.
        file: PathBuf,
        /// The key at fault as a dotted TOML path (e.g. `output.pulses.every`,
        /// `chain.sections[2].mass`).
        key: String,
        /// What is wrong with its value.
        message: String,
    },
}

/// Anything the command-line tool can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene or sweep file that cannot be used (exit code 2).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A simulation that could not be built or failed (blow-up, energy error; exit code 1).
    #[error("{0}")]
    Run(#[from] crate::run::RunError),
    /// Reading or writing a file or directory failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory involved.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A chain built in code (not from a scene) that the builder rejects.
    #[error(transparent)]
    Chain(#[from] crate::chain::ChainError),
    /// A CSV file or table (`what` names it).
    #[error("{what}: {source}")]
    Csv {
        /// The file or table, in words.
        what: String,
        /// The CSV reader's or writer's error.
        source: csv::Error,
    },
    /// JSON output (summaries, the units table).
    #[error("writing JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A batch job or member file (`batch`).
    #[error(transparent)]
    Batch(#[from] crate::batch::BatchError),
    /// A study's merge (`study`).
    #[error(transparent)]
    Study(#[from] crate::study::StudyError),
    /// A figure of `reproduce`.
    #[error(transparent)]
    Reproduce(#[from] crate::reproduce::ReproduceError),
    /// A chart the SVG backend could not draw.
    #[error(transparent)]
    Plot(#[from] crate::report::plot::PlotError),
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
