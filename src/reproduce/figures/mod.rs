//! The registry of `reproduce`'s figures, each one unit ([`FigureUnit`]) in its own file: the
//! units' modules, the names `--only` takes ([`Figure`]), the units in the order of the report
//! ([`units`]) and the numbers each unit measured ([`Results`], a unit's fields). A new figure is
//! a file here and an entry in this file (its module, its `Figure`, its `Results` field, its
//! line in `units`).
//!
//! Units: `fig1.rs`, `fig3.rs` and `containers/` (Fig. 4 and 5, which share the container runs
//! and fits, with the variants of (a)). Shared by units: `pulses.rs` (pulses in printed grain
//! numbers), `curves.rs` (the comparison of two `E_R` curves).

pub(crate) mod containers;
mod curves;
pub(crate) mod fig1;
pub(crate) mod fig3;
mod pulses;

pub use containers::{CollapsePoint, ContainerFit, ContainerQuantity, Variant, VariantResult};
pub use curves::CurveDiff;
pub(crate) use curves::{curve_diff, ENERGY_FLOOR};
pub use fig1::{Fig1, Fig1Quantity};
pub use fig3::{Fig3, Fig3Quantity, LargestPulse, Side};
pub use pulses::PulseOut;

use super::analyse::RunEntry;
use super::step_check::StepCheck;
use super::unit::FigureUnit;
use containers::Containers;
use fig1::Fig1Unit;
use fig3::Fig3Unit;

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
