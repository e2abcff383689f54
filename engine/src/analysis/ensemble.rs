//! Ensemble statistics of `E_R(t)`: the container dynamics are chaotic, so a single curve is
//! reproducible but not converged, and the object worth fitting is the ensemble mean over members
//! that differ by tiny perturbations.
//!
//! Every interval here comes from the spread **over members**, by the delete-one jackknife: a
//! quantity `q` computed from the mean of all `n` members is recomputed `n` times, each time
//! leaving one member out (`q_(i)`); its standard error is
//! `sqrt((n - 1) / n * sum_i (q_(i) - q_(.))^2)` and the 95 % interval is
//! `q +- t_{0.975, n-1} * SE` (Student t with `n - 1` degrees of freedom). Members are
//! independent, so unlike the residual-based interval of [`super::fit_power_law`] this does not
//! assume uncorrelated residuals along one curve. With fewer than 2 members there is no interval
//! (NaN).
//!
//! Curves are sampled at whole snapshots `t = 0, 1, .., N`, as everywhere in [`crate::analysis`].

use super::statistics::{mean, quantile_sorted};
use super::{fit_power_law, interp, log_bins, student_t_975, LogPoint};

/// The ensemble at one snapshot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// Mean over members.
    pub mean: f64,
    /// Median over members (type-7 quantile 0.5).
    pub median: f64,
    /// 5 % and 95 % quantiles over members.
    pub p05: f64,
    /// 95 % quantile over members (`p05` is the 5 % one).
    pub p95: f64,
}

/// Mean, median and 5-95 % band at every snapshot of `members` (curves of equal length; a
/// shorter member ends the result).
pub fn bands(members: &[&[f64]]) -> Vec<Band> {
    let len = members.iter().map(|m| m.len()).min().unwrap_or(0);
    let mut col = Vec::with_capacity(members.len());
    (0..len)
        .map(|t| {
            col.clear();
            col.extend(members.iter().map(|m| m[t]));
            let mean = mean(&col);
            col.sort_by(f64::total_cmp);
            Band {
                mean,
                median: quantile_sorted(&col, 0.5),
                p05: quantile_sorted(&col, 0.05),
                p95: quantile_sorted(&col, 0.95),
            }
        })
        .collect()
}

/// The mean curve of `members`, optionally leaving member `skip` out.
pub fn mean_curve(members: &[&[f64]], skip: Option<usize>) -> Vec<f64> {
    let len = members.iter().map(|m| m.len()).min().unwrap_or(0);
    let used: Vec<&[f64]> = members
        .iter()
        .enumerate()
        .filter(|(i, _)| Some(*i) != skip)
        .map(|(_, m)| *m)
        .collect();
    let n = used.len() as f64;
    (0..len)
        .map(|t| used.iter().map(|m| m[t]).sum::<f64>() / n)
        .collect()
}

/// A value with its jackknife interval over members.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// From the mean of all members.
    pub value: f64,
    /// Jackknife standard error (NaN with fewer than 2 members or when a leave-one-out value is
    /// missing).
    pub se: f64,
    /// Lower end of the 95 % interval: `value - t_{0.975, n-1} se` (NaN when `se` is).
    pub ci_lo: f64,
    /// Upper end of the 95 % interval: `value + t_{0.975, n-1} se`.
    pub ci_hi: f64,
    /// Members.
    pub n: usize,
}

/// `stat` of the mean curve with its delete-one jackknife interval over members (see the module).
/// `None` when `stat` of the full mean is `None`.
pub fn jackknife(members: &[&[f64]], stat: impl Fn(&[f64]) -> Option<f64>) -> Option<Estimate> {
    let n = members.len();
    let value = stat(&mean_curve(members, None))?;
    let nan = Estimate {
        value,
        se: f64::NAN,
        ci_lo: f64::NAN,
        ci_hi: f64::NAN,
        n,
    };
    if n < 2 {
        return Some(nan);
    }
    let mut loo = Vec::with_capacity(n);
    for i in 0..n {
        match stat(&mean_curve(members, Some(i))) {
            Some(q) => loo.push(q),
            None => return Some(nan),
        }
    }
    let nf = n as f64;
    let m = loo.iter().sum::<f64>() / nf;
    let se = ((nf - 1.0) / nf * loo.iter().map(|q| (q - m).powi(2)).sum::<f64>()).sqrt();
    let q = student_t_975(nf - 1.0);
    Some(Estimate {
        value,
        se,
        ci_lo: value - q * se,
        ci_hi: value + q * se,
        n,
    })
}

/// `gamma` of `E = A t^-gamma` fitted to the snapshots `lo..=hi` of `e` (log bins, see
/// [`super::log_bins`]).
pub fn gamma(e: &[f64], lo: usize, hi: usize, per_decade: usize) -> Option<f64> {
    fit_power_law(&log_bins(e, lo, hi, per_decade)).map(|f| f.gamma)
}

/// The local slope `d ln E / d ln t` at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlopePoint {
    /// Centre of the window (snapshots): `exp` of the mean `ln t` of its bin.
    pub t: f64,
    /// The local slope `d ln E / d ln t` (`-gamma` of the local power law).
    pub slope: f64,
}

/// Local slope of `e` over snapshots `lo..=hi`: the curve is binned (`per_decade` log bins) and at
/// every bin the slope is the least-squares slope of `ln E` on `ln t` over the bins within
/// `half_width` bins of it (the window is cut at the ends; at least 3 bins). For an exact power
/// law `t^-g` every point is `-g`.
pub fn local_slope(
    e: &[f64],
    lo: usize,
    hi: usize,
    per_decade: usize,
    half_width: usize,
) -> Vec<SlopePoint> {
    let pts = log_bins(e, lo, hi, per_decade);
    (0..pts.len())
        .filter_map(|j| {
            let a = j.saturating_sub(half_width);
            let b = (j + half_width).min(pts.len() - 1);
            if b - a < 2 {
                return None;
            }
            let f = fit_power_law(&pts[a..=b])?;
            Some(SlopePoint {
                t: pts[j].ln_t.exp(),
                slope: -f.gamma,
            })
        })
        .collect()
}

/// The longest stretch of consecutive slope points that stay within `+-tol` of one constant (their
/// max minus min at most `2 tol`). Returns `(first index, last index)`; `None` without points.
pub fn constant_stretch(slopes: &[f64], tol: f64) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize)> = None;
    for a in 0..slopes.len() {
        if !slopes[a].is_finite() {
            continue;
        }
        let (mut lo, mut hi) = (slopes[a], slopes[a]);
        let mut b = a;
        while b + 1 < slopes.len() && slopes[b + 1].is_finite() {
            let x = slopes[b + 1];
            if x.max(hi) - x.min(lo) > 2.0 * tol {
                break;
            }
            lo = lo.min(x);
            hi = hi.max(x);
            b += 1;
        }
        if best.is_none_or(|(p, q)| b - a > q - p) {
            best = Some((a, b));
        }
    }
    best
}

/// The first time (snapshots, interpolated in `ln t`) at which the binned curve `pts` falls to
/// `level` or below, after its maximum. `None` if it never does.
pub fn crossing_time(pts: &[LogPoint], level: f64) -> Option<f64> {
    let ll = level.ln();
    let imax = pts
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.ln_e.total_cmp(&b.1.ln_e))?
        .0;
    if pts[imax].ln_e <= ll {
        return None;
    }
    for j in imax + 1..pts.len() {
        let (a, b) = (pts[j - 1], pts[j]);
        if b.ln_e <= ll {
            let w = (a.ln_e - ll) / (a.ln_e - b.ln_e);
            let lt = a.ln_t + w * (b.ln_t - a.ln_t);
            // Check the interpolation lands on the curve (it does by construction).
            debug_assert!(interp(pts, lt).is_some_and(|x| (x - ll).abs() < 1e-9));
            return Some(lt.exp());
        }
    }
    None
}

/// The fewest points a correlation is given from: through two points a line always passes, so
/// r = +-1 says nothing; three is the least that can disagree with a line.
pub const MIN_PEARSON_POINTS: usize = 3;

/// [`pearson`], or why there is none: fewer than [`MIN_PEARSON_POINTS`] pairs, a value that is
/// not a finite number, or no spread in one of the two (r is 0 / 0).
pub fn pearson_checked(x: &[f64], y: &[f64]) -> Result<f64, String> {
    let n = x.len().min(y.len());
    if n < MIN_PEARSON_POINTS {
        return Err(format!(
            "{n} point{}, fewer than the {MIN_PEARSON_POINTS} a correlation needs",
            if n == 1 { "" } else { "s" }
        ));
    }
    if !x[..n].iter().chain(&y[..n]).all(|v| v.is_finite()) {
        return Err("a value is missing".into());
    }
    // Equal values exactly: the mean's round-off would leave deviations of 1e-17 and an r of
    // pure noise (0.2 three times has the mean 0.20000000000000004).
    let flat = |v: &[f64]| v.iter().all(|a| *a == v[0]);
    if flat(&x[..n]) || flat(&y[..n]) {
        return Err("no spread: every point has the same value".into());
    }
    let r = pearson(&x[..n], &y[..n]);
    if r.is_finite() {
        Ok(r)
    } else {
        Err("no spread: every point has the same value".into())
    }
}

/// Pearson's correlation coefficient of `x` and `y` (NaN when either has no spread; reports use
/// [`pearson_checked`]).
pub fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len()) as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx).powi(2);
        syy += (b - my).powi(2);
    }
    sxy / (sxx * syy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn no_correlation_from_fewer_than_three_points_or_without_spread() {
        // Two points: r = +-1 whatever they are.
        assert!(pearson_checked(&[1.0, 2.0], &[5.0, 3.0]).is_err());
        assert!(pearson_checked(&[1.0], &[5.0])
            .unwrap_err()
            .contains("1 point,"));
        // One key: the same x for every point gave NaN.
        assert!(pearson_checked(&[1.0, 1.0, 1.0], &[1.0, 2.0, 4.0])
            .unwrap_err()
            .contains("no spread"));
        assert!(pearson_checked(&[1.0, f64::NAN, 2.0], &[1.0, 2.0, 4.0]).is_err());
        // (1, 1), (2, 3), (3, 2): means 2 and 2, sxy = 1*(-1)... = (-1)(-1) + 0 + (1)(0) = 1,
        // sxx = 2, syy = 2: r = 0.5.
        assert_relative_eq!(
            pearson_checked(&[1.0, 2.0, 3.0], &[1.0, 3.0, 2.0]).unwrap(),
            0.5,
            max_relative = 1e-15
        );
    }

    #[test]
    fn bands_of_a_small_synthetic_ensemble() {
        let a = [1.0, 2.0, 3.0];
        let b = [3.0, 2.0, 1.0];
        let c = [2.0, 8.0, 2.0];
        let bs = bands(&[&a, &b, &c]);
        assert_eq!(bs.len(), 3);
        // Snapshot 1: values 2, 2, 8: mean 4, median 2, 5 % = 2, 95 %: position 1.9: 2 + 0.9 * 6.
        assert_eq!(bs[1].mean, 4.0);
        assert_eq!(bs[1].median, 2.0);
        assert_eq!(bs[1].p05, 2.0);
        assert_relative_eq!(bs[1].p95, 7.4, max_relative = 1e-15);
        // Snapshot 0: 1, 2, 3: 5 % at position 0.1 -> 1.1.
        assert_relative_eq!(bs[0].p05, 1.1, max_relative = 1e-15);
        assert_eq!(bs[0].median, 2.0);
    }

    #[test]
    fn jackknife_of_the_mean_is_the_standard_error_of_the_mean() {
        // For the statistic "value at t = 0" the jackknife SE equals the textbook s / sqrt(n).
        let m: Vec<[f64; 1]> = [1.0, 2.0, 4.0, 7.0].iter().map(|&x| [x]).collect();
        let refs: Vec<&[f64]> = m.iter().map(|x| &x[..]).collect();
        let est = jackknife(&refs, |e| Some(e[0])).unwrap();
        assert_eq!(est.value, 3.5);
        // Sample variance: ((2.5^2 + 1.5^2 + 0.5^2 + 3.5^2) / 3) = 7; SE = sqrt(7 / 4).
        assert_relative_eq!(est.se, (7.0f64 / 4.0).sqrt(), max_relative = 1e-14);
        // t_{0.975, 3} = 3.182446 (tables).
        assert_relative_eq!(
            est.ci_hi - est.value,
            3.182446 * est.se,
            max_relative = 1e-6
        );
        let one = jackknife(&refs[..1], |e| Some(e[0])).unwrap();
        assert!(one.se.is_nan());
    }

    fn power(n: usize, a: f64, g: f64) -> Vec<f64> {
        (0..=n)
            .map(|t| if t == 0 { 0.0 } else { a * (t as f64).powf(-g) })
            .collect()
    }

    #[test]
    fn local_slope_of_an_exact_power_law_is_constant() {
        let e = power(100_000, 65.0, 0.7055);
        let s = local_slope(&e, 10, 100_000, 10, 2);
        assert_eq!(s.len(), 40);
        for p in &s {
            // Bin means of ln t and ln E of a power law lie exactly on its line: round-off only.
            assert_relative_eq!(p.slope, -0.7055, max_relative = 1e-10);
        }
        let slopes: Vec<f64> = s.iter().map(|p| p.slope).collect();
        assert_eq!(constant_stretch(&slopes, 0.05), Some((0, 39)));
    }

    #[test]
    fn local_slope_sees_a_bend() {
        // t^-0.5 up to t = 1000, t^-1.5 after (continuous): the slope changes by 1.
        let e: Vec<f64> = (0..=100_000)
            .map(|t| {
                let t = t.max(1) as f64;
                if t <= 1000.0 {
                    t.powf(-0.5)
                } else {
                    1000f64.powf(-0.5) * (t / 1000.0).powf(-1.5)
                }
            })
            .collect();
        let s = local_slope(&e, 10, 100_000, 10, 2);
        assert!(s.first().unwrap().slope > -0.51 && s.last().unwrap().slope < -1.49);
        let slopes: Vec<f64> = s.iter().map(|p| p.slope).collect();
        let (a, b) = constant_stretch(&slopes, 0.05).unwrap();
        // Either side of the bend is two decades minus the window's reach across it.
        assert!(s[b].t / s[a].t < 200.0, "{} .. {}", s[a].t, s[b].t);
    }

    #[test]
    fn crossing_time_inverts_a_power_law() {
        let e = power(10_000, 100.0, 1.0);
        let pts = log_bins(&e, 1, 10_000, 20);
        // E = 100 / t falls to 0.1 at t = 1000: bins interpolate ln E linearly in ln t, exact here.
        let t = crossing_time(&pts, 0.1).unwrap();
        assert_relative_eq!(t, 1000.0, max_relative = 1e-9);
        assert!(crossing_time(&pts, 1e-9).is_none());
    }

    #[test]
    fn pearson_of_a_line_is_one() {
        let x = [1.0, 2.0, 3.0, 4.0];
        assert_relative_eq!(
            pearson(&x, &[3.0, 5.0, 7.0, 9.0]),
            1.0,
            max_relative = 1e-15
        );
        assert_relative_eq!(
            pearson(&x, &[9.0, 7.0, 5.0, 3.0]),
            -1.0,
            max_relative = 1e-15
        );
    }
}
