//! Stage 3, analyse: the runs of the plan, looked up by [`JobKey`], into [`Results`] — numbers
//! only; the text is `render`'s. Each figure's analysis is in [`super::figures`], the step-size
//! check in [`super::step_check`].

use super::figures::{self, ContainerFit, Curve, Fig1, Fig3, VariantResult};
use super::jobs::{RunData, Runs};
use super::plan::{ContainerRun, JobKey, Plan};
use super::step_check::{self, StepCheck};
use crate::error::Error;
use crate::observables::PulseRule;
use crate::study::outputs::Study;
use std::time::Instant;

/// Everything a `reproduce` run measured, and nothing rendered.
#[derive(Clone, Debug, Default)]
pub struct Results {
    /// Wall time from the start of the run to the end of the analysis.
    pub wall: f64,
    pub fig1: Option<Fig1>,
    pub fig3: Option<Fig3>,
    pub fits: Option<Vec<ContainerFit>>,
    pub variants: Vec<VariantResult>,
    pub step_checks: Vec<StepCheck>,
    pub runs: Vec<RunEntry>,
    /// The ensemble study of the containers (with `Options::members > 0`) and its wall time.
    pub ensemble: Option<(Study, f64)>,
}

/// One simulation of a `reproduce` run, for its runs table.
#[derive(Clone, Debug)]
pub struct RunEntry {
    pub key: JobKey,
    /// The run's bookkeeping ([`crate::run::RunSummary`]).
    pub run: crate::run::RunSummary,
    /// Output times recorded (t = 0 included).
    pub recorded: usize,
    /// Wall time of the job, set-up included.
    pub wall: f64,
}

impl RunEntry {
    fn of(key: &JobKey, d: &RunData) -> Self {
        RunEntry {
            key: key.clone(),
            run: d.run.clone(),
            recorded: d.energies.first().map_or(0, |e| e.len()),
            wall: d.wall,
        }
    }

    pub fn label(&self) -> String {
        self.key.label()
    }
}

/// Headline numbers (the insta snapshot of the golden tests).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Headline {
    pub fig1: Option<Fig1Headline>,
    pub fig3: Option<Fig3Headline>,
    pub fig5: Vec<Fig5Headline>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig1Headline {
    pub incident_energy: f64,
    pub transmitted_pulses: usize,
    pub transmitted_above_1_percent: usize,
    pub transmitted_above_0_1_percent: usize,
    pub leading_fraction: f64,
    pub reflected_fraction: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig3Headline {
    pub incident_energy: f64,
    pub left_lead_percent: Option<f64>,
    pub right_lead_percent: Option<f64>,
    pub container_percent: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Fig5Headline {
    pub container: String,
    pub gamma: Option<f64>,
    pub gamma_ci: Option<(f64, f64)>,
    pub alpha: Option<f64>,
}

impl Headline {
    pub fn of(r: &Results) -> Headline {
        Headline {
            fig1: r.fig1.as_ref().map(|f| Fig1Headline {
                incident_energy: f.incident.energy,
                transmitted_pulses: f.transmitted.len(),
                transmitted_above_1_percent: f.count_above(0.01),
                transmitted_above_0_1_percent: f.count_above(0.001),
                leading_fraction: f.transmitted.first().map_or(0.0, |p| p.fraction),
                reflected_fraction: f.reflected / f.incident.energy,
            }),
            fig3: r.fig3.as_ref().map(|f| Fig3Headline {
                incident_energy: f.incident.energy,
                left_lead_percent: f.left_lead.as_ref().map(|p| 100.0 * p.fraction),
                right_lead_percent: f.right_lead.as_ref().map(|p| 100.0 * p.fraction),
                container_percent: 100.0 * f.container_energy / f.incident.energy,
            }),
            fig5: r.fits.iter().flatten().map(Fig5Headline::of).collect(),
        }
    }
}

impl Fig5Headline {
    fn of(c: &ContainerFit) -> Self {
        Fig5Headline {
            container: c.key.clone(),
            gamma: c.fit.map(|f| f.gamma),
            gamma_ci: c.fit.map(|f| (f.ci_lo, f.ci_hi)),
            alpha: c.collapse.map(|x| x.alpha),
        }
    }
}

/// The run of `key`, which the plan has.
fn get<'a>(runs: &'a Runs, key: &JobKey) -> Result<&'a RunData, Error> {
    runs.get(key)
        .ok_or_else(|| Error::Other(format!("{}: not in the plan", key.label())))
}

/// Analyse the runs of `plan`; `started` is when the `reproduce` run began.
pub fn analyse(plan: &Plan, runs: &Runs, started: Instant) -> Result<Results, Error> {
    let mut r = Results {
        runs: runs.runs.iter().map(|(k, d)| RunEntry::of(k, d)).collect(),
        ensemble: runs.ensemble.clone(),
        ..Default::default()
    };
    if let Some(rule) = plan.fig1_rule {
        fig1(runs, rule, &mut r)?;
    }
    if let Some(rule) = plan.fig3_rule {
        fig3(runs, rule, &mut r)?;
    }
    if !plan.containers.is_empty() {
        containers(plan, runs, &mut r)?;
    }
    r.wall = started.elapsed().as_secs_f64();
    Ok(r)
}

fn fig1(runs: &Runs, rule: PulseRule, r: &mut Results) -> Result<(), Error> {
    let key = |control, fine| JobKey::Fig1 { control, fine };
    let m = get(runs, &key(false, false))?;
    let f = figures::fig1(m, get(runs, &key(true, false))?, rule)?;
    if let (Some(mf), Some(cf)) = (runs.get(&key(false, true)), runs.get(&key(true, true))) {
        let ff = figures::fig1(mf, cf, rule)?;
        r.step_checks.push(step_check::fig1(&f, &ff, m, mf));
    }
    r.fig1 = Some(f);
    Ok(())
}

fn fig3(runs: &Runs, rule: PulseRule, r: &mut Results) -> Result<(), Error> {
    let d = get(runs, &JobKey::Fig3 { fine: false })?;
    let f = figures::fig3(d, rule)?;
    if let Some(df) = runs.get(&JobKey::Fig3 { fine: true }) {
        let ff = figures::fig3(df, rule)?;
        r.step_checks.push(step_check::fig3(&f, &ff, d, df)?);
    }
    r.fig3 = Some(f);
    Ok(())
}

/// Fig. 4/5: the fits of every container, the variants of (a) and, with `--check-step`, the
/// step checks of the containers.
fn containers(plan: &Plan, runs: &Runs, r: &mut Results) -> Result<(), Error> {
    let main = |key: &str| get(runs, &JobKey::container(key, ContainerRun::Main));
    let mut curves = Vec::new();
    for c in &plan.containers {
        let d = main(&c.key)?;
        curves.push(Curve {
            key: c.key.clone(),
            label: c.label.clone(),
            er: d.region("container")?.energy.to_vec(),
            e0: d.run.initial_energy,
        });
    }
    let fits = figures::fig45(curves)?;
    let a = fits.iter().find(|c| c.key == "a").expect("checked");
    for &v in &plan.variants {
        let d = get(runs, &JobKey::Variant(v))?;
        r.variants.push(figures::variant(v, d, a)?);
    }
    for c in &plan.containers {
        let fine = JobKey::container(&c.key, ContainerRun::Fine);
        let twin = JobKey::container(&c.key, ContainerRun::Twin);
        if let (Some(fine), Some(twin)) = (runs.get(&fine), runs.get(&twin)) {
            let check = step_check::container(&c.key, main(&c.key)?, fine, twin, &fits)?;
            r.step_checks.push(check);
        }
    }
    r.fits = Some(fits);
    Ok(())
}
