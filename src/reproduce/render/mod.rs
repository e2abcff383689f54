//! Stage 4, render: every unit's part of the outputs ([`FigureUnit::render`], pure functions of
//! [`Results`]: nothing here runs or measures anything), put together with the shared pieces,
//! then written to the output directory by [`write`].
//!
//! Shared: REPORT.md's header, the paper comparison table (each unit adds its rows) and the runs
//! section (`report.rs`), `runs.csv` (`tables.rs`), the step-size check (`step_check.rs`), what
//! the SVG figures share (`plots.rs`) and number formatting (`text.rs`).

pub(crate) mod plots;
mod report;
pub(crate) mod step_check;
mod tables;
pub(crate) mod text;

use super::figures::Results;
use super::table::Table;
use super::unit::{FigureUnit, Part};
use super::Options;
use crate::error::Error;
use crate::report::AtomicFile;
use std::path::Path;

/// An SVG file's name and text.
pub(crate) struct Svg {
    /// File name in the output directory.
    pub name: &'static str,
    /// The SVG text.
    pub text: String,
}

/// The text of a run's outputs.
pub struct Rendered {
    /// The CSV tables: every unit's in registry order, then `runs.csv` and `check_step.csv`.
    pub tables: Vec<Table>,
    /// The SVG figures, in registry order.
    pub(crate) svgs: Vec<Svg>,
    /// REPORT.md.
    pub report: String,
}

/// Every output of `out`: the parts of `units` (registry order) and the shared pieces.
pub fn render(
    opts: &Options,
    units: &[Box<dyn FigureUnit>],
    out: &Results,
) -> Result<Rendered, Error> {
    let parts = units
        .iter()
        .map(|u| u.render(opts, out))
        .collect::<Result<Vec<Part>, Error>>()?;
    let report = report::markdown(opts, out, &parts);
    let mut tables = Vec::new();
    let mut svgs = Vec::new();
    let mut checks = Vec::new();
    for p in parts {
        tables.extend(p.tables);
        svgs.extend(p.svgs);
        checks.extend(p.checks);
    }
    tables.push(tables::runs(out));
    if !checks.is_empty() {
        tables.push(step_check::table(&checks));
    }
    Ok(Rendered {
        tables,
        svgs,
        report,
    })
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
