//! The statistics of a study from its members (band, gamma, slope, alpha, budget).

use super::*;
use crate::batch::Member;
use crate::error::Error;
use crate::study::random::Design;
use crate::study::sweep::{KeyKind, SweepFile};
use grainchain_engine::analysis::decay::{
    fit_window, gamma_withheld, onset_bins, BINS_PER_DECADE, SLOPE_BINS_PER_DECADE,
    SLOPE_HALF_WIDTH, SLOPE_TOLERANCE,
};
use grainchain_engine::analysis::ensemble::{self, Estimate};
use grainchain_engine::analysis::{collapse, log_bins, student_t_975, CollapseRule};

fn fraction_curves(ms: &[&Member]) -> Vec<Vec<f64>> {
    ms.iter()
        .map(|m| {
            m.energy[0]
                .iter()
                .map(|e| e / m.meta.initial_energy)
                .collect()
        })
        .collect()
}

fn peak(e: &[f64]) -> usize {
    e.iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map_or(0, |(i, _)| i)
}

/// Jackknife of a per-index statistic (the local slope at each bin): entry `i` of the result is
/// the estimate of entry `i` (all leave-one-out vectors must have the same length, else NaN
/// intervals).
fn jackknife_vec(members: &[&[f64]], stat: impl Fn(&[f64]) -> Vec<f64>) -> Vec<Estimate> {
    let n = members.len();
    let full = stat(&ensemble::mean_curve(members, None));
    let loo: Vec<Vec<f64>> = if n >= 2 {
        (0..n)
            .map(|i| stat(&ensemble::mean_curve(members, Some(i))))
            .collect()
    } else {
        Vec::new()
    };
    let ok = !loo.is_empty() && loo.iter().all(|l| l.len() == full.len());
    let nf = n as f64;
    let q = if n >= 2 {
        student_t_975(nf - 1.0)
    } else {
        f64::NAN
    };
    full.iter()
        .enumerate()
        .map(|(j, &v)| {
            let se = if ok {
                let m = loo.iter().map(|l| l[j]).sum::<f64>() / nf;
                ((nf - 1.0) / nf * loo.iter().map(|l| (l[j] - m).powi(2)).sum::<f64>()).sqrt()
            } else {
                f64::NAN
            };
            Estimate {
                value: v,
                se,
                ci_lo: v - q * se,
                ci_hi: v + q * se,
                n,
            }
        })
        .collect()
}

fn slope_at(slope: &[SlopeRow], t: f64) -> Option<f64> {
    let j = slope.iter().position(|s| s.t >= t)?;
    if j == 0 {
        return (slope[0].t == t).then_some(slope[0].slope);
    }
    let (a, b) = (slope[j - 1], slope[j]);
    let w = (t.ln() - a.t.ln()) / (b.t.ln() - a.t.ln());
    Some(a.slope + w * (b.slope - a.slope))
}

fn key_result(
    key: &str,
    kind: KeyKind,
    ms: &[&Member],
    levels: &[f64],
) -> Result<KeyResult, Error> {
    let curves = fraction_curves(ms);
    let refs: Vec<&[f64]> = curves.iter().map(|c| &c[..]).collect();
    let band = ensemble::bands(&refs);
    let n = band.len().saturating_sub(1);
    let mean: Vec<f64> = band.iter().map(|b| b.mean).collect();
    let (onset, _) = onset_bins(&mean);
    let (lo, hi) = fit_window(n, onset);
    let g = |lo: usize, hi: usize| move |e: &[f64]| ensemble::gamma(e, lo, hi, BINS_PER_DECADE);
    // No gamma before the leak onset or over less than MIN_FIT_DECADES: the reason instead.
    let withheld = gamma_withheld(onset, lo, hi);
    let fit = WindowFit {
        t_lo: lo,
        t_hi: hi,
        est: withheld
            .is_none()
            .then(|| ensemble::jackknife(&refs, g(lo, hi)))
            .flatten(),
        withheld: withheld.clone(),
    };
    let member_gamma = refs
        .iter()
        .map(|c| withheld.is_none().then(|| g(lo, hi)(c)).flatten())
        .collect();
    // Decades of time from the leak onset on: [t_on, 10 t_on], [10 t_on, 100 t_on], ..; the last
    // one, cut at N, only if it spans at least MIN_FIT_DECADES. None without a leak onset.
    let mut decades = Vec::new();
    let mut a = onset.map_or(n, |o| o.max(1));
    while a < n {
        let b = (a * 10).min(n);
        if gamma_withheld(onset, a, b).is_none() {
            decades.push(WindowFit {
                t_lo: a,
                t_hi: b,
                est: ensemble::jackknife(&refs, g(a, b)),
                withheld: None,
            });
        }
        a *= 10;
    }
    let p = peak(&mean).max(1);
    let slope_of = |e: &[f64]| {
        ensemble::local_slope(e, p, n, SLOPE_BINS_PER_DECADE, SLOPE_HALF_WIDTH)
            .into_iter()
            .map(|s| s.slope)
            .collect::<Vec<f64>>()
    };
    let ts: Vec<f64> = ensemble::local_slope(&mean, p, n, SLOPE_BINS_PER_DECADE, SLOPE_HALF_WIDTH)
        .into_iter()
        .map(|s| s.t)
        .collect();
    let slope: Vec<SlopeRow> = jackknife_vec(&refs, slope_of)
        .into_iter()
        .zip(&ts)
        .map(|(e, &t)| SlopeRow {
            t,
            slope: e.value,
            se: e.se,
            ci_lo: e.ci_lo,
            ci_hi: e.ci_hi,
        })
        .collect();
    let values: Vec<f64> = slope.iter().map(|s| s.slope).collect();
    let constant = ensemble::constant_stretch(&values, SLOPE_TOLERANCE).map(|(i, j)| {
        let (mn, mx) = values[i..=j]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        (slope[i].t, slope[j].t, 0.5 * (mn + mx))
    });
    let level_slopes = levels
        .iter()
        .map(|&l| (l, level_time(&mean, l).and_then(|t| slope_at(&slope, t))))
        .collect();
    let gauges = gauges(ms, &refs, n);
    let regions: Vec<String> = (ms[0].regions.iter())
        .filter(|r| crate::batch::Gauge::of_column(r).is_none())
        .cloned()
        .collect();
    // The sections outside the container are sampled (member files hold them at these snapshots
    // only); the container, recorded at every snapshot, is shown at the same ones.
    let budget_at = budget_outputs(n);
    let budget = (0..regions.len())
        .map(|r| {
            let cs: Vec<Vec<f64>> = ms
                .iter()
                .map(|m| {
                    let k = m.regions.iter().position(|x| *x == regions[r]);
                    budget_at
                        .iter()
                        .map(|&t| k.map_or(f64::NAN, |k| m.energy[k][t] / m.meta.initial_energy))
                        .collect()
                })
                .collect();
            let rr: Vec<&[f64]> = cs.iter().map(|c| &c[..]).collect();
            ensemble::mean_curve(&rr, None)
        })
        .collect();
    let design = match ms[0]
        .meta
        .design
        .as_ref()
        .filter(|_| kind == KeyKind::Random)
    {
        Some(v) => Some(
            serde_json::from_value::<DesignIn>(v.clone())
                .map_err(|e| crate::error::StudyError::Design {
                    key: key.to_string(),
                    message: e.to_string(),
                })?
                .into(),
        ),
        None => None,
    };
    Ok(KeyResult {
        key: key.to_string(),
        members: ms.len(),
        regions,
        e0: ms.iter().map(|m| m.meta.initial_energy).sum::<f64>() / ms.len() as f64,
        band,
        budget_at,
        budget,
        fit,
        member_gamma,
        decades,
        onset,
        slope,
        constant,
        level_slopes,
        design,
        max_energy_error: ms
            .iter()
            .map(|m| m.meta.max_energy_error)
            .fold(0.0, f64::max),
        min_end_margin: ms.iter().map(|m| m.meta.end_margin).min().unwrap_or(0),
        wall_per_member: ms.iter().map(|m| m.meta.wall).sum::<f64>() / ms.len() as f64,
        gauges,
        speed: None,
    })
}

/// The gauges over the late window `[n/2, n]` and their mean curves at the budget's snapshots
/// (None when the member files have none); `fractions` are the members' `E_R / E0`.
fn gauges(ms: &[&Member], fractions: &[&[f64]], n: usize) -> Option<Gauges> {
    fn column<'m>(m: &'m Member, name: &str) -> Option<&'m [f64]> {
        let k = m.regions.iter().position(|r| r == name)?;
        Some(&m.energy[k])
    }
    let (lo, hi) = (n / 2, n);
    let window_mean = |x: &[f64]| x[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64;
    let mut er = Vec::with_capacity(ms.len());
    let mut members = Vec::with_capacity(ms.len());
    let mut series: Vec<Vec<&[f64]>> = Vec::with_capacity(ms.len());
    for (m, e) in ms.iter().zip(fractions) {
        let columns = (crate::batch::Gauge::ALL.iter())
            .map(|g| column(m, g.name()))
            .collect::<Option<Vec<&[f64]>>>()?;
        er.push(window_mean(e));
        members.push(columns.iter().map(|c| window_mean(c)).collect());
        series.push(columns);
    }
    let at = budget_outputs(n);
    let curves = (0..crate::batch::Gauge::ALL.len())
        .map(|j| {
            at.iter()
                .map(|&t| series.iter().map(|s| s[j][t]).sum::<f64>() / series.len() as f64)
                .collect()
        })
        .collect();
    Some(Gauges {
        window: (lo, hi),
        er,
        members,
        curves,
    })
}

/// The design as read back from a member file.
#[derive(serde::Deserialize)]
struct DesignIn {
    key: String,
    walls: crate::study::sweep::Walls,
    sections: usize,
    grains: u64,
    mass_ratio: f64,
    frac_p1: f64,
    frac_p15: f64,
    frac_p2: f64,
    layout: String,
}

impl From<DesignIn> for Design {
    fn from(d: DesignIn) -> Self {
        Design {
            key: d.key,
            walls: d.walls,
            sections: d.sections,
            grains: d.grains,
            mass_ratio: d.mass_ratio,
            frac_p1: d.frac_p1,
            frac_p15: d.frac_p15,
            frac_p2: d.frac_p2,
            layout: d.layout,
        }
    }
}

fn level_time(curve: &[f64], level: f64) -> Option<f64> {
    let p = peak(curve).max(1);
    ensemble::crossing_time(&log_bins(curve, p, curve.len() - 1, BINS_PER_DECADE), level)
}

/// Compute every statistic of the study from its members (in study order).
pub fn analyse(
    sweep: &SweepFile,
    members: Vec<Member>,
    kinds: &std::collections::HashMap<String, KeyKind>,
) -> Result<Study, Error> {
    let s = &sweep.sweep;
    let mut keys: Vec<String> = Vec::new();
    for m in &members {
        if keys.last() != Some(&m.key) {
            keys.push(m.key.clone());
        }
    }
    let mut containers = Vec::new();
    let mut random = Vec::new();
    let mut searched = Vec::new();
    for k in &keys {
        let ms: Vec<&Member> = members.iter().filter(|m| &m.key == k).collect();
        let kind = kinds.get(k).copied().unwrap_or(KeyKind::Container);
        let mut r = key_result(k, kind, &ms, &s.levels)?;
        r.speed = s
            .containers
            .iter()
            .find(|c| &c.key == k)
            .and_then(|c| c.speed);
        match kind {
            KeyKind::Random => random.push(r),
            KeyKind::Search => searched.push(r),
            KeyKind::Container => containers.push(r),
        }
    }
    let search = match &s.search {
        Some(spec) => search_rows(spec, &searched),
        None => Vec::new(),
    };
    let mut alpha = Vec::new();
    let mut collapses = Vec::new();
    if let Some(rk) = &s.reference {
        let curves_of = |key: &str| {
            fraction_curves(
                &members
                    .iter()
                    .filter(|m| m.key == key)
                    .collect::<Vec<&Member>>(),
            )
        };
        let rc = curves_of(rk);
        let rr: Vec<&[f64]> = rc.iter().map(|c| &c[..]).collect();
        let ref_mean = ensemble::mean_curve(&rr, None);
        let (_, ref_bins) = onset_bins(&ref_mean);
        for c in &containers {
            let cc = curves_of(&c.key);
            let cr: Vec<&[f64]> = cc.iter().map(|c| &c[..]).collect();
            for &level in &s.levels {
                let lt = |e: &[f64]| level_time(e, level).map(f64::ln);
                let er = ensemble::jackknife(&rr, lt);
                let ek = ensemble::jackknife(&cr, lt);
                let (t_ref, t_key) = (er.map(|e| e.value.exp()), ek.map(|e| e.value.exp()));
                let alpha_v = t_ref.zip(t_key).map(|(a, b)| a / b);
                let (mut lo, mut hi) = (f64::NAN, f64::NAN);
                // The reference against itself is 1 by definition (no interval).
                if c.key == *rk {
                } else if let (Some(a), Some(er), Some(ek)) = (alpha_v, er, ek) {
                    let se = (er.se.powi(2) + ek.se.powi(2)).sqrt();
                    let dof = (er.n.min(ek.n) as f64) - 1.0;
                    if dof >= 1.0 && se.is_finite() {
                        let q = student_t_975(dof);
                        lo = a * (-q * se).exp();
                        hi = a * (q * se).exp();
                    }
                }
                alpha.push(AlphaRow {
                    key: c.key.clone(),
                    level,
                    t_ref,
                    t_key,
                    alpha: alpha_v,
                    ci_lo: lo,
                    ci_hi: hi,
                });
            }
            let mean = ensemble::mean_curve(&cr, None);
            let (_, bins) = onset_bins(&mean);
            let col = if &c.key == rk {
                None
            } else {
                collapse(&ref_bins, &bins, &CollapseRule::default())
            };
            collapses.push((c.key.clone(), col));
        }
    }
    let inputs: Vec<super::mechanism::KeyInput<'_>> = containers
        .iter()
        .map(|k| super::mechanism::KeyInput {
            key: &k.key,
            mean: k.band.iter().map(|b| b.mean).collect(),
            late: k.gauges.as_ref().map(|g| {
                let forces = (0..g.members.len())
                    .map(|i| {
                        (g.of(i, crate::batch::Gauge::ForceLeft)
                            + g.of(i, crate::batch::Gauge::ForceRight))
                            / 2.0
                    })
                    .collect();
                (g.window, forces)
            }),
        })
        .collect();
    let mechanism = super::mechanism::analyse(&inputs, &members);
    Ok(Study {
        name: s.name.clone(),
        description: s.description.clone(),
        digest: sweep.digest.clone(),
        snapshots: s.snapshots,
        perturbation: match s.perturbation {
            crate::study::sweep::Perturbation::StrikerSpeed { epsilon } => {
                format!("striker speed x (1 + k {epsilon:e}), member k = 0, 1, ..")
            }
            crate::study::sweep::Perturbation::Displacement { amplitude, seed } => format!(
                "container grains displaced uniformly in +-{amplitude:e} (ChaCha8, seed {seed}, stream 2^32 + member)"
            ),
        },
        containers,
        random,
        search,
        searched,
        reference: s.reference.clone(),
        alpha,
        collapse: collapses,
        job_seconds: members.iter().map(|m| m.meta.wall).sum(),
        missing: Vec::new(),
        mechanism,
    })
}

/// Score every reading of the search whose containers a, c, d, e all have members, with `t`
/// from the strike and from the arrival.
fn search_rows(spec: &crate::study::search::SearchSpec, keys: &[KeyResult]) -> Vec<SearchRow> {
    use crate::study::search::{gamma_withheld_of, reading, score, TimeOrigin};
    let mut rows = Vec::new();
    for i in 1..=spec.count {
        let of = |c: &str| keys.iter().find(|k| k.key == KeyKind::search(i, c));
        let (Some(a), Some(c), Some(d), Some(e)) = (of("a"), of("c"), of("d"), of("e")) else {
            continue;
        };
        let mean = |k: &KeyResult| k.band.iter().map(|b| b.mean).collect::<Vec<f64>>();
        let curves = [mean(a), mean(c), mean(d), mean(e)];
        for origin in [TimeOrigin::Strike, TimeOrigin::Arrival] {
            rows.push(SearchRow {
                index: i,
                reading: reading(spec, i),
                origin,
                score: score([&curves[0], &curves[1], &curves[2], &curves[3]], origin),
                decades: a.decades.iter().map(|w| w.est.map(|e| e.value)).collect(),
                note: gamma_withheld_of(&curves[0], origin),
                members: a.members,
            });
        }
    }
    rows
}
