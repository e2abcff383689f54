//! The decay analysis shared by `reproduce` and `study`: how a container's remaining energy
//! `E_R(t)` is binned, where its leak starts and over which window its power law is fitted. One
//! place for these rules, so a figure and a study never disagree on them.

use super::{fit_power_law, leak_onset, log_bins, LogPoint, PowerFit};

/// Bins per decade of the log-log fits and collapses.
pub const BINS_PER_DECADE: usize = 20;

/// Fraction of the peak energy at which a container counts as leaking (start of the collapse
/// range): after half the energy that entered has left again.
pub const ONSET_FRACTION: f64 = 0.5;

/// The fit window of a curve of `n` snapshots: the last decade, `[n/10, n]`, but never before
/// the leak onset (in a short run `n/10` can fall before the incident wave has even arrived).
pub fn fit_window(n: usize, onset: Option<usize>) -> (usize, usize) {
    ((n / 10).max(onset.unwrap_or(0)), n)
}

/// The windows of the sensitivity table, as fractions of `n` (starts clamped to the leak onset).
pub const WINDOWS: [(f64, f64); 5] = [
    (0.05, 1.0),
    (0.1, 1.0),
    (0.25, 1.0),
    (0.1, 0.5),
    (0.025, 0.25),
];

/// Fit `E_R / E0` in percent over snapshots `lo..=hi`.
pub fn fit_percent(e: &[f64], e0: f64, lo: usize, hi: usize) -> Option<PowerFit> {
    let pct: Vec<f64> = e.iter().map(|x| 100.0 * x / e0).collect();
    fit_power_law(&log_bins(&pct, lo, hi, BINS_PER_DECADE))
}

/// Binned curve of a container from its leak onset on (the collapse input).
pub fn onset_bins(e: &[f64]) -> (Option<usize>, Vec<LogPoint>) {
    let onset = leak_onset(e, ONSET_FRACTION);
    let bins = onset.map_or_else(Vec::new, |o| log_bins(e, o, e.len() - 1, BINS_PER_DECADE));
    (onset, bins)
}

/// Log bins per decade of the local slope.
pub const SLOPE_BINS_PER_DECADE: usize = 10;
/// Half width of the local-slope window, in bins (a fit over up to 5 bins, half a decade).
pub const SLOPE_HALF_WIDTH: usize = 2;
/// "Within +-0.05 of a constant" (the criterion).
pub const SLOPE_TOLERANCE: f64 = 0.05;
