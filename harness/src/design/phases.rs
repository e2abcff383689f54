//! The progress of `grainchain design`'s long phases, their wall times and the journal their
//! Monte Carlo columns go to ([`Phases`]).

use super::draws_journal::DrawsJournal;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// The progress of the long phases: a bar per phase with a count and an estimate of the time
/// left on a terminal (indicatif, which draws nothing when stderr is not one), nothing when the
/// caller is silent; each phase's wall time; and the Monte Carlo's journal, which every phase
/// after the searches evaluates its columns through (none: every column is run).
#[derive(Debug, Default)]
pub struct Phases {
    progress: bool,
    times: std::sync::Mutex<Vec<(String, f64)>>,
    journal: Option<DrawsJournal>,
}

impl Phases {
    /// Bars drawn when `progress`.
    pub fn new(progress: bool) -> Phases {
        Phases {
            progress,
            times: Default::default(),
            journal: None,
        }
    }

    /// The phases' Monte Carlo columns go through `journal`.
    pub fn with_journal(mut self, journal: DrawsJournal) -> Phases {
        self.journal = Some(journal);
        self
    }

    /// The Monte Carlo's journal, if any.
    pub fn journal(&self) -> Option<&DrawsJournal> {
        self.journal.as_ref()
    }

    /// A bar of `len` steps labelled `label` (hidden without progress).
    pub fn bar(&self, len: u64, label: &str) -> ProgressBar {
        if !self.progress {
            return ProgressBar::hidden();
        }
        let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
        pb.set_style(
            ProgressStyle::with_template(
                "{msg}: {pos}/{len} [{bar:30}] {elapsed}, about {eta} left",
            )
            .expect("a valid template")
            .progress_chars("=> "),
        );
        pb.set_message(label.to_string());
        pb
    }

    /// Run `phase`, recording its wall time under `name`; a failure to write the journal while
    /// it ran is its error.
    pub fn time<T, E: From<crate::error::Error>>(
        &self,
        name: &str,
        phase: impl FnOnce() -> Result<T, E>,
    ) -> Result<T, E> {
        let t = std::time::Instant::now();
        let out = phase();
        if let Some(j) = &self.journal {
            j.check()?;
        }
        self.times
            .lock()
            .expect("not poisoned")
            .push((name.to_string(), t.elapsed().as_secs_f64()));
        out
    }

    /// Each phase's wall time, in the order they ran, and the Monte Carlo columns taken from
    /// the journal and run (zeros without one).
    pub fn into_times(self) -> (Vec<(String, f64)>, (u64, u64)) {
        let counts = self.journal.as_ref().map_or((0, 0), DrawsJournal::counts);
        (self.times.into_inner().expect("not poisoned"), counts)
    }
}
