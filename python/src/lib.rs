//! `grainchain._grainchain`: the Python bindings of grainchain (PyO3 + rust-numpy), on the
//! engine's public API (`grainchain_engine`). The Python package `grainchain`
//! (`python/grainchain/__init__.py`) re-exports these names and wraps a run's dict in a
//! `RunResult`; `_grainchain.pyi` types them.
//!
//! The layout: [`errors`] (the exception classes and the mapping of every Rust error onto them),
//! [`args`] (whole-number arguments, their range checked with their name),
//! [`scene`] (scenes from a file, a TOML string or a dict, `check`), [`scene_dict`] (a dict into
//! TOML, every bad value named by its key), [`run`] (a run into NumPy arrays, the callback,
//! Ctrl-C), [`analysis`], [`catalogue`] (the problems), [`protector`] (granular protectors'
//! designs evaluated, one or a batch) and [`harness`] (studies and `reproduce`, from the
//! `grainchain` crate).

use pyo3::prelude::*;

mod analysis;
mod args;
mod catalogue;
mod errors;
mod harness;
mod protector;
mod run;
mod scene;
mod scene_dict;

/// Raise a Rust panic inside the bindings' panic guard (for the test that a panic becomes
/// `grainchain.InternalError`, never an abort). Not part of the public API.
#[pyfunction]
fn _panic_for_test(message: &str) -> PyResult<()> {
    errors::guard::<()>(|| panic!("{message}"))
}

/// The compiled module.
#[pymodule]
fn _grainchain(m: &Bound<'_, PyModule>) -> PyResult<()> {
    grainchain::set_revision(grainchain_revision::GIT);
    errors::register(m)?;
    scene::register(m)?;
    run::register(m)?;
    analysis::register(m)?;
    catalogue::register(m)?;
    harness::register(m)?;
    protector::register(m)?;
    m.add_function(wrap_pyfunction!(_panic_for_test, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
