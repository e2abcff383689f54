//! Stage 4, render: every unit's part of the outputs ([`super::unit::FigureUnit::render`], pure
//! functions of the numbers each unit keeps: nothing here runs or measures anything), put
//! together with the shared pieces, then written to the output directory by [`write`].
//!
//! Shared: REPORT.md's header, the paper comparison table (each unit adds its rows) and the runs
//! section (`report.rs`), `runs.csv` (`tables.rs`), the step-size check (`step_check.rs`), what
//! the SVG figures share (`plots.rs`) and number formatting (`text.rs`).

pub(crate) mod plots;
mod report;
pub(crate) mod step_check;
mod tables;
pub(crate) mod text;

use super::jobs::RunEntry;
use super::options::Options;
use super::table::Table;
use super::unit::{Part, Svg};
use crate::error::Error;
use crate::report::AtomicFile;
use std::path::Path;

/// The text of a run's outputs.
pub struct Rendered {
    /// The CSV tables: every unit's in registry order, then `runs.csv` and `check_step.csv`.
    pub tables: Vec<Table>,
    /// The SVG figures, in registry order.
    pub(crate) svgs: Vec<Svg>,
    /// REPORT.md.
    pub report: String,
}

/// Every output of a run: the units' `parts` (registry order) and the shared pieces; `wall`: the
/// run's time to the end of its analysis, `runs`: its simulations.
pub(crate) fn render(opts: &Options, parts: Vec<Part>, wall: f64, runs: &[RunEntry]) -> Rendered {
    let report = report::markdown(opts, wall, runs, &parts);
    let mut tables = Vec::new();
    let mut svgs = Vec::new();
    let mut checks = Vec::new();
    for p in parts {
        tables.extend(p.tables);
        svgs.extend(p.svgs);
        checks.extend(p.checks);
    }
    tables.push(tables::runs(runs));
    if !checks.is_empty() {
        tables.push(step_check::table(&checks));
    }
    Rendered {
        tables,
        svgs,
        report,
    }
}

/// Write `r` into `dir`: the tables, the figures, then REPORT.md.
pub fn write(dir: &Path, r: &Rendered) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    for t in &r.tables {
        t.write(dir)?;
    }
    for s in &r.svgs {
        AtomicFile::write_all(dir.join(s.name), s.text.as_bytes())?;
    }
    AtomicFile::write_all(dir.join("REPORT.md"), r.report.as_bytes())
}
