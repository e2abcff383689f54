//! The analysis of the remaining energy on NumPy arrays (`grainchain_engine::analysis`): log
//! bins, the power-law fit with its interval, the leak onset, the collapse factor alpha,
//! ensemble statistics and the local slope. Arrays are read in place when contiguous.

use crate::args::{bad, Whole};
use grainchain_engine::analysis::{self, ensemble, LogPoint};
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A 1-D float64 array as a vector (a copy only when it is not contiguous).
fn vec1(a: &PyReadonlyArray1<'_, f64>) -> Vec<f64> {
    a.as_slice()
        .map(|s| s.to_vec())
        .unwrap_or_else(|_| a.as_array().to_vec())
}

/// The rows of a 2-D float64 array (members x snapshots).
fn rows2(a: &PyReadonlyArray2<'_, f64>) -> Vec<Vec<f64>> {
    a.as_array()
        .rows()
        .into_iter()
        .map(|r| r.to_vec())
        .collect()
}

/// `hi` defaulting to the last index, both checked against the curve.
fn range(n: usize, lo: &Whole, hi: Option<&Whole>) -> PyResult<(usize, usize)> {
    let lo = lo.usize(0).map_err(bad("lo"))?;
    let hi = match hi {
        Some(h) => h.usize(0).map_err(bad("hi"))?,
        None => n.saturating_sub(1),
    };
    if n == 0 || lo > hi || hi >= n {
        return Err(PyValueError::new_err(format!(
            "snapshots lo = {lo} .. hi = {hi} are not inside a curve of {n} values"
        )));
    }
    Ok((lo, hi))
}

fn bins_dict<'py>(py: Python<'py>, pts: &[LogPoint]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "ln_t",
        PyArray1::from_vec(py, pts.iter().map(|p| p.ln_t).collect()),
    )?;
    d.set_item(
        "ln_e",
        PyArray1::from_vec(py, pts.iter().map(|p| p.ln_e).collect()),
    )?;
    d.set_item(
        "count",
        PyArray1::from_vec(py, pts.iter().map(|p| p.count as i64).collect()),
    )?;
    Ok(d)
}

fn bins_of(d: &Bound<'_, PyDict>) -> PyResult<Vec<LogPoint>> {
    let get = |k: &str| -> PyResult<Vec<f64>> {
        let x = d
            .get_item(k)?
            .ok_or_else(|| PyValueError::new_err(format!("log bins need `{k}` (from log_bins)")))?;
        x.extract::<Vec<f64>>()
    };
    let (t, e, c) = (get("ln_t")?, get("ln_e")?, get("count")?);
    if t.len() != e.len() || t.len() != c.len() {
        return Err(PyValueError::new_err(
            "log bins: ln_t, ln_e, count differ in length",
        ));
    }
    Ok((0..t.len())
        .map(|k| LogPoint {
            ln_t: t[k],
            ln_e: e[k],
            count: c[k] as usize,
        })
        .collect())
}

/// Log-spaced bins of the curve `e` (t counted in snapshots) over snapshots `lo..=hi` (default:
/// to the end), `per_decade` bins per factor 10: `{"ln_t", "ln_e", "count"}` arrays (the mean
/// `ln t` and `ln E` of each bin's snapshots; empty bins and `E <= 0` skipped).
#[pyfunction]
#[pyo3(
    signature = (e, lo = Whole::new(1), hi = None, per_decade = Whole::new(analysis::decay::BINS_PER_DECADE as u64)),
    text_signature = "(e, lo=1, hi=None, per_decade=...)"
)]
fn log_bins<'py>(
    py: Python<'py>,
    e: PyReadonlyArray1<'py, f64>,
    lo: Whole,
    hi: Option<Whole>,
    per_decade: Whole,
) -> PyResult<Bound<'py, PyDict>> {
    let per_decade = per_decade.usize(1).map_err(bad("per_decade"))?;
    let e = vec1(&e);
    let (lo, hi) = range(e.len(), &lo, hi.as_ref())?;
    bins_dict(py, &analysis::log_bins(&e, lo, hi, per_decade))
}

/// Least-squares power law `E = A t^-gamma` on log bins (the dict of `log_bins`): `{"gamma",
/// "se", "ci_lo", "ci_hi" (95 % interval, Student t), "a", "n", "rms"}`, or None with fewer than
/// 3 bins.
#[pyfunction]
fn fit_power_law<'py>(
    py: Python<'py>,
    bins: &Bound<'py, PyDict>,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    analysis::fit_power_law(&bins_of(bins)?)
        .map(|f| pythonize::pythonize(py, &f))
        .transpose()
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The leak onset: the first snapshot after the maximum of `e` at which it is down to
/// `fraction` of the maximum (None if it never is).
#[pyfunction]
#[pyo3(signature = (e, fraction = analysis::decay::ONSET_FRACTION))]
fn leak_onset(e: PyReadonlyArray1<'_, f64>, fraction: f64) -> Option<usize> {
    analysis::leak_onset(&vec1(&e), fraction)
}

/// The time factor alpha that best collapses `curve`'s log bins onto `reference`'s (both dicts
/// of `log_bins`): `{"alpha", "rms", "t_lo", "t_hi"}` or None when they never overlap by
/// `min_overlap_decades`.
#[pyfunction]
#[pyo3(
    signature = (reference, curve, *, min_overlap_decades = 0.3, alpha_min = 0.02, alpha_max = 50.0, points_per_decade = Whole::new(40)),
    text_signature = "(reference, curve, *, min_overlap_decades=0.3, alpha_min=0.02, alpha_max=50.0, points_per_decade=40)"
)]
fn collapse_alpha<'py>(
    py: Python<'py>,
    reference: &Bound<'py, PyDict>,
    curve: &Bound<'py, PyDict>,
    min_overlap_decades: f64,
    alpha_min: f64,
    alpha_max: f64,
    points_per_decade: Whole,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let points_per_decade = points_per_decade
        .usize(1)
        .map_err(bad("points_per_decade"))?;
    let rule = analysis::CollapseRule {
        min_overlap_decades,
        alpha_min,
        alpha_max,
        points_per_decade,
    };
    analysis::collapse(&bins_of(reference)?, &bins_of(curve)?, &rule)
        .map(|c| pythonize::pythonize(py, &c))
        .transpose()
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Mean, median and 5 % / 95 % quantiles over members at every snapshot of `members` (a 2-D
/// array, members x snapshots): `{"mean", "median", "p05", "p95"}` arrays.
#[pyfunction]
fn ensemble_bands<'py>(
    py: Python<'py>,
    members: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let rows = rows2(&members);
    let refs: Vec<&[f64]> = rows.iter().map(|r| r.as_slice()).collect();
    let b = ensemble::bands(&refs);
    let d = PyDict::new(py);
    d.set_item(
        "mean",
        PyArray1::from_vec(py, b.iter().map(|x| x.mean).collect()),
    )?;
    d.set_item(
        "median",
        PyArray1::from_vec(py, b.iter().map(|x| x.median).collect()),
    )?;
    d.set_item(
        "p05",
        PyArray1::from_vec(py, b.iter().map(|x| x.p05).collect()),
    )?;
    d.set_item(
        "p95",
        PyArray1::from_vec(py, b.iter().map(|x| x.p95).collect()),
    )?;
    Ok(d)
}

/// gamma of the ensemble's mean curve over snapshots `lo..=hi`, with its delete-one jackknife
/// 95 % interval over members: `{"value", "se", "ci_lo", "ci_hi", "n"}` (None when the mean has
/// no fit). `members` is a 2-D array, members x snapshots.
#[pyfunction]
#[pyo3(
    signature = (members, lo, hi, per_decade = Whole::new(analysis::decay::BINS_PER_DECADE as u64)),
    text_signature = "(members, lo, hi, per_decade=...)"
)]
fn ensemble_gamma<'py>(
    py: Python<'py>,
    members: PyReadonlyArray2<'py, f64>,
    lo: Whole,
    hi: Whole,
    per_decade: Whole,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let per_decade = per_decade.usize(1).map_err(bad("per_decade"))?;
    let rows = rows2(&members);
    let n = rows.first().map_or(0, |r| r.len());
    let (lo, hi) = range(n, &lo, Some(&hi))?;
    let refs: Vec<&[f64]> = rows.iter().map(|r| r.as_slice()).collect();
    ensemble::jackknife(&refs, |m| ensemble::gamma(m, lo, hi, per_decade))
        .map(|e| pythonize::pythonize(py, &e))
        .transpose()
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The local slope `d ln E / d ln t` of `e` over snapshots `lo..=hi`: least squares over the
/// log bins within `half_width` bins of each bin: `{"t", "slope"}` arrays.
#[pyfunction]
#[pyo3(
    signature = (e, lo = Whole::new(1), hi = None, per_decade = Whole::new(analysis::decay::SLOPE_BINS_PER_DECADE as u64), half_width = Whole::new(analysis::decay::SLOPE_HALF_WIDTH as u64)),
    text_signature = "(e, lo=1, hi=None, per_decade=..., half_width=...)"
)]
fn local_slope<'py>(
    py: Python<'py>,
    e: PyReadonlyArray1<'py, f64>,
    lo: Whole,
    hi: Option<Whole>,
    per_decade: Whole,
    half_width: Whole,
) -> PyResult<Bound<'py, PyDict>> {
    let per_decade = per_decade.usize(1).map_err(bad("per_decade"))?;
    let half_width = half_width.usize(0).map_err(bad("half_width"))?;
    let e = vec1(&e);
    let (lo, hi) = range(e.len(), &lo, hi.as_ref())?;
    let s = ensemble::local_slope(&e, lo, hi, per_decade, half_width);
    let d = PyDict::new(py);
    d.set_item("t", PyArray1::from_vec(py, s.iter().map(|p| p.t).collect()))?;
    d.set_item(
        "slope",
        PyArray1::from_vec(py, s.iter().map(|p| p.slope).collect()),
    )?;
    Ok(d)
}

/// Add the analysis names to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(log_bins, m)?)?;
    m.add_function(wrap_pyfunction!(fit_power_law, m)?)?;
    m.add_function(wrap_pyfunction!(leak_onset, m)?)?;
    m.add_function(wrap_pyfunction!(collapse_alpha, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_bands, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_gamma, m)?)?;
    m.add_function(wrap_pyfunction!(local_slope, m)?)?;
    Ok(())
}
