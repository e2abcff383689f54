//! The harness from Python (the `grainchain` crate): ensemble studies and the reproduction of
//! the paper, into an output folder, as `grainchain study` and `grainchain reproduce` make them.
//! The steps are the CLI's (`src/main.rs`: the size guard, the scene checks, the folder claim,
//! the jobs, the merge), without the printing; what they did comes back as a dict.

use crate::args::{bad, Whole};
use crate::errors;
use crate::scene::WORDS;
use grainchain::error::Error;
use grainchain::report::outdir::files_with;
use grainchain::study as st;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// What a study did.
struct StudyDone {
    ran: usize,
    kept: usize,
    rerun: Vec<String>,
    jobs: usize,
    wall: f64,
    job_seconds: f64,
    merged: bool,
    missing: Vec<String>,
    out: PathBuf,
}

/// `grainchain study SWEEP [--out] [--shard] [--resume] [--threads] [--force]
/// [--allow-large-output]` (then the merge, unless a shard).
fn study_steps(
    sweep: &Path,
    out: Option<PathBuf>,
    shard: Option<st::Shard>,
    threads: usize,
    resume: bool,
    force: bool,
    allow_large_output: bool,
) -> Result<StudyDone, Error> {
    let sf = st::SweepFile::load(sweep)?;
    if let Some(e) = sf
        .size_refusal(sweep, WORDS)
        .filter(|_| !allow_large_output)
    {
        return Err(e.into());
    }
    let out = out.unwrap_or_else(|| PathBuf::from(format!("out/study-{}", sf.sweep.name)));
    let jobs = st::plan(&sf).len();
    st::check_scenes(&sf)?;
    let dir = st::claim(&sf, sweep, &out, shard, force)?;
    let opts = st::Options {
        out: out.clone(),
        shard: shard.unwrap_or(st::Shard::ALL),
        threads,
        resume,
        progress: false,
    };
    let r = st::run_jobs(&sf, &opts)?;
    let mut done = StudyDone {
        ran: r.ran,
        kept: r.kept,
        rerun: r.rerun,
        jobs,
        wall: r.wall,
        job_seconds: r.job_seconds,
        merged: false,
        missing: Vec::new(),
        out: out.clone(),
    };
    if shard.is_none() {
        let merged = st::merge_with(&sf, std::slice::from_ref(&out), &out, false)?;
        dir.finish(&files_with(&out, &[".csv", ".svg", ".md"])?)?;
        done.merged = true;
        done.missing = merged.missing;
    }
    Ok(done)
}

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
        .map(|s| s.parse::<st::Shard>())
        .transpose()
        .map_err(|e| PyValueError::new_err(format!("shard: {e}")))?;
    let threads = match threads {
        Some(t) => t.usize(1).map_err(bad("threads"))?,
        None => std::thread::available_parallelism().map_or(2, |n| n.get()),
    };
    let d = errors::detached(py, || {
        study_steps(
            &sweep,
            out,
            shard,
            threads,
            resume,
            force,
            allow_large_output,
        )
    })?
    .map_err(errors::harness)?;
    let r = PyDict::new(py);
    r.set_item("out", d.out.display().to_string())?;
    r.set_item("jobs", d.jobs)?;
    r.set_item("ran", d.ran)?;
    r.set_item("kept", d.kept)?;
    r.set_item("rerun", d.rerun)?;
    r.set_item("wall", d.wall)?;
    r.set_item("job_seconds", d.job_seconds)?;
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
    use clap::ValueEnum;
    let only = only
        .unwrap_or_default()
        .iter()
        .map(|s| grainchain::reproduce::Figure::from_str(s, true))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PyValueError::new_err(format!("only: {e}")))?;
    let threads = threads.usize(1).map_err(bad("threads"))?;
    // At least 40 snapshots: the bound of the CLI's `--snapshots` (`range(40..)`), kept the same.
    let snapshots = snapshots
        .map(|n| n.u64(40))
        .transpose()
        .map_err(bad("snapshots"))?;
    let opts = grainchain::reproduce::Options {
        appendix: Vec::new(),
        only,
        out: out.clone(),
        scenes,
        snapshots,
        check_step: false,
        threads,
        progress: false,
    };
    let (runs, report) = errors::detached(py, || -> Result<_, Error> {
        // The CLI's claim (`members = 0`: no ensemble appendix).
        let dir = grainchain::reproduce::claim(&opts, 0, force)?;
        let o = grainchain::reproduce::run(&opts)?;
        dir.finish(&files_with(&opts.out, &[".csv", ".svg", ".md"])?)?;
        Ok((o.runs.len(), o.report.clone()))
    })?
    .map_err(errors::harness)?;
    let r = PyDict::new(py);
    r.set_item("out", out.display().to_string())?;
    r.set_item("runs", runs)?;
    r.set_item("report", report)?;
    Ok(r)
}

/// Add the harness's names to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add_function(wrap_pyfunction!(reproduce, m)?)?;
    Ok(())
}
