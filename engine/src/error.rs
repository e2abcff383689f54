//! The engine's errors that span its parts: [`InputError`] (an input file that cannot be used:
//! which file, which key, what is wrong) and [`Error`], what a function that reads a scene and
//! runs it can fail with. Each part's own error (`ChainError`, `LawError`, `ParamsError`,
//! `RunError`, `UnknownProblem`) is defined beside it. None carries an exit code: that is the
//! command-line tool's business.

use std::path::PathBuf;

/// An input file (a scene, sweep or design file) that cannot be used: which file, which key, what
/// is wrong.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
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

/// What a function that spans the engine's parts (load a scene, build its chain, run it) can fail
/// with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file that cannot be used.
    #[error(transparent)]
    Input(#[from] InputError),
    /// A simulation that could not be built or failed (blow-up, energy error).
    #[error(transparent)]
    Run(#[from] crate::run::RunError),
    /// A chain built in code that the builder rejects.
    #[error(transparent)]
    Chain(#[from] crate::chain::ChainError),
}
