//! Whole-number arguments. PyO3's own extraction of a `usize`, `u64` or `u32` argument raises a
//! bare `OverflowError` ("can't convert negative int to unsigned") for -1 or 10**30, naming
//! neither the argument nor what it may be. An argument typed [`Whole`] takes any integer as
//! Python gives it (an `int`, or anything `operator.index` takes: NumPy's integers), and its
//! range is checked with the argument's name by the function that uses it, into the package's
//! error for bad arguments. A yes-or-no argument typed [`Flag`] takes `True` or `False` and says
//! so when given anything else.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyInt;

/// An integer argument, not yet checked against its range.
pub struct Whole {
    /// The value, or the nearest end of `i128`'s range beyond it (every range checked here lies
    /// well inside `i128`, so a value clamped there is out of range all the same).
    value: i128,
    /// The value as Python writes it, for the message.
    text: String,
}

impl Whole {
    /// A default value.
    pub fn new(v: u64) -> Whole {
        Whole {
            value: v.into(),
            text: v.to_string(),
        }
    }

    /// The value if it lies in `lo..=hi`, else what is wrong (after the argument's name:
    /// `threads: must be an integer from 1 to 18446744073709551615, got -1`; the library's
    /// own checks say it in the same words).
    pub fn within(&self, lo: u64, hi: u64) -> Result<u64, String> {
        if self.value < i128::from(lo) || self.value > i128::from(hi) {
            return Err(format!(
                "must be an integer from {lo} to {hi}, got {}",
                self.text
            ));
        }
        // In lo..=hi, so it fits.
        Ok(self.value as u64)
    }

    /// As a `usize` of at least `lo`.
    pub fn usize(&self, lo: usize) -> Result<usize, String> {
        self.within(lo as u64, usize::MAX as u64)
            .map(|v| v as usize)
    }

    /// As a `u32` of at least `lo`.
    pub fn u32(&self, lo: u32) -> Result<u32, String> {
        self.within(lo.into(), u32::MAX.into()).map(|v| v as u32)
    }

    /// As a `u64` of at least `lo`.
    pub fn u64(&self, lo: u64) -> Result<u64, String> {
        self.within(lo, u64::MAX)
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for Whole {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Whole> {
        let obj = obj.to_owned();
        // `operator.index`: an int as it is, a NumPy integer as its int; anything else (a float,
        // a str) is a TypeError, which PyO3 prefixes with the argument's name.
        let int = match obj.cast::<PyInt>() {
            Ok(i) => i.clone(),
            Err(_) => obj
                .py()
                .import("operator")?
                .call_method1("index", (&obj,))?
                .cast_into::<PyInt>()?,
        };
        let value = match int.extract::<i128>() {
            Ok(v) => v,
            Err(_) if int.lt(0)? => i128::MIN,
            Err(_) => i128::MAX,
        };
        Ok(Whole {
            value,
            text: int.str()?.to_string(),
        })
    }
}

/// The error of a bad argument `name` outside the protector (whose `DesignError` names its key
/// itself): a `ValueError` reading `name: problem`.
pub fn bad(name: &str) -> impl Fn(String) -> PyErr + '_ {
    move |problem| PyValueError::new_err(format!("{name}: {problem}"))
}

/// A yes-or-no argument: `True` or `False` (or NumPy's `bool_`), nothing else. PyO3's own `bool`
/// refuses an int or a str with "'int' object cannot be converted to 'PyBool'", a Rust type's
/// name; this one says what the argument takes (PyO3 puts the argument's name before it:
/// `argument 'gradients': must be True or False, got int`). Truthiness is not taken: `"no"` and
/// `1` are mistakes, not switches.
pub struct Flag(pub bool);

impl<'a, 'py> FromPyObject<'a, 'py> for Flag {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Flag> {
        obj.extract::<bool>().map(Flag).map_err(|_| {
            let ty = obj
                .get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string());
            PyTypeError::new_err(format!("must be True or False, got {ty}"))
        })
    }
}
