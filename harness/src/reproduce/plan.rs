//! Stage 1, the plan: which simulations a `reproduce` run needs, each named by a typed
//! [`JobKey`], built from the scene files before anything runs (so a bad scene fails first).
//! Each unit plans its own jobs ([`super::unit::FigureUnit::plan`]); this is the list they add
//! to and the helpers they share.

use super::figures::Variant;
use super::options::Options;
use crate::batch::scenes::{self, SceneSource};
use crate::batch::Job;
use crate::error::Error;
use grainchain_engine::file::SceneFile;
use grainchain_engine::PulseRule;
use grainchain_engine::Scene;

/// Which run of a container.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ContainerRun {
    /// The Fig. 4/5 run.
    Main,
    /// At `dt / STEP_FACTOR` (`--check-step`).
    Fine,
    /// The chaos twin: striker speed x (1 + [`TWIN_EPS`](crate::batch::scenes::TWIN_EPS)) (`--check-step`).
    Twin,
}

/// The name of one simulation of the plan.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum JobKey {
    /// Fig. 1 (`fig1-heavy-to-light.toml`).
    Fig1 {
        /// The control run: the light section made heavy too, so that only the striker's own
        /// rebound is left in the heavy section (subtracted to get the reflected energy).
        control: bool,
        /// At `dt / STEP_FACTOR` (`--check-step`).
        fine: bool,
    },
    /// Fig. 3 (`fig3-standard-container.toml`).
    Fig3 {
        /// At `dt / STEP_FACTOR` (`--check-step`).
        fine: bool,
    },
    /// A container of Fig. 4/5.
    Container {
        /// The container's key (`a` for `a-standard.toml`).
        key: String,
        /// Which of its runs.
        run: ContainerRun,
    },
    /// A variant of container (a).
    Variant(Variant),
}

impl JobKey {
    /// The key of the `run` of the container with key `key`.
    pub fn container(key: &str, run: ContainerRun) -> Self {
        JobKey::Container {
            key: key.to_string(),
            run,
        }
    }

    /// Its name in the progress bar, error messages and the runs tables.
    pub fn label(&self) -> String {
        match self {
            JobKey::Fig1 {
                control: false,
                fine: false,
            } => "fig1".into(),
            JobKey::Fig1 {
                control: true,
                fine: false,
            } => "fig1 control".into(),
            JobKey::Fig1 {
                control: false,
                fine: true,
            } => "fig1:fine".into(),
            JobKey::Fig1 {
                control: true,
                fine: true,
            } => "fig1:control:fine".into(),
            JobKey::Fig3 { fine: false } => "fig3".into(),
            JobKey::Fig3 { fine: true } => "fig3 dt/8".into(),
            JobKey::Container { key, run } => match run {
                ContainerRun::Main => format!("fig4 ({key})"),
                ContainerRun::Fine => format!("({key}) dt/8"),
                ContainerRun::Twin => format!("({key}) twin"),
            },
            JobKey::Variant(v) => format!("(a) {}", v.key()),
        }
    }

    /// The scene regions whose energy the job records.
    pub fn regions(&self) -> &'static [&'static str] {
        match self {
            JobKey::Fig1 { .. } => &["heavy", "light"],
            _ => &["container"],
        }
    }

    /// Which ends of the chain must stay untouched (left, right): Fig. 1 has a free left end
    /// behind the striker, Fig. 3 the striker at the right end, and the free-end variant is
    /// meant to reach its ends.
    pub fn untouched_ends(&self) -> (bool, bool) {
        match self {
            JobKey::Fig1 { .. } => (false, true),
            JobKey::Fig3 { .. } => (true, false),
            JobKey::Container { .. } => (true, true),
            JobKey::Variant(v) => (v.check_ends(), v.check_ends()),
        }
    }

    /// The job of this key on `scene`, recording whole-chain snapshots at `snapshots`.
    fn job(&self, scene: Scene, snapshots: Vec<u64>) -> Job {
        Job {
            label: self.label(),
            scene,
            regions: self.regions().iter().map(|s| s.to_string()).collect(),
            unprotected: Vec::new(),
            unprotected_at: None,
            snapshots,
            require_untouched_ends: self.untouched_ends(),
            gauges: None,
            mechanism: false,
        }
    }
}

/// The snapshot indices a figure scene lists in `output.snapshots.at` (the first and the last
/// are the figure's) and its pulse rule.
pub(crate) fn listed_snapshots(
    src: &SceneSource,
    fig: &str,
) -> Result<(Vec<u64>, PulseRule), Error> {
    let sc = src.checked()?;
    let at = sc
        .output()
        .snapshots
        .as_ref()
        .map(|s| s.at.clone())
        .unwrap_or_default();
    if at.len() < 2 {
        return Err(src.missing(&format!(
            "`output.snapshots.at` with at least two snapshots ({fig}: before/incident and the figure's)"
        )));
    }
    let rule = sc
        .output()
        .pulses
        .as_ref()
        .map(|p| p.rule)
        .unwrap_or_default();
    Ok((vec![at[0], *at.last().expect("two")], rule))
}

/// Everything to run, in the order it runs.
#[derive(Default)]
pub struct Plan {
    /// The keys of [`Plan::jobs`], in the same order.
    pub keys: Vec<JobKey>,
    /// The simulations, in the order they are handed to the threads (the long container runs
    /// first).
    pub jobs: Vec<Job>,
}

impl Plan {
    /// Add the job `key` on `scene`, recording whole-chain snapshots at `snapshots`.
    pub(crate) fn add(&mut self, key: JobKey, scene: Scene, snapshots: Vec<u64>) {
        self.jobs.push(key.job(scene, snapshots));
        self.keys.push(key);
    }
}

/// The run length of `--snapshots`, when given.
pub(crate) fn set_len(opts: &Options, f: &mut SceneFile) -> Result<(), Error> {
    if let Some(n) = opts.snapshots {
        scenes::set_snapshots(f, n);
    }
    Ok(())
}

/// A figure's scene file `file` in the scene directory.
pub(crate) fn load(opts: &Options, file: &str) -> Result<SceneSource, Error> {
    opts.files.load(&opts.scenes.join(file))
}
