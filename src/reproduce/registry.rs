//! The registry of `reproduce`'s figures: the names `--only` takes ([`Figure`]), the units that
//! make them ([`units`], in the order of the report) and the numbers each unit measured
//! ([`Results`], a field per unit). A new figure is a file under `figures/` and an entry here.

use super::analyse::RunEntry;
use super::figures::VariantResult;
use super::figures::{containers::Containers, fig1::Fig1Unit, fig3::Fig3Unit};
use super::figures::{ContainerFit, ContainerQuantity, Fig1, Fig1Quantity, Fig3, Fig3Quantity};
use super::step_check::StepCheck;
use super::unit::FigureUnit;

/// The figures `reproduce` can make.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, clap::ValueEnum)]
pub enum Figure {
    /// Fig. 1: a solitary wave from heavy into light grains breaks into a train of solitary
    /// waves (`fig1-heavy-to-light.toml` and its control run).
    Fig1,
    /// Fig. 3: the standard container's leading waves at the figure's snapshot
    /// (`fig3-standard-container.toml`).
    Fig3,
    /// Fig. 4: the energy `E_R` remaining in containers (a)-(e) over time (`containers/*.toml`),
    /// with the outer-chain variants of (a).
    Fig4,
    /// Fig. 5: power-law fits `E_R ~ t^-gamma` of the same container runs, the time rescaling
    /// alpha of each onto (a), and every variant of (a).
    Fig5,
}

impl Figure {
    /// Every figure, in the paper's order.
    pub const ALL: [Figure; 4] = [Figure::Fig1, Figure::Fig3, Figure::Fig4, Figure::Fig5];

    /// Its lower-case name (`fig1` .. `fig5`), as `--only` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Figure::Fig1 => "fig1",
            Figure::Fig3 => "fig3",
            Figure::Fig4 => "fig4",
            Figure::Fig5 => "fig5",
        }
    }
}

/// The units of a `reproduce` run, in the order of the report (their step checks, tables,
/// figures and sections come in this order; the plan puts [`FigureUnit::runs_first`] units'
/// jobs first). Fig. 4 and Fig. 5 are one unit: they are drawn from the same container runs
/// and fits.
pub(crate) fn units() -> Vec<Box<dyn FigureUnit>> {
    vec![
        Box::<Fig1Unit>::default(),
        Box::<Fig3Unit>::default(),
        Box::<Containers>::default(),
    ]
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
    /// The variants of container (a) that ran, in [`super::Variant::ALL`] order.
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
