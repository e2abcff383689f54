//! A run into NumPy arrays: `grainchain run`'s run (`run_output::stream`: the scene's recorder,
//! the protected load, the summary; so the numbers are the CLI's bit for bit) streams into a sink that keeps columns in Rust vectors, handed to
//! NumPy without a copy at the end. The GIL is released while the engine runs; at each output the
//! sink takes it back only to look for Ctrl-C (at most every [`SIGNAL_CHECK`]) and to call the
//! Python callback, if any. A run still going in a daemon thread when the interpreter exits
//! cannot take it back: the sink then stops the run quietly ([`Stop::Exiting`]).

use crate::errors;
use crate::scene::{Scene, WORDS};
use grainchain::report::run_output::{
    output_size_check, pulse_rows, stream, track_rows, Cell, PULSE_COLUMNS, TRACK_COLUMNS,
};
use grainchain_engine::{Chain, Frame, Pulses, Row, RunError, Sink, Snapshot, Track};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::time::{Duration, Instant};

/// How often a run looks for a pending signal (Ctrl-C): well inside the half second the user
/// waits, and rare enough that taking the GIL costs nothing measurable (a few hundred times a
/// minute). The check happens at output times, so an output interval that takes longer than
/// this in wall time delays it to the next output.
const SIGNAL_CHECK: Duration = Duration::from_millis(50);

/// Why the sink stopped the run.
enum Stop {
    /// The engine's error.
    Run(RunError),
    /// A Python exception: Ctrl-C (`KeyboardInterrupt`) or the callback's.
    Py(PyErr),
    /// The callback asked to stop (returned a false value other than None).
    Asked,
    /// The interpreter is shutting down (a run in a daemon thread at exit): the thread cannot
    /// attach to it any more, so the run ends and the thread parks (`errors::detached`).
    Exiting,
}

impl From<RunError> for Stop {
    fn from(e: RunError) -> Stop {
        Stop::Run(e)
    }
}

/// Columns of one table, in the order of its CSV header.
#[derive(Default)]
struct Table {
    names: Vec<String>,
    cols: Vec<Vec<f64>>,
}

impl Table {
    fn with(names: &[&str]) -> Table {
        Table {
            names: names.iter().map(|s| s.to_string()).collect(),
            cols: vec![Vec::new(); names.len()],
        }
    }
    fn push(&mut self, row: &[f64]) {
        for (c, x) in self.cols.iter_mut().zip(row) {
            c.push(*x);
        }
    }
    /// A row of `pulses.csv` or `tracks.csv`, every cell a float64.
    fn push_cells(&mut self, row: &[Cell]) {
        for (c, x) in self.cols.iter_mut().zip(row) {
            c.push(x.value());
        }
    }
    /// The columns as a dict of float64 arrays (each vector handed over, not copied).
    fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let d = PyDict::new(py);
        for (n, c) in self.names.into_iter().zip(self.cols) {
            d.set_item(n, PyArray1::from_vec(py, c))?;
        }
        Ok(d)
    }
}

/// What the recorder hands over, kept in columns.
struct Columns<'a> {
    /// energies.csv (empty unless the scene asks for it).
    energies: Table,
    energies_on: bool,
    regions: Vec<String>,
    started: bool,
    /// Snapshots: index, time, one flat vector per field (output-major), the grain numbers.
    snap_index: Vec<i64>,
    snap_time: Vec<f64>,
    snap_values: Vec<Vec<f64>>,
    snap_grains: Vec<i64>,
    pulses: Table,
    tracks: Table,
    callback: Option<&'a Py<PyAny>>,
    last_check: Instant,
    /// The current output's row (for the callback).
    row: Vec<f64>,
    /// Rows of energies.csv and snapshots the run will make (capacity reserved at the first, so
    /// the vectors never grow by doubling: the arrays take their size, not up to twice it).
    rows_expected: usize,
    snapshots_expected: usize,
}

impl Sink for Columns<'_> {
    type Error = Stop;

    fn start(&mut self, regions: &[String]) -> Result<(), Stop> {
        self.regions = regions.to_vec();
        Ok(())
    }

    fn row(&mut self, row: &Row<'_>) -> Result<(), Stop> {
        // The columns of energies.csv, exactly (`grainchain run`): `Row::columns`.
        if !std::mem::replace(&mut self.started, true) && self.energies_on {
            let h = row.columns(&self.regions);
            self.energies = Table {
                cols: vec![Vec::with_capacity(self.rows_expected); h.len()],
                names: h,
            };
        }
        self.row.clear();
        row.values(&mut self.row);
        if self.energies_on {
            self.energies.push(&self.row);
        }
        Ok(())
    }

    fn snapshot(&mut self, s: &Snapshot<'_>) -> Result<(), Stop> {
        if self.snap_values.is_empty() {
            let n = self.snapshots_expected * s.grains.len();
            self.snap_values = vec![Vec::with_capacity(n); s.values.len()];
            self.snap_grains = s.grains.clone().map(|i| s.chain.grain_number(i)).collect();
        }
        self.snap_index.push(s.index as i64);
        self.snap_time.push(s.time);
        for (flat, field) in self.snap_values.iter_mut().zip(s.values) {
            flat.extend_from_slice(field);
        }
        Ok(())
    }

    fn pulses(&mut self, p: &Pulses<'_>) -> Result<(), Stop> {
        for row in pulse_rows(p) {
            self.pulses.push_cells(&row);
        }
        Ok(())
    }

    fn track(&mut self, track: &Track, chain: &Chain) -> Result<(), Stop> {
        for row in track_rows(track, chain) {
            self.tracks.push_cells(&row);
        }
        Ok(())
    }

    fn output_done(&mut self, frame: &Frame) -> Result<(), Stop> {
        // `try_attach`, not `attach`: once the interpreter is finalizing (a daemon thread's run at
        // exit) attaching panics inside PyO3 ("The Python interpreter is not initialized"), and
        // the panic's text went to stderr. `try_attach` gives None instead, and the run stops.
        if let Some(f) = self.callback {
            return Python::try_attach(|py| {
                py.check_signals().map_err(Stop::Py)?;
                let values = PyDict::new(py);
                if self.started {
                    let names: Vec<String> = if self.energies_on {
                        self.energies.names.clone()
                    } else {
                        Vec::new()
                    };
                    for (n, x) in names.iter().zip(&self.row) {
                        values.set_item(n, *x).map_err(Stop::Py)?;
                    }
                }
                let r = f
                    .bind(py)
                    .call1((frame.state.t, values))
                    .map_err(Stop::Py)?;
                // None (no return) goes on; any other value stops when Python calls it false
                // (`False`, `numpy.False_`, 0), and an exception from its `__bool__` propagates.
                if !r.is_none() && !r.is_truthy().map_err(Stop::Py)? {
                    return Err(Stop::Asked);
                }
                Ok(())
            })
            .unwrap_or(Err(Stop::Exiting));
        }
        if self.last_check.elapsed() >= SIGNAL_CHECK {
            self.last_check = Instant::now();
            Python::try_attach(|py| py.check_signals())
                .ok_or(Stop::Exiting)?
                .map_err(Stop::Py)?;
        }
        Ok(())
    }
}

/// Run a scene (a `Scene`, path, TOML text or dict) and return its outputs as a dict of NumPy
/// arrays and dicts (`grainchain.run` wraps it in a `RunResult`).
#[pyfunction]
#[pyo3(signature = (scene, *, on_output = None, allow_large_output = false))]
fn _run<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    on_output: Option<Py<PyAny>>,
    allow_large_output: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let scene = Scene::from_any(scene, allow_large_output)?;
    let s = &scene.inner;
    output_size_check(s, s.path(), WORDS, allow_large_output).map_err(errors::scene)?;
    let mut cols = Columns {
        energies: Table::default(),
        energies_on: s.output().energies,
        regions: Vec::new(),
        started: false,
        snap_index: Vec::new(),
        snap_time: Vec::new(),
        snap_values: Vec::new(),
        snap_grains: Vec::new(),
        // The columns of pulses.csv and tracks.csv, as `grainchain run` writes them.
        pulses: Table::with(&PULSE_COLUMNS),
        tracks: Table::with(&TRACK_COLUMNS),
        callback: on_output.as_ref(),
        last_check: Instant::now(),
        row: Vec::new(),
        rows_expected: (s.outputs() + 1) as usize,
        // As the scene's estimate counts them: every `every`-th output from 0, or the listed
        // ones inside the run.
        snapshots_expected: s.output().snapshots.as_ref().map_or(0, |x| {
            if x.at.is_empty() {
                (s.outputs() / x.every.max(1) + 1) as usize
            } else {
                x.at.iter().filter(|&&k| k <= s.outputs()).count()
            }
        }),
    };
    // The engine runs without the GIL; a panic anywhere in it becomes InternalError. Errors come
    // out as Rust values, made Python exceptions once attached again (`errors::detached`). The
    // run is `grainchain run`'s (`run_output::stream`), into columns instead of files.
    let outcome = errors::detached(py, || -> Result<_, RunError> { stream(s, &mut cols) });
    let (r, summary) = outcome?.map_err(errors::run)?;
    let finished = match r {
        Ok(done) => done,
        Err(Stop::Asked) => false,
        Err(Stop::Run(e)) => return Err(errors::run(e)),
        Err(Stop::Py(e)) => return Err(e),
        // Not reached: a run stopped for the interpreter's exit parks its thread for good in
        // `errors::detached` rather than attach again. Kept exact should that change.
        Err(Stop::Exiting) => {
            return Err(errors::RunError::new_err(
                "the run stopped: the Python interpreter is shutting down",
            ))
        }
    };
    let out = PyDict::new(py);
    out.set_item("scene", s.name())?;
    out.set_item("finished", finished)?;
    out.set_item(
        "energies",
        std::mem::take(&mut cols.energies).into_dict(py)?,
    )?;
    let snaps = PyDict::new(py);
    if let Some(spec) = &s.output().snapshots {
        let rows = cols.snap_index.len();
        let grains = cols.snap_grains.len();
        let mut flats = std::mem::take(&mut cols.snap_values);
        // No snapshot taken (a run stopped before the first): empty arrays of each field.
        flats.resize(spec.fields.len(), Vec::new());
        for (field, flat) in spec.fields.iter().zip(flats) {
            let a = PyArray1::from_vec(py, flat).reshape([rows, grains])?;
            snaps.set_item(field.name(), a)?;
        }
    }
    out.set_item("snapshots", snaps)?;
    out.set_item(
        "snapshot_index",
        PyArray1::from_vec(py, std::mem::take(&mut cols.snap_index)),
    )?;
    out.set_item(
        "snapshot_time",
        PyArray1::from_vec(py, std::mem::take(&mut cols.snap_time)),
    )?;
    out.set_item(
        "snapshot_grains",
        PyArray1::from_vec(py, std::mem::take(&mut cols.snap_grains)),
    )?;
    if s.output().pulses.is_some() {
        out.set_item("pulses", std::mem::take(&mut cols.pulses).into_dict(py)?)?;
    } else {
        out.set_item("pulses", py.None())?;
    }
    if s.output().tracks.is_some() {
        out.set_item("tracks", std::mem::take(&mut cols.tracks).into_dict(py)?)?;
    } else {
        out.set_item("tracks", py.None())?;
    }
    out.set_item(
        "summary",
        pythonize::pythonize(py, &summary)
            .map_err(|e| errors::InternalError::new_err(e.to_string()))?,
    )?;
    Ok(out)
}

/// Add the run names to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_run, m)?)?;
    Ok(())
}
