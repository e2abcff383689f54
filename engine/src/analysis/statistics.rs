//! The statistics every part of the crate and the harness reports with: the mean, the sample
//! standard deviation and the standard error of the mean, and type-7 quantiles (issue 49: they
//! were written four times, each with its own rule for small samples).
//!
//! **One rule for small samples.** The mean of no values is NaN; a standard deviation or a
//! standard error needs two values, and is NaN with fewer (one value shows no spread: a report
//! says "no error", not 0). The sums run in the slice's order, so a result is the same bits for
//! the same values in the same order.

/// The mean of `x` (NaN when empty).
pub fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// The mean and the sample variance (over `n - 1`; NaN with fewer than 2 values).
fn mean_var(x: &[f64]) -> (f64, f64) {
    let m = mean(x);
    if x.len() < 2 {
        return (m, f64::NAN);
    }
    let var = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() as f64 - 1.0);
    (m, var)
}

/// The mean and the sample standard deviation (over `n - 1`; NaN with fewer than 2 values).
pub fn mean_sd(x: &[f64]) -> (f64, f64) {
    let (m, var) = mean_var(x);
    (m, var.sqrt())
}

/// The mean and the standard error of the mean (`sqrt(s^2 / n)`, `s` the sample standard
/// deviation; NaN with fewer than 2 values).
pub fn mean_se(x: &[f64]) -> (f64, f64) {
    let (m, var) = mean_var(x);
    (m, (var / x.len() as f64).sqrt())
}

/// The `q`-quantile (`0 <= q <= 1`) of `x` by linear interpolation between order statistics
/// (Hyndman and Fan's type 7, the default of R and NumPy): position `q (n - 1)` in the sorted
/// values. NaN for an empty slice.
pub fn quantile(x: &[f64], q: f64) -> f64 {
    let mut s = x.to_vec();
    s.sort_by(f64::total_cmp);
    quantile_sorted(&s, q)
}

/// [`quantile`] of values already sorted in increasing order.
pub fn quantile_sorted(s: &[f64], q: f64) -> f64 {
    if s.is_empty() {
        return f64::NAN;
    }
    let h = q.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let (i, f) = (h.floor() as usize, h - h.floor());
    if i + 1 < s.len() {
        s[i] + f * (s[i + 1] - s[i])
    } else {
        s[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn mean_sd_and_se_by_hand() {
        let (m, sd) = mean_sd(&[1.0, 2.0, 4.0, 7.0]);
        assert_eq!(m, 3.5);
        // Squares of the deviations: 6.25 + 2.25 + 0.25 + 12.25 = 21, over 3.
        assert_relative_eq!(sd, 7f64.sqrt(), max_relative = 1e-15);
        assert_relative_eq!(
            mean_se(&[1.0, 2.0, 4.0, 7.0]).1,
            (7.0f64 / 4.0).sqrt(),
            max_relative = 1e-15
        );
    }

    #[test]
    fn small_samples_have_no_spread() {
        assert!(mean(&[]).is_nan());
        let (m, sd) = mean_sd(&[3.0]);
        assert!(m == 3.0 && sd.is_nan());
        assert!(mean_se(&[3.0]).1.is_nan());
    }

    #[test]
    fn quantiles_match_hand_computed_type_7() {
        // Sorted: 1 2 4 8 16. Type 7: position q (n - 1).
        let x = [8.0, 1.0, 16.0, 2.0, 4.0];
        assert_eq!(quantile(&x, 0.5), 4.0);
        assert_eq!(quantile(&x, 0.0), 1.0);
        assert_eq!(quantile(&x, 1.0), 16.0);
        assert_relative_eq!(quantile(&x, 0.05), 1.2, max_relative = 1e-15);
        // 0.05 * 4 = 0.2: 1 + 0.2 (2 - 1) = 1.2; 0.95 * 4 = 3.8: 8 + 0.8 * 8 = 14.4.
        assert_relative_eq!(quantile(&x, 0.95), 14.4, max_relative = 1e-15);
        assert!(quantile(&[], 0.5).is_nan());
        // NumPy's linear quantile.
        assert_eq!(quantile_sorted(&[1.0, 2.0, 3.0, 4.0, 5.0], 0.95), 4.8);
        assert_eq!(quantile_sorted(&[7.0], 0.95), 7.0);
        assert_eq!(quantile_sorted(&[0.0, 10.0], 0.5), 5.0);
    }
}
