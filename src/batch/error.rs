//! What can go wrong in a batch: a job whose scene does not fit what it was asked to record, a
//! job that failed or was not run, a member file that cannot be used.

use std::path::PathBuf;

/// A failure of the batch layer a caller may handle (each says which job or file).
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// A region was asked of a run that did not record it.
    #[error("{job}: no region `{region}` recorded")]
    RegionNotRecorded {
        /// The job's label.
        job: String,
        /// The region asked for.
        region: String,
    },
    /// A job asks for a snapshot after the run's end.
    #[error("{}: the figure needs snapshot {snapshot}, but the run has {outputs} (run.duration / run.output_interval)", scene.display())]
    SnapshotBeyondRun {
        /// The scene file.
        scene: PathBuf,
        /// The snapshot asked for.
        snapshot: u64,
        /// The run's number of outputs.
        outputs: u64,
    },
    /// A disturbance reached a chain end that had to stay untouched.
    #[error("{job} ({scene}): a disturbance reached the {side} end of the chain within the run, so a wave could come back; make the chain of {scene} longer on that side", scene = scene.display())]
    ReachedEnd {
        /// The job's label.
        job: String,
        /// The scene file.
        scene: PathBuf,
        /// `left` or `right`.
        side: &'static str,
    },
    /// A job was not run (an earlier job failed and stopped the batch).
    #[error("{job}: not run")]
    NotRun {
        /// The job's label.
        job: String,
    },
    /// A member's bookkeeping file cannot be read as JSON of the expected form.
    #[error("{}: {message}", file.display())]
    MemberMeta {
        /// The `.json` file.
        file: PathBuf,
        /// The JSON reader's message.
        message: String,
    },
    /// A member file written for another version of the batch (another digest).
    #[error("{}: written for another version of the sweep file (digest {here} here, {there} there); run that job again or remove the file", file.display())]
    ForeignMember {
        /// The `.json` file.
        file: PathBuf,
        /// This batch's digest.
        here: String,
        /// The member's digest.
        there: String,
    },
    /// A value of a member CSV is not a number.
    #[error("{}: row {row}: column `{column}` is not a number", file.display())]
    MemberValue {
        /// The `.csv` file.
        file: PathBuf,
        /// The row, counting the header as row 1.
        row: usize,
        /// The column's name.
        column: String,
    },
}
