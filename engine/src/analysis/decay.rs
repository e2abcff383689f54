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

/// The shortest window a gamma is fitted over, in decades of time (a factor 2 in `t`): over less,
/// the log bins hold a handful of points so close in `ln t` that any curvature (the wave still
/// arriving, a last reflection) reads as a slope of hundreds; the decades of a study keep the same
/// rule for their last, partial window.
pub const MIN_FIT_DECADES: f64 = 0.3;

/// Why no gamma is given over snapshots `lo..=hi` of a curve whose leak onset is `onset`
/// ([`leak_onset`] at [`ONSET_FRACTION`]), or `None` when a fit may be made: a curve without a
/// leak onset has not started to decay (its energy is still rising or has never fallen to half its
/// peak), and a window before the onset or shorter than [`MIN_FIT_DECADES`] fits no decay.
pub fn gamma_withheld(onset: Option<usize>, lo: usize, hi: usize) -> Option<String> {
    let Some(on) = onset else {
        return Some(
            "no leak onset: E_R has not fallen to half its peak (still rising or held), so there \
             is no decay to fit"
                .into(),
        );
    };
    if lo < on {
        return Some(format!(
            "the window starts at snapshot {lo}, before the leak onset (snapshot {on})"
        ));
    }
    let decades = if lo == 0 {
        f64::INFINITY
    } else {
        (hi as f64 / lo as f64).log10()
    };
    if !(decades >= MIN_FIT_DECADES) || lo == 0 {
        return Some(format!(
            "the window [{lo}, {hi}] from the leak onset on spans {} decade, less than the {} a \
             fit needs",
            if lo == 0 {
                "no".to_string()
            } else {
                format!("{decades:.2}")
            },
            MIN_FIT_DECADES
        ));
    }
    None
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_is_withheld_before_the_onset_and_over_short_windows() {
        // A run of 300 snapshots whose E_R is still rising: no onset, no gamma over [30, 300].
        assert!(gamma_withheld(None, 30, 300)
            .unwrap()
            .contains("no leak onset"));
        // The onset at 250: the window [250, 300] spans log10(1.2) = 0.08 decade.
        let why = gamma_withheld(Some(250), 250, 300).unwrap();
        assert!(why.contains("0.08 decade"), "{why}");
        // A window that starts before the onset.
        assert!(gamma_withheld(Some(40), 30, 300)
            .unwrap()
            .contains("before the leak onset"));
        // [100, 200] is log10(2) = 0.301 decade: allowed; [100, 199] is 0.299: not.
        assert_eq!(gamma_withheld(Some(100), 100, 200), None);
        assert!(gamma_withheld(Some(100), 100, 199).is_some());
        assert_eq!(gamma_withheld(Some(30), 30, 300), None);
    }
}
