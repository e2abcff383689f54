//! A figure of `reproduce` as one unit: it plans its jobs, analyses their runs into numbers and
//! renders those numbers, which it keeps until the run ends. The registry
//! (`figures/mod.rs`: `Units`) drives every wanted unit through the same stages.

use super::jobs::{RunEntry, Runs};
use super::options::Options;
use super::plan::Plan;
use super::render::step_check::CheckRow;
use super::table::Table;
use crate::error::Error;

/// One figure (or figures sharing their runs) of `reproduce`: plan, analyse, render.
///
/// A unit is made fresh for every `reproduce` run; what it reads from the scene files (a pulse
/// rule, the containers found) it keeps for its analysis, and what it measures for its render
/// and for the run's results (each unit's `into_results`, which the registry calls).
pub(crate) trait FigureUnit {
    /// Whether `opts` asks for it (a unit not wanted is neither planned, analysed nor
    /// rendered).
    fn wanted(&self, opts: &Options) -> bool;

    /// Whether its jobs go before every other unit's (the long runs, so that the threads
    /// finish together). Units of equal rank keep the registry's order.
    fn runs_first(&self) -> bool {
        false
    }

    /// Stage 1, first half: read its scene files (every unit's are read, in registry order,
    /// before any unit plans).
    fn load(&mut self, opts: &Options) -> Result<(), Error>;

    /// Stage 1: add its jobs to `plan` (building every scene, so a bad scene fails before
    /// anything runs).
    fn plan(&mut self, opts: &Options, plan: &mut Plan) -> Result<(), Error>;

    /// Stage 3: its runs into numbers, kept in the unit (with `--check-step` also its step
    /// checks). Every number rendering shows is computed here.
    fn analyse(&mut self, runs: &Runs) -> Result<(), Error>;

    /// Stage 4: its part of the outputs, from its numbers and `runs`, every simulation of the
    /// run (nothing is computed here but text).
    fn render(&self, opts: &Options, runs: &[RunEntry]) -> Result<Part, Error>;
}

/// A unit's part of the outputs; the render stage puts the parts of all units together in
/// registry order, between the shared pieces (REPORT.md's header, the runs, the step-size
/// check).
#[derive(Default)]
pub(crate) struct Part {
    /// Its rows of the table "Every number the paper states, beside ours" (markdown lines).
    pub compare: String,
    /// Its sections of REPORT.md.
    pub section: String,
    /// Its CSV tables.
    pub tables: Vec<Table>,
    /// Its SVG figures.
    pub svgs: Vec<Svg>,
    /// Its rows of the step-size check (`--check-step`; empty without).
    pub checks: Vec<CheckRow>,
}

/// An SVG file's name and text.
pub(crate) struct Svg {
    /// File name in the output directory.
    pub name: &'static str,
    /// The SVG text.
    pub text: String,
}
