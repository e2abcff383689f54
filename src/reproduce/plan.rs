//! Stage 1, the plan: which simulations a `reproduce` run needs, each named by a typed
//! [`JobKey`], built from the scene files before anything runs (so a bad scene fails first).

use super::variants::Variant;
use super::{Figure, Options, STEP_FACTOR, TWIN_EPS, VARIANT_SNAPSHOTS};
use crate::batch::scenes::{self, container_sources, ContainerSource, SceneSource};
use crate::batch::Job;
use crate::error::Error;
use crate::observables::PulseRule;
use crate::scene::file::SceneFile;
use crate::scene::Scene;

/// Which run of a container.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ContainerRun {
    /// The Fig. 4/5 run.
    Main,
    /// At `dt / STEP_FACTOR` (`--check-step`).
    Fine,
    /// The chaos twin: striker speed x (1 + [`TWIN_EPS`]) (`--check-step`).
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
            snapshots,
            require_untouched_ends: self.untouched_ends(),
        }
    }
}

/// The snapshot indices a figure scene lists in `output.snapshots.at` (the first and the last
/// are the figure's) and its pulse rule.
fn listed_snapshots(src: &SceneSource, fig: &str) -> Result<(Vec<u64>, PulseRule), Error> {
    let sc = src.scene(|_| Ok(()))?;
    let at = sc
        .output
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
        .output
        .pulses
        .as_ref()
        .map(|p| p.rule)
        .unwrap_or_default();
    Ok((vec![at[0], *at.last().expect("two")], rule))
}

/// Everything to run, in the order it runs, and what the analysis needs to know about it.
#[derive(Default)]
pub struct Plan {
    /// The keys of [`Plan::jobs`], in the same order.
    pub keys: Vec<JobKey>,
    /// The simulations, in the order they are handed to the threads (the long container runs
    /// first).
    pub jobs: Vec<Job>,
    /// The containers of Fig. 4/5 (empty when neither is wanted).
    pub containers: Vec<ContainerSource>,
    /// The pulse rule of the Fig. 1 scene (`None`: the figure is not wanted).
    pub fig1_rule: Option<PulseRule>,
    /// The pulse rule of the Fig. 3 scene (`None`: the figure is not wanted).
    pub fig3_rule: Option<PulseRule>,
    /// The variants of (a) that run.
    pub variants: Vec<Variant>,
}

impl Plan {
    fn add(&mut self, key: JobKey, scene: Scene, snapshots: Vec<u64>) {
        self.jobs.push(key.job(scene, snapshots));
        self.keys.push(key);
    }
}

/// The plan of `opts`: biggest jobs first, so that the threads finish together.
pub fn plan(opts: &Options) -> Result<Plan, Error> {
    let load = |f: Figure, file: &str| -> Result<Option<SceneSource>, Error> {
        match opts.wants(f) {
            true => SceneSource::load(opts.scenes.join(file)).map(Some),
            false => Ok(None),
        }
    };
    let fig1 = load(Figure::Fig1, "fig1-heavy-to-light.toml")?;
    let fig3 = load(Figure::Fig3, "fig3-standard-container.toml")?;
    let mut plan = Plan::default();
    if opts.wants(Figure::Fig4) || opts.wants(Figure::Fig5) {
        plan.containers = container_sources(&opts.scenes.join("containers"))?;
    }
    if let Some(n) = opts.snapshots {
        if n < 40 {
            return Err(crate::reproduce::ReproduceError::TooFewSnapshots { snapshots: n }.into());
        }
    }
    if !plan.containers.is_empty() {
        plan_containers(opts, &mut plan)?;
        plan_variants(opts, &mut plan)?;
    }
    if let Some(src) = &fig1 {
        plan_fig1(opts, src, &mut plan)?;
    }
    if let Some(src) = &fig3 {
        plan_fig3(opts, src, &mut plan)?;
    }
    Ok(plan)
}

/// The run length of `--snapshots`, when given.
fn set_len(opts: &Options, f: &mut SceneFile) -> Result<(), Error> {
    if let Some(n) = opts.snapshots {
        scenes::set_snapshots(f, n);
    }
    Ok(())
}

/// Every container at `dt / 8` (with `--check-step`), then as Fig. 4/5 runs, then their twins.
fn plan_containers(opts: &Options, plan: &mut Plan) -> Result<(), Error> {
    let mut runs = vec![ContainerRun::Main];
    if opts.check_step {
        runs = vec![ContainerRun::Fine, ContainerRun::Main, ContainerRun::Twin];
    }
    let containers = plan.containers.clone();
    for run in runs {
        for c in &containers {
            let sc = c.source.scene(|f| {
                set_len(opts, f)?;
                match run {
                    ContainerRun::Main => {}
                    ContainerRun::Fine => scenes::refine_step(f, STEP_FACTOR),
                    ContainerRun::Twin => scenes::perturb_striker(f, TWIN_EPS),
                }
                Ok(())
            })?;
            plan.add(JobKey::container(&c.key, run), sc, vec![]);
        }
    }
    Ok(())
}

/// The variants of (a), at most [`VARIANT_SNAPSHOTS`] long.
fn plan_variants(opts: &Options, plan: &mut Plan) -> Result<(), Error> {
    let a = plan
        .containers
        .iter()
        .find(|c| c.key == "a")
        .expect("checked");
    let src = a.source.clone();
    let n_main = src.scene(|f| set_len(opts, f))?.outputs();
    let n_var = n_main.min(VARIANT_SNAPSHOTS);
    for v in Variant::ALL.into_iter().filter(|v| v.wanted(opts)) {
        let sc = src.scene(|f| {
            scenes::set_snapshots(f, n_var);
            v.apply(&src, f)
        })?;
        plan.add(JobKey::Variant(v), sc, vec![]);
        plan.variants.push(v);
    }
    Ok(())
}

/// Fig. 1 and its control run (the light section heavy too), each also at `dt / 8` with
/// `--check-step`.
fn plan_fig1(opts: &Options, src: &SceneSource, plan: &mut Plan) -> Result<(), Error> {
    let (snaps, rule) = listed_snapshots(src, "fig1")?;
    plan.fig1_rule = Some(rule);
    let fines: &[bool] = if opts.check_step {
        &[false, true]
    } else {
        &[false]
    };
    for &fine in fines {
        for control in [false, true] {
            let sc = src.scene(|f| {
                if control {
                    scenes::copy_mass(src, f, "light", "heavy")?;
                }
                if fine {
                    scenes::refine_step(f, STEP_FACTOR);
                }
                Ok(())
            })?;
            plan.add(JobKey::Fig1 { control, fine }, sc, snaps.clone());
        }
    }
    Ok(())
}

/// Fig. 3, also at `dt / 8` with `--check-step`.
fn plan_fig3(opts: &Options, src: &SceneSource, plan: &mut Plan) -> Result<(), Error> {
    let (snaps, rule) = listed_snapshots(src, "fig3")?;
    plan.fig3_rule = Some(rule);
    let main = src.scene(|_| Ok(()))?;
    plan.add(JobKey::Fig3 { fine: false }, main, snaps.clone());
    if opts.check_step {
        let sc = src.scene(|f| {
            scenes::refine_step(f, STEP_FACTOR);
            Ok(())
        })?;
        plan.add(JobKey::Fig3 { fine: true }, sc, snaps);
    }
    Ok(())
}
