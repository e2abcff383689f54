//! `grainchain reproduce`: every figure of Hong (2005) from the scene files in `scenes/`, as CSV,
//! SVG and a `REPORT.md` that puts each number the paper states beside ours.
//!
//! Figures: `fig1` (heavy-to-light interface), `fig3` (the standard container's leaks at the
//! 280th snapshot), `fig4` (energy remaining in containers (a)-(e), plus the outer-chain checks),
//! `fig5` (power-law fits, the time rescaling alpha per container, and how gamma moves with the
//! fit window and the open choices of the reconstruction). The container layouts are a
//! reconstruction (`../shared/reference/containers.md`); every output says so.
//!
//! A run is four stages, each a module: [`plan`] (the simulations to run, each named by a typed
//! [`plan::JobKey`]), [`jobs`] (execute them on `threads` threads; results indexed by job, so
//! they do not depend on scheduling), [`analyse`] (the numbers of every figure, in
//! [`analyse::Results`], with each figure's analysis in [`figures`] and the step-size check in
//! [`step_check`]) and `render` (the tables, SVG figures and REPORT.md as pure functions of the
//! results).

/// The analysis is a library module of its own ([`crate::analysis`]); re-exported here for the
/// figures that use it.
pub use crate::analysis;
pub mod analyse;
mod ensemble;
pub mod figures;
pub mod jobs;
pub mod plan;
mod render;
pub mod scenes;
pub mod step_check;
pub mod table;
pub mod variants;

pub use analyse::{Fig1Headline, Fig3Headline, Fig5Headline, Headline, Results, RunEntry};
pub use plan::{container_sources, ContainerSource};

use crate::error::Error;
use std::path::PathBuf;
use std::time::Instant;
use table::Table;

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
    /// Also run every container as an ensemble of this many members (striker speed x (1 + k
    /// 1e-12), multirate 16 with margin 20, as `grainchain study`) and give gamma and alpha with
    /// intervals from the spread over members (0: no ensemble). Member files and the study's
    /// tables go to `<out>/ensemble/`.
    pub members: u64,
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
            members: 0,
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

/// Relative change of the striker's speed in the chaos twin: far below any integrator error, so
/// whatever it changes no step size can pin down.
pub const TWIN_EPS: f64 = 1e-12;

/// The step-size check compares with a run at `dt / STEP_FACTOR`.
pub const STEP_FACTOR: f64 = 8.0;

/// Paper values (Hong 2005).
pub mod paper {
    /// Fig. 5: the universal exponent.
    pub const GAMMA: f64 = 0.7055;
    /// Fig. 5: time rescaling per container ((b) is not rescaled; (d) is 2/9 in the caption).
    pub const ALPHA: [(&str, f64); 5] =
        [("a", 1.0), ("b", 1.0), ("c", 2.0), ("d", 0.22), ("e", 9.0)];
    /// Fig. 3: the leading wave leaving the container at the right, % of the incident energy.
    pub const RIGHT_PERCENT: f64 = 3.3;
    /// Fig. 3: the leading wave leaving the container at the left, % of the incident energy.
    pub const LEFT_PERCENT: f64 = 7.7;
    /// Fig. 1: the number of transmitted waves is "about the mass ratio".
    pub const MASS_RATIO: f64 = 10.0;
    /// Fig. 3 text: a solitary wave is about 5 grains wide.
    pub const WAVE_GRAINS: f64 = 5.0;
    /// Fig. 5: A = 65.31 alpha^gamma (normalisation unstated).
    pub const A: f64 = 65.31;

    /// The paper's alpha of the container with key `key` (`"a"` .. `"e"`, from [`ALPHA`]);
    /// `None` for any other key.
    pub fn alpha(key: &str) -> Option<f64> {
        ALPHA.iter().find(|(k, _)| *k == key).map(|(_, a)| *a)
    }
}

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
