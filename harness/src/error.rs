//! Every error type of the crate above the engine, in one module that imports nothing above
//! it: the scene error (which file, which key, what is wrong), the typed failures of the batch
//! layer, of `study`, of `design` and of `reproduce`, a chart that could not be drawn, and
//! [`Error`], what the command-line tool can fail with, each at this one path.

use grainchain_engine::InputError;
use std::path::PathBuf;

/// Anything the command-line tool can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene or sweep file that cannot be used (exit code 2).
    #[error(transparent)]
    Input(#[from] InputError),
    /// A simulation that could not be built or failed (blow-up, energy error; exit code 1).
    #[error("{0}")]
    Run(#[from] grainchain_engine::RunError),
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
    Chain(#[from] grainchain_engine::ChainError),
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
    Batch(#[from] BatchError),
    /// A study's merge (`study`).
    #[error(transparent)]
    Study(#[from] StudyError),
    /// A figure of `reproduce`.
    #[error(transparent)]
    Reproduce(#[from] ReproduceError),
    /// An output folder that belongs to another command or is being written by one.
    #[error(transparent)]
    OutDir(#[from] OutDirError),
    /// A chart the SVG backend could not draw.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A protector design that could not be evaluated, or its search (`design`).
    #[error(transparent)]
    Design(#[from] DesignFailure),
    /// A design search's journals (`design`): a damaged one, or islands missing.
    #[error(transparent)]
    Journal(#[from] JournalError),
    /// A command's option out of its range (exit code 2): its name (`threads`, as a library
    /// caller spells it; the CLI's parser names the flag before this is reached) and what is
    /// wrong.
    #[error("{name}: {problem}")]
    Usage {
        /// The option.
        name: &'static str,
        /// What is wrong with its value.
        problem: String,
    },
}

impl From<grainchain_engine::Error> for Error {
    fn from(e: grainchain_engine::Error) -> Self {
        match e {
            grainchain_engine::Error::Input(e) => Error::Input(e),
            grainchain_engine::Error::Run(e) => Error::Run(e),
            grainchain_engine::Error::Chain(e) => Error::Chain(e),
        }
    }
}

impl Error {
    /// Exit code: 2 for bad input, 1 for a failed run or output.
    pub fn exit_code(&self) -> i32 {
        match self {
            // A member file is an input of the merge: a damaged or foreign one is bad input.
            Error::Input(_)
            | Error::Usage { .. }
            | Error::OutDir(OutDirError::NotOurs { .. } | OutDirError::BadManifest { .. })
            | Error::Batch(
                BatchError::DamagedMember { .. }
                | BatchError::ForeignMember { .. }
                | BatchError::MemberValue { .. }
                | BatchError::MemberMeta { .. },
            )
            | Error::Journal(JournalError::Damaged { .. }) => 2,
            _ => 1,
        }
    }
}

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
    /// The batch's thread pool could not be started.
    #[error("the batch's threads: {0}")]
    Threads(String),
    /// A member's bookkeeping file cannot be read as JSON of the expected form.
    #[error("{}: {message}", file.display())]
    MemberMeta {
        /// The `.json` file.
        file: PathBuf,
        /// The JSON reader's message.
        message: String,
    },
    /// A member file written for another version of the batch: other settings or another build.
    #[error("{}: {why}; run that job again (--resume reruns it) or remove the file", file.display())]
    ForeignMember {
        /// The `.json` file.
        file: PathBuf,
        /// The difference: which build wrote it, or the first setting that differs.
        why: String,
    },
    /// A member file that is incomplete or damaged (cut short, changed, a non-finite value).
    #[error("{}: damaged member: {problem}; run that job again (--resume reruns it) or remove the file", file.display())]
    DamagedMember {
        /// The file at fault.
        file: PathBuf,
        /// What is wrong with it.
        problem: String,
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

/// A failure of a design search's journals (`design::search`) a caller may handle: what
/// `--resume` and `--merge` read is refused, never dropped in silence.
#[derive(Debug, thiserror::Error)]
pub enum JournalError {
    /// An island's journal or convergence file that cannot be used: a line damaged or cut, not
    /// UTF-8, not matching its checksum; a file of another design file or of an older build; a
    /// journal changed after its island finished.
    #[error("{}{}: {problem}; {advice}", file.display(), line.map_or_else(String::new, |l| format!(": line {l}")))]
    Damaged {
        /// The file at fault.
        file: PathBuf,
        /// The line at fault, counting from 1 (the digest line), or `None` for the whole file.
        line: Option<usize>,
        /// What is wrong with it.
        problem: String,
        /// What to do (which island to run again, and how).
        advice: String,
    },
    /// Islands of the search that are missing or have not finished.
    #[error("{}: cannot merge: {}; {advice}", dir.display(), missing.join(", "))]
    MissingIslands {
        /// The folder of the journals (`evaluations/`).
        dir: PathBuf,
        /// What is missing, one island each (`island 2 of 3: no island-2-of-3.csv`).
        missing: Vec<String>,
        /// What to do (the commands that run them).
        advice: String,
    },
}

/// A failure of `grainchain reproduce` a caller may handle.
#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    /// `--snapshots` too short for the containers.
    #[error("--snapshots {snapshots}: the containers need at least 40 snapshots (the incident wave alone takes ~140 to arrive)")]
    TooFewSnapshots {
        /// The number asked for.
        snapshots: u64,
    },
    /// A figure's scene does not list its two snapshots.
    #[error("{figure}: the scene must list two snapshots in output.snapshots.at (before, after)")]
    SnapshotsNotListed {
        /// The figure (`fig1`, `fig3`).
        figure: String,
    },
    /// No incident wave where the figure expects it.
    #[error("{figure}: no incident wave {place}")]
    NoIncidentWave {
        /// The figure (`fig1`, `fig3`).
        figure: &'static str,
        /// Where it was looked for.
        place: &'static str,
    },
    /// Fig. 5 rescales time relative to container (a), which was not run.
    #[error("fig5: the reference container (a) is missing")]
    MissingReference,
    /// A job the analysis needs was not planned.
    #[error("{job}: not in the plan")]
    NotInPlan {
        /// The job's label.
        job: String,
    },
    /// A figure with no data to draw.
    #[error("{figure}: nothing to plot")]
    NothingToPlot {
        /// The figure.
        figure: &'static str,
    },
}

/// The SVG backend failed to draw a chart.
#[derive(Debug, thiserror::Error)]
#[error("plot `{title}`: {message}")]
pub struct PlotError {
    /// The chart's title.
    pub title: String,
    /// The backend's message.
    pub message: String,
}

/// An output folder this command may not write (see [`crate::report::outdir`]).
#[derive(Debug, thiserror::Error)]
pub enum OutDirError {
    /// Another process holds the folder's lock.
    #[error("{}: another grainchain command is writing to this folder (it holds {}); wait for it to finish or choose another --out", dir.display(), lock.display())]
    Locked {
        /// The folder.
        dir: PathBuf,
        /// The lock file.
        lock: PathBuf,
    },
    /// The folder holds files another command (or another input) wrote, or files grainchain did
    /// not write.
    #[error("{}: {why}; {advice}", dir.display())]
    NotOurs {
        /// The folder.
        dir: PathBuf,
        /// Who wrote it, which input differs, or what in it grainchain did not write.
        why: String,
        /// What the user can do (`--force` only where it would help).
        advice: String,
    },
    /// A manifest that cannot be read.
    #[error("{}: not a grainchain manifest: {message}", file.display())]
    BadManifest {
        /// The manifest.
        file: PathBuf,
        /// The JSON reader's message.
        message: String,
    },
}

/// A protector design search that failed (`design`).
#[derive(Debug, thiserror::Error)]
pub enum DesignFailure {
    /// A design the engine could not evaluate, with the design file.
    #[error("{file}: {source}")]
    Evaluation {
        /// The design file.
        file: PathBuf,
        /// Why the design could not be evaluated.
        source: grainchain_engine::protector::DesignError,
    },
    /// Every design evaluated breaks a constraint (mass, length).
    #[error("{file}: no evaluated design meets the constraints")]
    NoneFeasible {
        /// The design file.
        file: PathBuf,
    },
    /// Nothing to merge: no journal in the folder.
    #[error("{file}: no evaluations in {dir} (run the search, or its {parts}, first)")]
    NoEvaluations {
        /// The design file.
        file: PathBuf,
        /// The folder of the journals.
        dir: PathBuf,
        /// What writes them: `islands` or `shards`.
        parts: &'static str,
    },
    /// The search's thread pool could not start.
    #[error("design search: threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// The best design could not be written as a scene (`best.toml`).
    #[error("best.toml: cannot write the scene: {0}")]
    BestToml(toml::ser::Error),
    /// The genetic search refused its settings or failed: its own error, which it can only
    /// print for debugging (`genetic_algorithm`'s errors have no `Display`).
    #[error("design search: {0}")]
    Genetic(String),
}
