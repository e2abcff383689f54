//! (filled in below)
use pyo3::prelude::*;

/// Add this part's names to the module.
pub fn register(_m: &Bound<'_, PyModule>) -> PyResult<()> {
    Ok(())
}
