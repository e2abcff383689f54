//! The progress of `grainchain design`'s long phases and their wall times ([`Phases`]).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// The progress of the long phases: a bar per phase with a count and an estimate of the time
/// left on a terminal (indicatif, which draws nothing when stderr is not one), nothing when the
/// caller is silent; and each phase's wall time.
#[derive(Debug, Default)]
pub struct Phases {
    progress: bool,
    times: std::sync::Mutex<Vec<(String, f64)>>,
}

impl Phases {
    /// Bars drawn when `progress`.
    pub fn new(progress: bool) -> Phases {
        Phases {
            progress,
            times: Default::default(),
        }
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

    /// Run `phase`, recording its wall time under `name`.
    pub fn time<T>(&self, name: &str, phase: impl FnOnce() -> T) -> T {
        let t = std::time::Instant::now();
        let out = phase();
        self.times
            .lock()
            .expect("not poisoned")
            .push((name.to_string(), t.elapsed().as_secs_f64()));
        out
    }

    /// Each phase's wall time, in the order they ran.
    pub fn into_times(self) -> Vec<(String, f64)> {
        self.times.into_inner().expect("not poisoned")
    }
}
