//! The problems catalogue (`grainchain_engine::problems`): names, descriptions, reference values,
//! and a run of a problem's recommended simulation.

use crate::errors;
use grainchain_engine::problems;
use grainchain_engine::{Recorder, Sink};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The names of the catalogue's problems, in catalogue order.
#[pyfunction]
fn problem_names() -> Vec<&'static str> {
    problems::NAMES.to_vec()
}

fn lookup(name: &str) -> PyResult<problems::Problem> {
    problems::by_name(name).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A problem of the catalogue: `{"name", "description", "references": [{"name", "value",
/// "source"}, ...]}`. Raises `ValueError` (listing the known names) for an unknown name.
#[pyfunction]
fn problem<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyDict>> {
    let p = lookup(name)?;
    let d = PyDict::new(py);
    d.set_item("name", p.name())?;
    d.set_item("description", p.description())?;
    let refs = p
        .references()
        .into_iter()
        .map(|r| {
            let x = PyDict::new(py);
            x.set_item("name", r.name)?;
            x.set_item("value", r.value)?;
            x.set_item("source", r.source)?;
            Ok(x)
        })
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("references", refs)?;
    Ok(d)
}

/// Run a problem's recommended simulation (integrator, step, schedule, initial conditions of the
/// catalogue) and return `{"energies": {index, time, kinetic, potential, total, momentum},
/// "displacement", "velocity" (the final state, one value per grain), "summary"}`; `scenes` is
/// the scene directory (the containers read their files there).
#[pyfunction]
#[pyo3(signature = (name, *, scenes = PathBuf::from("scenes")))]
fn run_problem<'py>(py: Python<'py>, name: &str, scenes: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let p = lookup(name)?;
    struct Totals(Vec<[f64; 6]>);
    impl Sink for Totals {
        type Error = grainchain_engine::RunError;
        fn row(&mut self, r: &grainchain_engine::Row<'_>) -> Result<(), Self::Error> {
            let t = r.totals;
            self.0.push([
                r.index as f64,
                r.time,
                t.kinetic,
                t.potential,
                t.total,
                t.momentum,
            ]);
            Ok(())
        }
    }
    let (rows, u, v, summary) = errors::detached(py, || -> Result<_, grainchain_engine::Error> {
        let mut sim = p.simulation(&scenes)?;
        let mut rows = Totals(Vec::new());
        Recorder::new().stream(&mut sim, &mut rows)?;
        let st = sim.state();
        Ok((rows.0, st.u.clone(), st.v.clone(), sim.summary()))
    })?
    .map_err(errors::engine)?;
    let d = PyDict::new(py);
    let e = PyDict::new(py);
    for (k, n) in ["index", "time", "kinetic", "potential", "total", "momentum"]
        .iter()
        .enumerate()
    {
        e.set_item(
            n,
            PyArray1::from_vec(py, rows.iter().map(|r| r[k]).collect()),
        )?;
    }
    d.set_item("energies", e)?;
    d.set_item("displacement", PyArray1::from_vec(py, u))?;
    d.set_item("velocity", PyArray1::from_vec(py, v))?;
    d.set_item(
        "summary",
        pythonize::pythonize(py, &summary)
            .map_err(|e| errors::InternalError::new_err(e.to_string()))?,
    )?;
    Ok(d)
}

/// Add the catalogue's names to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(problem_names, m)?)?;
    m.add_function(wrap_pyfunction!(problem, m)?)?;
    m.add_function(wrap_pyfunction!(run_problem, m)?)?;
    Ok(())
}
