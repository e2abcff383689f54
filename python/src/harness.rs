//! The harness from Python (the `grainchain` crate): ensemble studies and the reproduction of
//! the paper, into an output folder, by the very functions `grainchain study` and `grainchain
//! reproduce` call (`grainchain::commands`: the size guard, the scene checks, the folder claim,
//! the jobs, the merge), silent, with Python's words; what they did comes back as a dict.

use crate::args::{bad, Whole};
use crate::errors;
use crate::scene::WORDS;
use grainchain::commands::{self, Caller};
use grainchain::reproduce::{self as rp, Figure, Request};
use grainchain::study::Shard;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Python as the commands' caller: silent (what was done is returned), and its words are its
/// arguments.
const PYTHON: Caller = Caller {
    speaks: false,
    words: WORDS,
};

/// Run an ensemble study (a sweep file, see `studies/`) into `out` (default
/// `out/study-<name>`), as `grainchain study` does: member files in `out/members/`, then the
/// merged tables (CSV), figures (SVG) and STUDY.md, unless `shard` ("K/N") runs one part only.
/// `resume` keeps member files already written for this sweep. Returns `{"out", "jobs", "ran",
/// "kept", "rerun", "wall", "job_seconds", "merged", "missing"}`; read the results with
/// `grainchain.read_study(out)`. The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (sweep, *, out = None, threads = None, shard = None, resume = false, force = false, allow_large_output = false))]
#[allow(clippy::too_many_arguments)]
fn study<'py>(
    py: Python<'py>,
    sweep: PathBuf,
    out: Option<PathBuf>,
    threads: Option<Whole>,
    shard: Option<&str>,
    resume: bool,
    force: bool,
    allow_large_output: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let shard = shard
        .map(|s| s.parse::<Shard>())
        .transpose()
        .map_err(|e| PyValueError::new_err(format!("shard: {e}")))?;
    let threads = threads
        .map(|t| t.u64(1))
        .transpose()
        .map_err(bad("threads"))?;
    let opts = commands::study::Options {
        sweep,
        out,
        shard,
        resume,
        threads,
        force,
        allow_large_output,
        ..Default::default()
    };
    let d = errors::detached(py, || commands::study::study(&opts, &PYTHON))?
        .map_err(errors::harness)?;
    let r = PyDict::new(py);
    r.set_item("out", d.out.display().to_string())?;
    r.set_item("jobs", d.jobs)?;
    r.set_item("ran", d.run.ran)?;
    r.set_item("kept", d.run.kept)?;
    r.set_item("rerun", d.run.rerun)?;
    r.set_item("wall", d.run.wall)?;
    r.set_item("job_seconds", d.run.job_seconds)?;
    r.set_item("merged", d.merged)?;
    r.set_item("missing", d.missing)?;
    Ok(r)
}

/// Reproduce the paper (Hong 2005) into `out`, as `grainchain reproduce` does: every figure as
/// CSV and SVG and REPORT.md. `only`: figure names (`fig1`, `fig3`, `fig4`, `fig5`, ...);
/// `snapshots`: length of the Fig. 4/5 runs (default the scene files', 4000). Returns
/// `{"out", "runs", "report"}` (the number of simulations and REPORT.md's text).
#[pyfunction]
#[pyo3(
    signature = (*, out = PathBuf::from("out/reproduce"), scenes = PathBuf::from("scenes"), only = None, snapshots = None, threads = Whole::new(2), force = false),
    text_signature = "(*, out=..., scenes=..., only=None, snapshots=None, threads=2, force=False)"
)]
#[allow(clippy::too_many_arguments)]
fn reproduce<'py>(
    py: Python<'py>,
    out: PathBuf,
    scenes: PathBuf,
    only: Option<Vec<String>>,
    snapshots: Option<Whole>,
    threads: Whole,
    force: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let only = only
        .unwrap_or_default()
        .iter()
        .map(|s| Figure::named(s))
        .collect::<Result<Vec<_>, _>>()
        .map_err(bad("only"))?;
    // Any Python integer into the library's range (its bounds, `reproduce::SNAPSHOTS` and
    // `MIN_THREADS`); `Request::check` holds the rules and checks them again.
    let threads = threads
        .within(rp::MIN_THREADS, u64::MAX)
        .map_err(bad("threads"))?;
    let snapshots = snapshots
        .map(|n| n.within(rp::SNAPSHOTS.0, rp::SNAPSHOTS.1))
        .transpose()
        .map_err(bad("snapshots"))?;
    let request = Request {
        out: out.clone(),
        scenes,
        only,
        snapshots,
        check_step: false,
        threads,
        members: 0,
        force,
    };
    let o = errors::detached(py, || commands::reproduce::reproduce(request, &PYTHON))?
        .map_err(errors::harness)?;
    let r = PyDict::new(py);
    r.set_item("out", out.display().to_string())?;
    r.set_item("runs", o.runs.len())?;
    r.set_item("report", o.report)?;
    Ok(r)
}

/// Add the harness's names to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add_function(wrap_pyfunction!(reproduce, m)?)?;
    Ok(())
}
