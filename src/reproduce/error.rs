//! What can go wrong when `reproduce` analyses and draws its figures.

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
    /// The SVG backend failed.
    #[error("drawing {name}: {message}")]
    Drawing {
        /// The file being drawn.
        name: String,
        /// The backend's message.
        message: String,
    },
}
