//! `grainchain reproduce`: every figure of Hong (2005) from the scene files in `scenes/`, as CSV,
//! SVG and a `REPORT.md` that puts each number the paper states beside ours.
//!
//! Figures: `fig1` (heavy-to-light interface), `fig3` (the standard container's leaks at the
//! 280th snapshot), `fig4` (energy remaining in containers (a)-(e), plus the outer-chain checks),
//! `fig5` (power-law fits, the time rescaling alpha per container, and how gamma moves with the
//! fit window and the open choices of the reconstruction). The container layouts are a
//! reconstruction (`docs/containers.md`); every output says so.
//!
//! Each figure is one unit (`unit.rs`: `FigureUnit`) that plans its jobs, analyses their runs
//! into numbers and renders those numbers: `figures/fig1.rs`, `figures/fig3.rs` and
//! `figures/containers/` (Fig. 4 and 5, which share the container runs). They are registered
//! in `figures/mod.rs`, with the names `--only` takes ([`Figure`]) and the numbers each measured
//! ([`Results`]).
//!
//! A run is four stages over the registered units, each stage a module: `plan` (the simulations
//! to run, each named by a typed [`JobKey`]), `jobs` (execute them on `threads` threads; results
//! indexed by job, so they do not depend on scheduling), `analyse` (every unit's numbers into
//! [`Results`], with their step-size checks, [`StepCheck`]) and `render` (every unit's tables,
//! SVG figures and REPORT.md sections as pure functions of the results, between the shared
//! pieces), then the outputs are written.

mod figures;
mod headline;
mod jobs;
mod options;
mod plan;
mod render;
mod step_check;
mod table;
mod unit;

/// The figures' public types, as the registry (`figures/mod.rs`) exports them.
pub use figures::*;
pub use headline::{Fig1Headline, Fig3Headline, Fig5Headline, Headline};
pub use jobs::RunEntry;
pub use options::{
    check_members, Checked, Figure, Options, Request, MIN_THREADS, SNAPSHOTS, STEP_FACTOR,
    VARIANT_SNAPSHOTS,
};
pub use plan::{ContainerRun, JobKey};
pub use step_check::StepCheck;
pub use table::{Cell, Table};

use crate::batch::scenes::SceneFiles;
use crate::error::Error;
use crate::report::fnv1a;
use crate::report::outdir::{Claim, OutDir};
use figures::Units;
use grainchain_engine::InputError;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

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

/// Run `reproduce`: plan, execute, analyse, render, each stage over the wanted units of the
/// registry; CSV, SVG and REPORT.md go into `opts.out`.
pub fn run(opts: &Options) -> Result<Outcome, Error> {
    let started = Instant::now();
    let mut units = Units::new(opts);
    let plan = units.plan(opts)?;
    let runs = jobs::execute(opts, &plan)?;
    units.analyse(&runs)?;
    let wall = started.elapsed().as_secs_f64();
    let entries = runs.entries();
    let parts = units.parts(opts, &entries)?;
    let rendered = render::render(opts, parts, wall, &entries);
    render::write(&opts.out, &rendered)?;
    let results = units.results(wall, entries);
    Ok(Outcome {
        headline: Headline::of(&results),
        results,
        tables: rendered.tables,
        report: rendered.report,
    })
}

/// Claim the output folder of `opts` as `grainchain reproduce` does (`report::outdir`): it
/// belongs to these options (`members`: the ensemble appendix's size, 0 for none) and to the
/// scene files as parsed ([`scenes_digest`]); the scene folder is never deleted, even inside
/// the output folder.
/// The scene files read for the digest are handed back, so the figures load them without
/// reading them again.
pub fn claim(opts: &Options, members: u64, force: bool) -> Result<(OutDir, SceneFiles), Error> {
    let options = format!(
        "only={:?} snapshots={:?} check_step={} members={members}",
        opts.only, opts.snapshots, opts.check_step
    );
    let (digest, files) = scenes_digest(&opts.scenes)?;
    let inputs = BTreeMap::from([
        ("options".to_string(), fnv1a(options.as_bytes())),
        ("scenes".to_string(), digest),
    ]);
    let dir = OutDir::claim_with(
        &opts.out,
        Claim {
            command: "reproduce",
            inputs,
            force,
            protect: vec![opts.scenes.clone()],
            ..Claim::default()
        },
    )?;
    Ok((dir, files))
}

/// The digest of the scene files `reproduce` reads (`scenes/*.toml` and
/// `scenes/containers/*.toml`, each as parsed: comments and spelling do not count), and the
/// scene files as read, so that nothing reads them again ([`SceneFiles`]).
pub fn scenes_digest(scenes: &Path) -> Result<(String, SceneFiles), Error> {
    // The first thing `reproduce` reads: a missing folder is a usage error that says where the
    // scenes are (issue 38: outside the repository it said "scenes: No such file").
    let unreadable = |dir: &Path, e: std::io::Error| {
        Error::Input(InputError::Invalid {
            file: dir.to_path_buf(),
            key: "--scenes".into(),
            message: format!(
                "cannot read the paper's scene folder ({e}): run from the repository's root, \
                 where `scenes/` and `scenes/containers/` are, or pass --scenes DIR"
            ),
        })
    };
    let (digests, files) = SceneFiles::read_folder(
        &[scenes.to_path_buf(), scenes.join("containers")],
        unreadable,
    )?;
    let mut all = String::new();
    for (f, d) in &digests {
        all.push_str(&format!("{}={d};", f.display()));
    }
    Ok((fnv1a(all.as_bytes()), files))
}
