//! `grainchain reproduce`: every figure of Hong (2005) from the scene files in `scenes/`, as CSV,
//! SVG and a `REPORT.md` that puts each number the paper states beside ours.
//!
//! Figures: `fig1` (heavy-to-light interface), `fig3` (the standard container's leaks at the
//! 280th snapshot), `fig4` (energy remaining in containers (a)-(e), plus the outer-chain checks),
//! `fig5` (power-law fits, the time rescaling alpha per container, and how gamma moves with the
//! fit window and the open choices of the reconstruction). The container layouts are a
//! reconstruction (`../shared/reference/containers.md`); every output says so.
//!
//! A run is four stages, each a module: `plan` (the simulations to run, each named by a typed
//! [`JobKey`]), `jobs` (execute them on `threads` threads; results indexed by job, so
//! they do not depend on scheduling), `analyse` (the numbers of every figure, in
//! [`Results`], with each figure's analysis in `figures` and the step-size check in
//! `step_check`) and `render` (the tables, SVG figures and REPORT.md as pure functions of the
//! results).

mod analyse;
mod figures;
mod jobs;
mod plan;
mod render;
mod step_check;
mod table;
mod variants;

pub use crate::batch::{container_sources, ContainerSource};
pub use crate::error::ReproduceError;
pub use analyse::{Fig1Headline, Fig3Headline, Fig5Headline, Headline, Results, RunEntry};
pub use figures::{ContainerFit, CurveDiff, Fig1, Fig3, PulseOut, VariantResult};
pub use plan::{ContainerRun, JobKey};
pub use step_check::{CheckTarget, Quantity, Side, StepCheck};
pub use table::{Cell, Table};
pub use variants::Variant;

use crate::error::Error;
use std::path::PathBuf;
use std::time::Instant;

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

/// What to run and where to write it.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output directory.
    pub out: PathBuf,
    /// The scene directory (`scenes/`, holding `fig1-heavy-to-light.toml`,
    /// `fig3-standard-container.toml` and `containers/*.toml`).
    pub scenes: PathBuf,
    /// Figures to make; empty: all.
    pub only: Vec<Figure>,
    /// Length of the Fig. 4/5 runs in snapshots (default: the scene files', 4000). Shorter runs
    /// are for quick looks and the golden tests; the report says when it is not the default.
    pub snapshots: Option<u64>,
    /// Also run every figure at an eighth of the step (and a chaos twin of every container) and
    /// report the differences (requirement 6 of the issue). Several minutes.
    pub check_step: bool,
    /// Worker threads for the simulations (default 2; at least 1, at most one per job). The
    /// results do not depend on it.
    pub threads: usize,
    /// Show a progress bar on stderr (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// Sections appended to REPORT.md, rendered by others: the CLI's `reproduce --members N`
    /// runs the containers as an ensemble study first and hands its section in here.
    pub appendix: Vec<String>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            out: PathBuf::from("out/reproduce"),
            scenes: PathBuf::from("scenes"),
            only: Vec::new(),
            snapshots: None,
            check_step: false,
            threads: 2,
            progress: true,
            appendix: Vec::new(),
        }
    }
}

impl Options {
    /// Whether figure `f` is to be made: it is listed in [`Options::only`], or that list is
    /// empty.
    pub fn wants(&self, f: Figure) -> bool {
        self.only.is_empty() || self.only.contains(&f)
    }
}

/// Longest run of the variant studies of container (a), in snapshots: they compare fits over
/// the same window with the default run's first snapshots, and the cost of a run grows with the
/// square of its length (the active window grows with time), so they stop at half the paper's
/// 4000 snapshots.
pub const VARIANT_SNAPSHOTS: u64 = 2000;

pub use crate::batch::scenes::TWIN_EPS;

/// The step-size check compares with a run at `dt / STEP_FACTOR`.
pub const STEP_FACTOR: f64 = 8.0;

/// Everything a `reproduce` run produced: its [`Results`] (also reachable through `Deref`, as
/// `outcome.fig1`) and their rendered text.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Every number the run measured.
    pub results: Results,
    /// The headline numbers of `results` ([`Headline::of`]), as the golden tests snapshot them.
    pub headline: Headline,
    /// The CSV tables written to the output directory, as written.
    pub tables: Vec<Table>,
    /// The text of the `REPORT.md` written to the output directory.
    pub report: String,
}

impl std::ops::Deref for Outcome {
    type Target = Results;
    fn deref(&self) -> &Results {
        &self.results
    }
}

/// Run `reproduce`: plan, execute, analyse, render; CSV, SVG and REPORT.md go into `opts.out`.
pub fn run(opts: &Options) -> Result<Outcome, Error> {
    let started = Instant::now();
    let plan = plan::plan(opts)?;
    let runs = jobs::execute(opts, &plan)?;
    let results = analyse::analyse(&plan, &runs, started)?;
    let rendered = render::render(opts, &results)?;
    render::write(&opts.out, &rendered)?;
    Ok(Outcome {
        headline: Headline::of(&results),
        results,
        tables: rendered.tables,
        report: rendered.report,
    })
}
