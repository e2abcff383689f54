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

/// The normal distribution's two-sided 95 % point: an interval `x +- 1.96 se` holds the true
/// value with a chance of 95 % where the estimate is normal.
pub const Z95: f64 = 1.959_963_984_540_054;

/// A confidence interval of the mean of `x`, `mean +- z se` (NaN ends with fewer than 2 values).
pub fn mean_interval(x: &[f64], z: f64) -> (f64, f64) {
    let (m, se) = mean_se(x);
    (m - z * se, m + z * se)
}

/// A distribution-free confidence interval of the `q`-quantile from values sorted in increasing
/// order: the order statistics `x_(r)` and `x_(s)` (1-based) with `r` and `s` the numbers `n q -+
/// z sqrt(n q (1 - q))` rounded up (the normal approximation of the binomial count of values
/// below the quantile; Conover, *Practical Nonparametric Statistics*, 3rd ed., 1999, sec. 3.2),
/// clamped to `1..=n`. It assumes nothing of the values' distribution; where a rank is clamped
/// (few values, a quantile near 0 or 1: at 64 values the 95th percentile's `s` is past `n`), that
/// end is the smallest or largest value and the interval holds the quantile with a chance below
/// the nominal one. `(NaN, NaN)` for no values.
pub fn quantile_interval(s: &[f64], q: f64, z: f64) -> (f64, f64) {
    let n = s.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let q = q.clamp(0.0, 1.0);
    let centre = n as f64 * q;
    let half = z * (centre * (1.0 - q)).sqrt();
    let rank = |x: f64| (x.ceil() as i64).clamp(1, n as i64) as usize - 1;
    (s[rank(centre - half)], s[rank(centre + half)])
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

    /// The quantile interval by hand, and its coverage: of 4000 samples of 200 standard normal
    /// values, the share whose interval holds the true 90th percentile (1.2816) is 95 % within
    /// the sampling error of a share (4 standard errors of a binomial share at 4000: 0.014) and
    /// the discreteness of the ranks (ranks 172 and 189 of 200: the exact coverage, the chance
    /// that 172 to 188 of 200 values lie below the quantile, is 0.9561).
    #[test]
    fn quantile_intervals_by_hand_and_their_coverage() {
        use rand::{Rng, SeedableRng};
        // 10 values 1..10, q = 0.5, z = 1.96: 5 -+ 1.96 sqrt(2.5) = 1.90, 8.10, up: ranks 2 and 9.
        let x: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(quantile_interval(&x, 0.5, Z95), (2.0, 9.0));
        // 64 values at q = 0.95: 60.8 -+ 3.42 = 57.4, 64.2: ranks 58 and 65, clamped to 64.
        let y: Vec<f64> = (1..=64).map(f64::from).collect();
        assert_eq!(quantile_interval(&y, 0.95, Z95), (58.0, 64.0));
        assert!(quantile_interval(&[], 0.5, Z95).0.is_nan());
        let (lo, hi) = mean_interval(&[1.0, 2.0, 4.0, 7.0], 2.0);
        let se = (7.0f64 / 4.0).sqrt();
        assert_relative_eq!(lo, 3.5 - 2.0 * se, max_relative = 1e-15);
        assert_relative_eq!(hi, 3.5 + 2.0 * se, max_relative = 1e-15);

        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let truth = 1.281_551_565_545;
        let trials = 4000;
        let mut held = 0;
        for _ in 0..trials {
            let mut v: Vec<f64> = (0..200)
                .map(|_| rng.sample::<f64, _>(rand_distr::StandardNormal))
                .collect();
            v.sort_by(f64::total_cmp);
            let (lo, hi) = quantile_interval(&v, 0.9, Z95);
            held += usize::from(lo <= truth && truth <= hi);
        }
        let share = held as f64 / trials as f64;
        assert!((share - 0.9561).abs() < 0.014, "{share}");
    }
}
