//! Stage 4, render: [`Results`] into text — the CSV tables, the SVG figures and REPORT.md —
//! by pure functions (nothing here runs or measures anything), then written to the output
//! directory by [`write`].
//!
//! REPORT.md is assembled in `report.rs` from one function per section: the paper comparison
//! (`compare.rs`), each figure's section (`fig1.rs` .. `fig5.rs`), the step-size check
//! (`step_check.rs`), the runs and the ensemble (`ensemble.rs`).

mod compare;
mod fig1;
mod fig3;
mod fig4;
mod fig5;
mod plots;
mod report;
mod step_check;
mod tables;
mod text;

use super::analyse::Results;
use super::table::Table;
use super::Options;
use crate::error::Error;
use crate::report::AtomicFile;
use plots::Svg;
use std::path::Path;

/// The text of a run's outputs.
pub struct Rendered {
    pub tables: Vec<Table>,
    pub svgs: Vec<Svg>,
    pub report: String,
}

/// Every output of `out`.
pub fn render(opts: &Options, out: &Results) -> Result<Rendered, Error> {
    Ok(Rendered {
        tables: tables::all(opts, out),
        svgs: plots::all(opts, out)?,
        report: report::markdown(opts, out),
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
