//! A figure of `reproduce` as one unit: it plans its jobs, analyses their runs into numbers and
//! renders those numbers. The stages of [`super::run`] drive every registered unit
//! ([`super::figures::units`]) through the same three steps.

use super::figures::Results;
use super::jobs::Runs;
use super::plan::Plan;
use super::render::step_check::CheckRow;
use super::render::Svg;
use super::table::Table;
use super::Options;
use crate::error::Error;

/// One figure (or figures sharing their runs) of `reproduce`: plan, analyse, render.
///
/// A unit is made fresh for every `reproduce` run ([`super::figures::units`]); what it reads
/// from the scene files (a pulse rule, the containers found) it keeps for its analysis.
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

    /// Stage 3: its runs into numbers, in its own fields of `out` (with `--check-step` also
    /// its step checks). Every number rendering shows is computed here.
    fn analyse(&self, runs: &Runs, out: &mut Results) -> Result<(), Error>;

    /// Stage 4: its part of the outputs, read from `out` (nothing is computed here but text).
    fn render(&self, opts: &Options, out: &Results) -> Result<Part, Error>;
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
