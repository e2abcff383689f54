//! The registry of `reproduce`'s figures, each one unit ([`FigureUnit`]) in its own file that
//! keeps its own numbers: the units' modules, every figure `--only` takes ([`Figure::ALL`]), the
//! wanted units of a run in the order of the report ([`Units`], which drives them through the
//! stages) and the numbers they measured, put together at the end ([`Results`]). A new figure is
//! a file here (its unit and its `Figure`) and its lines in this file (its module, its
//! `Figure` in `ALL`, its field of `Units` and of `Results`).
//!
//! Units: `fig1.rs`, `fig3.rs` and `containers/` (Fig. 4 and 5, which share the container runs
//! and fits, with the variants of (a)). Shared by units: `pulses.rs` (pulses in printed grain
//! numbers), `curves.rs` (the comparison of two `E_R` curves).

pub(crate) mod containers;
pub(crate) mod curves;
pub(crate) mod fig1;
pub(crate) mod fig3;
mod pulses;

pub use containers::{CollapsePoint, ContainerFit, ContainerQuantity, Variant, VariantResult};
pub use curves::CurveDiff;
pub use fig1::{Fig1, Fig1Quantity};
pub use fig3::{Fig3, Fig3Quantity, LargestPulse, Side};
pub use pulses::PulseOut;

use super::jobs::{RunEntry, Runs};
use super::options::{Figure, Options};
use super::plan::Plan;
use super::step_check::StepCheck;
use super::unit::{FigureUnit, Part};
use crate::error::Error;
use containers::Containers;
use fig1::Fig1Unit;
use fig3::Fig3Unit;

impl Figure {
    /// Every figure, in the paper's order.
    pub const ALL: [Figure; 4] = [Figure::FIG1, Figure::FIG3, Figure::FIG4, Figure::FIG5];

    /// The figure of [`Figure::ALL`] named `name` (as `--only` spells it, any case), else what
    /// is wrong, listing the names.
    pub fn named(name: &str) -> Result<Figure, String> {
        Figure::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| {
                let names: Vec<&str> = Figure::ALL.iter().map(|f| f.name()).collect();
                format!("no figure `{name}` (the figures: {})", names.join(", "))
            })
    }
}

/// `--only`'s values: [`Figure::ALL`] by name, each with what it shows.
impl clap::ValueEnum for Figure {
    fn value_variants<'a>() -> &'a [Self] {
        &Figure::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.about()))
    }
}

/// The wanted units of a `reproduce` run, in the order of the report (their step checks,
/// tables, figures and sections come in this order; the plan puts [`FigureUnit::runs_first`]
/// units' jobs first). A unit not wanted is `None`: neither planned, analysed nor rendered.
/// Fig. 4 and Fig. 5 are one unit: they are drawn from the same container runs and fits.
pub(crate) struct Units {
    fig1: Option<Fig1Unit>,
    fig3: Option<Fig3Unit>,
    containers: Option<Containers>,
}

/// A fresh unit, if `opts` wants it.
fn wanted<U: FigureUnit + Default>(opts: &Options) -> Option<U> {
    let u = U::default();
    u.wanted(opts).then_some(u)
}

impl Units {
    /// The units `opts` wants, fresh.
    pub(crate) fn new(opts: &Options) -> Units {
        Units {
            fig1: wanted(opts),
            fig3: wanted(opts),
            containers: wanted(opts),
        }
    }

    /// The wanted units, in report order.
    fn each(&self) -> Vec<&dyn FigureUnit> {
        let mut v: Vec<&dyn FigureUnit> = Vec::new();
        v.extend(self.fig1.as_ref().map(|u| u as &dyn FigureUnit));
        v.extend(self.fig3.as_ref().map(|u| u as &dyn FigureUnit));
        v.extend(self.containers.as_ref().map(|u| u as &dyn FigureUnit));
        v
    }

    /// The wanted units, in report order, to change.
    fn each_mut(&mut self) -> Vec<&mut dyn FigureUnit> {
        let mut v: Vec<&mut dyn FigureUnit> = Vec::new();
        v.extend(self.fig1.as_mut().map(|u| u as &mut dyn FigureUnit));
        v.extend(self.fig3.as_mut().map(|u| u as &mut dyn FigureUnit));
        v.extend(self.containers.as_mut().map(|u| u as &mut dyn FigureUnit));
        v
    }

    /// Stage 1, the plan: every unit reads its scene files, then plans; the jobs of
    /// [`FigureUnit::runs_first`] units (the biggest) first, so that the threads finish
    /// together, each group in report order.
    pub(crate) fn plan(&mut self, opts: &Options) -> Result<Plan, Error> {
        for u in self.each_mut() {
            u.load(opts)?;
        }
        if let Some(n) = opts.snapshots {
            if n < 40 {
                return Err(crate::error::ReproduceError::TooFewSnapshots { snapshots: n }.into());
            }
        }
        let mut plan = Plan::default();
        for first in [true, false] {
            for u in self
                .each_mut()
                .into_iter()
                .filter(|u| u.runs_first() == first)
            {
                u.plan(opts, &mut plan)?;
            }
        }
        Ok(plan)
    }

    /// Stage 3, analyse: every unit's runs into its numbers, which it keeps.
    pub(crate) fn analyse(&mut self, runs: &Runs) -> Result<(), Error> {
        for u in self.each_mut() {
            u.analyse(runs)?;
        }
        Ok(())
    }

    /// Stage 4, render: every unit's part of the outputs, in report order; `runs`: every
    /// simulation of the run.
    pub(crate) fn parts(&self, opts: &Options, runs: &[RunEntry]) -> Result<Vec<Part>, Error> {
        self.each().iter().map(|u| u.render(opts, runs)).collect()
    }

    /// Every unit's numbers, with the run's own (`wall`, `runs`).
    pub(crate) fn results(self, wall: f64, runs: Vec<RunEntry>) -> Results {
        let (fig1, fig1_step) = self.fig1.map_or((None, None), Fig1Unit::into_results);
        let (fig3, fig3_step) = self.fig3.map_or((None, None), Fig3Unit::into_results);
        let (fits, variants, container_steps) = self
            .containers
            .map_or((None, Vec::new(), Vec::new()), Containers::into_results);
        Results {
            wall,
            fig1,
            fig3,
            fits,
            variants,
            fig1_step,
            fig3_step,
            container_steps,
            runs,
        }
    }
}

/// Everything a `reproduce` run measured, and nothing rendered: a unit's fields (its numbers,
/// its step-size check), then what every unit shares.
#[derive(Clone, Debug, Default)]
pub struct Results {
    /// Wall time from the start of the run to the end of the analysis.
    pub wall: f64,
    /// Fig. 1's analysis (`None` when Fig. 1 is not wanted).
    pub fig1: Option<Fig1>,
    /// Fig. 3's analysis (`None` when Fig. 3 is not wanted).
    pub fig3: Option<Fig3>,
    /// Fig. 4/5: one fit per container, in file-name order; `None` when neither figure is
    /// wanted.
    pub fits: Option<Vec<ContainerFit>>,
    /// The variants of container (a) that ran, in [`Variant::ALL`] order.
    pub variants: Vec<VariantResult>,
    /// Fig. 1's step-size check (`--check-step`; otherwise `None`).
    pub fig1_step: Option<StepCheck<Fig1Quantity>>,
    /// Fig. 3's step-size check (`--check-step`; otherwise `None`).
    pub fig3_step: Option<StepCheck<Fig3Quantity>>,
    /// The step-size checks of the containers in file-name order (`--check-step`; otherwise
    /// empty).
    pub container_steps: Vec<StepCheck<ContainerQuantity>>,
    /// Every simulation of the run, in plan order (the runs table).
    pub runs: Vec<RunEntry>,
}
