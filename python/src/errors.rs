//! The exception classes and the mapping of every Rust error onto them. The message is always
//! the Rust error's `Display`, the text the CLI prints after `error: `; the fields that name the
//! place (file and key of a scene error; time, step and grain of a blow-up) are also attributes.

use grainchain_engine::{InputError as EngineSceneError, RunError as EngineRunError, StepError};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};

create_exception!(
    grainchain,
    SceneError,
    PyValueError,
    "A scene that cannot be used: the message names the file, the key and what is wrong (the \
     text of `grainchain check`). Attributes: `file` (str), `key` (str, or None for a parse \
     error)."
);
create_exception!(
    grainchain,
    DesignError,
    PyValueError,
    "A protector design, load or setting that cannot be evaluated: the message names the place \
     (`beads[2]`, `designs[1][2]`, indices into your lists, from 0) and the key (`material`, \
     `diameter`, `striker.material`, `speed`, `need`, ...) and says what is wrong. Attributes: \
     `design` (int index into the batch, or None), `bead` (int index into the design, or None), \
     `key` (str)."
);
create_exception!(
    grainchain,
    RunError,
    PyRuntimeError,
    "A run that could not be set up or failed (invalid run settings, a recorder request outside \
     the chain)."
);
create_exception!(
    grainchain,
    BlowUpError,
    RunError,
    "A numerical blow-up: a non-finite displacement or velocity, an energy error over the bound, \
     or an adaptive step that fell below its smallest size. Attributes: `time` (float), `step` \
     (int), `grain` (int, the printed grain number)."
);
create_exception!(
    grainchain,
    StudyError,
    PyRuntimeError,
    "A study, `reproduce` or output folder that failed (the harness's error text)."
);
create_exception!(
    grainchain,
    InternalError,
    PyRuntimeError,
    "A bug in grainchain: a Rust panic, caught at the boundary and turned into this exception \
     (never an abort of the Python process). Please report it with the message."
);

/// Add the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("RunError", py.get_type::<RunError>())?;
    m.add("DesignError", py.get_type::<DesignError>())?;
    m.add("BlowUpError", py.get_type::<BlowUpError>())?;
    m.add("StudyError", py.get_type::<StudyError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    Ok(())
}

/// Set attributes on a fresh exception (its class is ours, so setting them cannot fail but for
/// lack of memory, which is then the error raised).
fn with_attrs(err: PyErr, attrs: &[(&str, Py<PyAny>)]) -> PyErr {
    Python::attach(|py| {
        let v = err.value(py);
        for (k, x) in attrs {
            if let Err(e) = v.setattr(*k, x) {
                return e;
            }
        }
        err
    })
}

/// A scene error as `grainchain.SceneError`.
pub fn scene(e: EngineSceneError) -> PyErr {
    let msg = e.to_string();
    let (file, key) = match &e {
        EngineSceneError::Read { file, .. } | EngineSceneError::Parse { file, .. } => {
            (file.display().to_string(), None)
        }
        EngineSceneError::Invalid { file, key, .. } => {
            (file.display().to_string(), Some(key.clone()))
        }
    };
    Python::attach(|py| {
        with_attrs(
            SceneError::new_err(msg),
            &[
                ("file", file.into_pyobject(py).unwrap().into_any().unbind()),
                ("key", key.into_pyobject(py).unwrap().into_any().unbind()),
            ],
        )
    })
}

/// A bad protector design as `grainchain.DesignError`: the message is `AT: KEY: PROBLEM` (the
/// engine's `what: problem` when there is no `at`; `AT: PROBLEM` when the key is empty).
pub fn design_error(
    design: Option<usize>,
    bead: Option<usize>,
    key: &str,
    at: Option<&str>,
    problem: &str,
) -> PyErr {
    let msg = match (at, key.is_empty()) {
        (Some(a), false) => format!("{a}: {key}: {problem}"),
        (Some(a), true) => format!("{a}: {problem}"),
        (None, _) => format!("{key}: {problem}"),
    };
    Python::attach(|py| {
        with_attrs(
            DesignError::new_err(msg),
            &[
                (
                    "design",
                    design.into_pyobject(py).unwrap().into_any().unbind(),
                ),
                ("bead", bead.into_pyobject(py).unwrap().into_any().unbind()),
                ("key", key.into_pyobject(py).unwrap().into_any().unbind()),
            ],
        )
    })
}

/// A run error as `grainchain.BlowUpError` (with time, step and grain) or `grainchain.RunError`.
pub fn run(e: EngineRunError) -> PyErr {
    run_prefixed(e, "")
}

/// [`run`] with `prefix` before the message (a batch's `designs[k]: `).
pub fn run_prefixed(e: EngineRunError, prefix: &str) -> PyErr {
    let msg = format!("{prefix}{e}");
    let place = match &e {
        EngineRunError::EnergyDrift {
            time, step, grain, ..
        }
        | EngineRunError::Step(StepError::NonFinite { time, step, grain })
        | EngineRunError::Step(StepError::StepSizeUnderflow {
            time, step, grain, ..
        }) => Some((*time, *step, *grain)),
        EngineRunError::Settings(_) | EngineRunError::Chain(_) => None,
    };
    match place {
        Some((time, step, grain)) => Python::attach(|py| {
            with_attrs(
                BlowUpError::new_err(msg),
                &[
                    ("time", time.into_pyobject(py).unwrap().into_any().unbind()),
                    ("step", step.into_pyobject(py).unwrap().into_any().unbind()),
                    (
                        "grain",
                        grain.into_pyobject(py).unwrap().into_any().unbind(),
                    ),
                ],
            )
        }),
        None => RunError::new_err(msg),
    }
}

/// An error of the engine's spanning kind.
pub fn engine(e: grainchain_engine::Error) -> PyErr {
    match e {
        grainchain_engine::Error::Input(s) => scene(s),
        grainchain_engine::Error::Run(r) => run(r),
        grainchain_engine::Error::Chain(c) => chain(c),
    }
}

/// A chain the builder refuses: a `ValueError` (bad arguments), with the builder's text.
pub fn chain(e: grainchain_engine::ChainError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// An error of the harness (studies, reproduce, output folders): scene and run errors keep their
/// own classes, an option out of its range is a `ValueError` (`threads: ...`), the rest is
/// `grainchain.StudyError`.
pub fn harness(e: grainchain::error::Error) -> PyErr {
    match e {
        grainchain::error::Error::Input(s) => scene(s),
        grainchain::error::Error::Run(r) => run(r),
        u @ grainchain::error::Error::Usage { .. } => PyValueError::new_err(u.to_string()),
        other => StudyError::new_err(other.to_string()),
    }
}

/// Run `f`, turning a Rust panic into `grainchain.InternalError` with the panic's message. (PyO3
/// would raise its own `PanicException`, a `BaseException` that `except Exception` does not
/// catch; a library error should be an ordinary exception.) The `InternalError` is made lazily:
/// no Python object until it is raised, so `f` may run detached ([`detached`]).
pub fn guard<T>(f: impl FnOnce() -> T) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => Ok(r),
        Err(payload) => {
            let what = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic without a message".to_string());
            Err(InternalError::new_err(format!(
                "internal error (a Rust panic; please report it): {what}"
            )))
        }
    }
}

/// Run `f` detached from the interpreter (other Python threads go on while the engine works), its
/// panics caught by [`guard`]. `f` returns Rust values and Rust errors, made Python objects by the
/// caller once attached again: making one attaches, and the thread must not attach at exit.
///
/// At interpreter exit a daemon thread's run may still be going. Attaching then panicked inside
/// PyO3 ("The Python interpreter is not initialized"), and reattaching at the end of the detached
/// stretch is worse: CPython before 3.14 ends such a thread with `pthread_exit`, whose forced
/// unwind through PyO3's panic guard aborted the process ("FATAL: exception not rethrown"). So
/// when `f` returns to a finalizing interpreter the thread parks for good instead, as CPython
/// 3.14 and PyO3's own `PyGILState_Ensure` do with such a thread; the process exits around it.
pub fn detached<T: Send>(py: Python<'_>, f: impl Send + FnOnce() -> T) -> PyResult<T> {
    py.detach(|| {
        let r = guard(f);
        if finalizing() {
            loop {
                std::thread::park();
            }
        }
        r
    })
}

/// Whether the interpreter is shutting down: `Py_IsInitialized` turns 0 where finalization starts
/// (`Py_FinalizeEx` clears it where it sets the finalizing flag; `Py_IsFinalizing` is not in the
/// stable ABI before 3.13, and this module is built for 3.9 on). Safe to call detached.
pub fn finalizing() -> bool {
    // SAFETY: `Py_IsInitialized` reads a flag of the runtime; CPython allows it at any time,
    // attached or not (PyO3's `try_attach` calls it before attaching).
    unsafe { pyo3::ffi::Py_IsInitialized() == 0 }
}
