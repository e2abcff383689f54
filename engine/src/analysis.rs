//! Curve analysis, usable from scripts: log-spaced binning, power-law fits with confidence
//! intervals, the time rescaling that collapses one curve onto another, the leak onset (pulse
//! detection is the crate's [`crate::detect_pulses`]). `grainchain reproduce` uses it for Fig. 4 and 5.
//!
//! Everything here works on a remaining-energy curve `E_R(t)` sampled at whole snapshots
//! `t = 0, 1, .., N` (index = snapshot number, as in the paper's Fig. 4).
//!
//! **Binning.** A log-log fit to every snapshot would weight the last decade ten times more than
//! the one before it (snapshots are evenly spaced in `t`). The fit therefore uses log-spaced bins
//! (`per_decade` bins per factor 10 of time): each bin contributes one point, the mean of `ln t`
//! and the mean of `ln E` over the snapshots in it.
//!
//! **Fit.** Ordinary least squares of `ln E = ln A - gamma ln t` over the bin points. The 95 %
//! confidence interval of `gamma` is `gamma +- t_{0.975, n-2} * SE(gamma)` with the standard
//! error from the residuals (Student t with `n - 2` degrees of freedom). It assumes independent
//! residuals; the residuals of these curves are correlated (wave trains leave in bursts), so the
//! interval understates the real uncertainty. The spread over fit windows, step sizes and
//! perturbed twins (reported beside it) is the better measure.

pub mod decay;
pub mod ensemble;
pub mod statistics;

/// A point of a binned curve: mean `ln t` and mean `ln E` over the snapshots of one bin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogPoint {
    /// Mean of `ln t` over the bin's snapshots (t in snapshots).
    pub ln_t: f64,
    /// Mean of `ln E` over the bin's snapshots.
    pub ln_e: f64,
    /// Snapshots in the bin.
    pub count: usize,
}

/// Log-spaced bins over snapshots `lo..=hi`: `per_decade` bins per factor 10, bin `k` holding
/// the snapshots with `lo 10^(k/per_decade) <= t < lo 10^((k+1)/per_decade)`, the last bin also
/// holding `hi`. Bins without a snapshot are skipped; snapshots with `E <= 0` are skipped (no
/// logarithm).
pub fn log_bins(e: &[f64], lo: usize, hi: usize, per_decade: usize) -> Vec<LogPoint> {
    let mut out = Vec::new();
    if e.is_empty() || per_decade == 0 {
        return out;
    }
    let lo = lo.max(1);
    let hi = hi.min(e.len() - 1);
    if lo > hi {
        return out;
    }
    let pd = per_decade as f64;
    // Number of bins: the decades spanned times per_decade, rounded up (a hair of tolerance so
    // an exact decade gives exactly per_decade bins).
    let nb = (((hi as f64 / lo as f64).log10() * pd - 1e-9).ceil() as usize).max(1);
    let mut acc = vec![(0.0f64, 0.0f64, 0usize); nb];
    for (t, &et) in e.iter().enumerate().take(hi + 1).skip(lo) {
        if !(et > 0.0) {
            continue;
        }
        let k = (((t as f64 / lo as f64).log10() * pd + 1e-12).floor() as usize).min(nb - 1);
        let a = &mut acc[k];
        a.0 += (t as f64).ln();
        a.1 += et.ln();
        a.2 += 1;
    }
    for (st, se, n) in acc {
        if n > 0 {
            out.push(LogPoint {
                ln_t: st / n as f64,
                ln_e: se / n as f64,
                count: n,
            });
        }
    }
    out
}

/// A power law `E = A t^-gamma` fitted by least squares on log-log points.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PowerFit {
    /// The fitted exponent `gamma` (E decays as `t^-gamma`).
    pub gamma: f64,
    /// Standard error of `gamma` from the residuals.
    pub se: f64,
    /// 95 % confidence interval of `gamma` (Student t, `n - 2` degrees of freedom).
    pub ci_lo: f64,
    /// Upper end of the 95 % confidence interval (`ci_lo` is the lower end).
    pub ci_hi: f64,
    /// `A` in the units of the curve (E at t = 1).
    pub a: f64,
    /// Number of points (bins).
    pub n: usize,
    /// Root-mean-square residual in `ln E`.
    pub rms: f64,
}

/// Ordinary least squares of `ln e = ln A - gamma ln t`. `None` with fewer than 3 points or no
/// spread in `ln t`.
pub fn fit_power_law(points: &[LogPoint]) -> Option<PowerFit> {
    let n = points.len();
    if n < 3 {
        return None;
    }
    let nf = n as f64;
    let mx = points.iter().map(|p| p.ln_t).sum::<f64>() / nf;
    let my = points.iter().map(|p| p.ln_e).sum::<f64>() / nf;
    let sxx: f64 = points.iter().map(|p| (p.ln_t - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.ln_t - mx) * (p.ln_e - my)).sum();
    if !(sxx > 0.0) {
        return None;
    }
    let slope = sxy / sxx;
    let icpt = my - slope * mx;
    let ssr: f64 = points
        .iter()
        .map(|p| (p.ln_e - icpt - slope * p.ln_t).powi(2))
        .sum();
    let dof = nf - 2.0;
    let se = (ssr / dof / sxx).sqrt();
    let q = student_t_975(dof);
    let gamma = -slope;
    Some(PowerFit {
        gamma,
        se,
        ci_lo: gamma - q * se,
        ci_hi: gamma + q * se,
        a: icpt.exp(),
        n,
        rms: (ssr / nf).sqrt(),
    })
}

/// The 97.5 % quantile of Student's t distribution with `nu` degrees of freedom (two-sided 95 %):
/// the root of `P(T <= t) = 0.975`, found by bisection on the exact distribution function (via the
/// regularized incomplete beta function, Numerical Recipes' continued fraction).
///
/// Hand-written on purpose (issue 39, item 5; measured against mpmath at 40 digits), as it is
/// within 1e-15 relative of the exact quantile at nu = 1, 2, 3, 12 and 29, 1e-10 at nu = 1e3, 1e5
/// and 1e6.
/// statrs 0.19 (`StudentsT::inverse_cdf(0.975)`, without default features: no nalgebra) is
/// 1e-13 off at nu = 29, 3.5e-6 at nu = 1e5 and 6e-5 at nu = 1e6, and differs from this one in
/// the last bits at every nu from 1 to 2000; its `beta_reg` in this bisection still differs at
/// 1355 of those 2000 (up to 5.6e-13 relative, 12 ulps at nu = 3). Either would move every
/// confidence interval grainchain writes (fits, `ensemble.csv`, STUDY.md, REPORT.md) for no
/// gain and a loss of accuracy; `student_t_matches_tables` checks this one against the printed tables.
pub fn student_t_975(nu: f64) -> f64 {
    // P(|T| > t) = I_{nu/(nu+t^2)}(nu/2, 1/2); we need it to equal 0.05.
    let tail = |t: f64| inc_beta(nu / 2.0, 0.5, nu / (nu + t * t));
    let (mut lo, mut hi) = (0.0f64, 1000.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > 0.05 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error ~1e-15).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // reflection
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized incomplete beta function I_x(a, b).
fn inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front =
        (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

/// Continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..300 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < tiny { tiny } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < tiny { tiny } else { c };
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < tiny { tiny } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < tiny { tiny } else { c };
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

/// `ln E` at `ln t` by linear interpolation between binned points (`None` outside their range).
pub fn interp(points: &[LogPoint], ln_t: f64) -> Option<f64> {
    let first = points.first()?;
    let last = points.last()?;
    // Overlap ends are computed as (a + ln alpha) - ln alpha, which can miss `a` by an ulp:
    // accept and clamp points within 1e-9 of the range.
    if ln_t < first.ln_t - 1e-9 || ln_t > last.ln_t + 1e-9 {
        return None;
    }
    let ln_t = ln_t.clamp(first.ln_t, last.ln_t);
    let k = points.partition_point(|p| p.ln_t <= ln_t);
    if k == 0 {
        return Some(first.ln_e);
    }
    if k >= points.len() {
        return Some(last.ln_e);
    }
    let (a, b) = (points[k - 1], points[k]);
    let w = (ln_t - a.ln_t) / (b.ln_t - a.ln_t);
    Some(a.ln_e + w * (b.ln_e - a.ln_e))
}

/// The time rescaling `alpha` that best lays a curve onto a reference curve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Collapse {
    /// The time rescaling: the curve at time `t` matches the reference at `alpha t`, i.e.
    /// `E(t) = E_ref(alpha t)`.
    pub alpha: f64,
    /// RMS of `ln E - ln E_ref` over the overlap at the best `alpha`.
    pub rms: f64,
    /// The overlap used, in the reference's time (snapshots).
    pub t_lo: f64,
    /// End of the overlap, in the reference's time (snapshots).
    pub t_hi: f64,
}

/// Rules of the collapse search.
#[derive(Clone, Copy, Debug)]
pub struct CollapseRule {
    /// Smallest overlap accepted, in decades of time.
    pub min_overlap_decades: f64,
    /// Search range of `alpha`.
    pub alpha_min: f64,
    /// Upper end of the search range of `alpha`.
    pub alpha_max: f64,
    /// Comparison points per decade of the overlap.
    pub points_per_decade: usize,
}

impl Default for CollapseRule {
    fn default() -> Self {
        CollapseRule {
            min_overlap_decades: 0.3,
            alpha_min: 0.02,
            alpha_max: 50.0,
            points_per_decade: 40,
        }
    }
}

/// Mismatch of `curve` with time multiplied by `alpha` against `reference`: the RMS difference
/// of `ln E` at log-spaced times of the overlap. `None` when the overlap is shorter than the rule
/// allows.
pub fn mismatch(
    reference: &[LogPoint],
    curve: &[LogPoint],
    alpha: f64,
    rule: &CollapseRule,
) -> Option<(f64, f64, f64)> {
    let la = alpha.ln();
    let lo = reference.first()?.ln_t.max(curve.first()?.ln_t + la);
    let hi = reference.last()?.ln_t.min(curve.last()?.ln_t + la);
    let decades = (hi - lo) / std::f64::consts::LN_10;
    if !(decades >= rule.min_overlap_decades) {
        return None;
    }
    let m = ((decades * rule.points_per_decade as f64).ceil() as usize).max(2);
    let mut ss = 0.0;
    for j in 0..=m {
        let x = lo + (hi - lo) * j as f64 / m as f64;
        let r = interp(reference, x)?;
        let c = interp(curve, x - la)?;
        ss += (c - r).powi(2);
    }
    Some(((ss / (m + 1) as f64).sqrt(), lo.exp(), hi.exp()))
}

/// Find the `alpha` that minimizes [`mismatch`]: a grid over `ln alpha` (steps of 0.005) and a
/// golden-section refinement around the best grid point. Deterministic.
pub fn collapse(
    reference: &[LogPoint],
    curve: &[LogPoint],
    rule: &CollapseRule,
) -> Option<Collapse> {
    let (a0, a1) = (rule.alpha_min.ln(), rule.alpha_max.ln());
    let h = 0.005;
    let steps = ((a1 - a0) / h).ceil() as usize;
    let mut best: Option<(f64, f64)> = None;
    for k in 0..=steps {
        let la = a0 + (a1 - a0) * k as f64 / steps as f64;
        if let Some((r, _, _)) = mismatch(reference, curve, la.exp(), rule) {
            if best.is_none_or(|(_, br)| r < br) {
                best = Some((la, r));
            }
        }
    }
    let (mut lo, mut hi) = {
        let (la, _) = best?;
        (la - h, la + h)
    };
    let f = |la: f64| mismatch(reference, curve, la.exp(), rule).map_or(f64::INFINITY, |m| m.0);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..40 {
        if fc < fd {
            hi = d;
            d = c;
            fd = fc;
            c = hi - g * (hi - lo);
            fc = f(c);
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + g * (hi - lo);
            fd = f(d);
        }
    }
    let la = 0.5 * (lo + hi);
    let (la, (rms, t_lo, t_hi)) = match mismatch(reference, curve, la.exp(), rule) {
        Some(m) if m.0 <= best?.1 => (la, m),
        _ => {
            let la = best?.0;
            (la, mismatch(reference, curve, la.exp(), rule)?)
        }
    };
    Some(Collapse {
        alpha: la.exp(),
        rms,
        t_lo,
        t_hi,
    })
}

/// The first snapshot after the maximum of `e` at which `e` has fallen to `fraction` of that
/// maximum: where a container has started to leak.
pub fn leak_onset(e: &[f64], fraction: f64) -> Option<usize> {
    let (imax, emax) = e
        .iter()
        .copied()
        .enumerate()
        .fold(
            (0, f64::NEG_INFINITY),
            |b, (i, x)| if x > b.1 { (i, x) } else { b },
        );
    if !(emax > 0.0) {
        return None;
    }
    (imax..e.len()).find(|&i| e[i] <= fraction * emax)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn power_curve(n: usize, a: f64, gamma: f64, t0: f64) -> Vec<f64> {
        (0..=n)
            .map(|t| {
                if t == 0 {
                    0.0
                } else {
                    a * (t as f64 * t0).powf(-gamma)
                }
            })
            .collect()
    }

    #[test]
    fn student_t_matches_tables() {
        // Tabulated 97.5 % quantiles, to the 6 decimals of the tables (the bisection and the
        // incomplete beta function are accurate to ~1e-12; the tables round at 5e-7).
        for (nu, q) in [
            (1.0, 12.706205),
            (2.0, 4.302653),
            (3.0, 3.182446),
            (5.0, 2.570582),
            (10.0, 2.228139),
            (20.0, 2.085963),
            (30.0, 2.042272),
            (100.0, 1.983972),
        ] {
            assert!(
                (student_t_975(nu) - q).abs() < 1e-6,
                "nu = {nu}: {} vs {q}",
                student_t_975(nu)
            );
        }
    }

    #[test]
    fn exact_power_law_is_recovered_with_zero_width_interval() {
        let e = power_curve(4000, 65.31, 0.7055, 1.0);
        let pts = log_bins(&e, 400, 4000, 20);
        assert_eq!(pts.len(), 20);
        let f = fit_power_law(&pts).unwrap();
        // Bin means of ln t and ln E of an exact power law lie on the same line: only round-off
        // (~1e-15 relative in the logs) remains.
        assert_relative_eq!(f.gamma, 0.7055, max_relative = 1e-12);
        assert_relative_eq!(f.a, 65.31, max_relative = 1e-10);
        assert!(f.se < 1e-12 && f.ci_hi - f.ci_lo < 1e-11);
    }

    #[test]
    fn noisy_power_law_interval_covers_truth_and_has_textbook_width() {
        // A deterministic +-1 % alternating perturbation: known residual size.
        let e = power_curve(4000, 100.0, 0.8, 1.0);
        let pts: Vec<LogPoint> = log_bins(&e, 400, 4000, 20)
            .into_iter()
            .enumerate()
            .map(|(k, mut p)| {
                p.ln_e += if k % 2 == 0 { 0.01 } else { -0.01 };
                p
            })
            .collect();
        let f = fit_power_law(&pts).unwrap();
        assert!(f.ci_lo < 0.8 && 0.8 < f.ci_hi, "{f:?}");
        // Independent check of SE: residuals are +-0.01 (the alternation is nearly orthogonal
        // to ln t), so SE ~ 0.01 / sqrt(sum (x - mean)^2) within 10 %.
        let mx = pts.iter().map(|p| p.ln_t).sum::<f64>() / pts.len() as f64;
        let sxx: f64 = pts.iter().map(|p| (p.ln_t - mx).powi(2)).sum();
        let expect = 0.01 * (pts.len() as f64 / (pts.len() as f64 - 2.0)).sqrt() / sxx.sqrt();
        assert_relative_eq!(f.se, expect, max_relative = 0.1);
    }

    #[test]
    fn collapse_finds_the_time_scale_of_a_rescaled_power_law() {
        // E_x(t) = E_ref(alpha t): the collapse must find alpha, for alpha above and below 1.
        let reference = log_bins(&power_curve(4000, 100.0, 0.75, 1.0), 100, 4000, 20);
        for alpha in [0.22, 0.5, 2.0, 9.0] {
            let x = power_curve(4000, 100.0, 0.75, alpha);
            let curve = log_bins(&x, 10, 4000, 20);
            let c = collapse(&reference, &curve, &CollapseRule::default()).unwrap();
            // A pure power law is matched by any alpha up to the factor A: here A is the same,
            // so the minimum is at alpha exactly; the golden-section search resolves ln alpha to
            // ~1e-6, and interpolation between bins adds ~1e-4 in ln E (curvature of ln E in
            // ln t is zero, so in fact less).
            assert_relative_eq!(c.alpha, alpha, max_relative = 1e-3);
            assert!(c.rms < 1e-6, "{c:?}");
        }
    }

    #[test]
    fn leak_onset_is_after_the_maximum() {
        let e = vec![0.0, 1.0, 4.0, 3.0, 2.5, 1.9, 1.0];
        assert_eq!(leak_onset(&e, 0.5), Some(5));
        assert_eq!(leak_onset(&[0.0, 0.0], 0.5), None);
    }

    #[test]
    fn bins_skip_empty_and_nonpositive() {
        let e = vec![0.0, 0.0, 1.0, 1.0, 1.0];
        let b = log_bins(&e, 1, 4, 10);
        assert!(b.iter().all(|p| p.ln_e == 0.0));
        assert_eq!(b.iter().map(|p| p.count).sum::<usize>(), 3);
    }
}
