//! What can go wrong when a study merges its members.

/// A failure of `grainchain study` a caller may handle.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// Members of the study are missing (their shards have not run).
    #[error("cannot merge: {missing} of {total} members are missing, e.g. {}; run their shards first (job j belongs to shard K/N when j mod N = K - 1)", examples.join(", "))]
    MissingMembers {
        /// How many are missing.
        missing: usize,
        /// How many the study has.
        total: usize,
        /// The first few, as `stem (job j)`.
        examples: Vec<String>,
    },
    /// A random container's design in a member file cannot be read.
    #[error("{key}: design in member file: {message}")]
    Design {
        /// The container key.
        key: String,
        /// The JSON reader's message.
        message: String,
    },
}
