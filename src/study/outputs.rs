//! The statistics of a study and its files: CSV tables, SVG figures and STUDY.md.
//!
//! Per container (a key), from its members' container energy normalized by each member's own
//! incident energy, `f_k(t) = E_R,k(t) / E0_k`:
//! - **band**: mean, median, 5 % and 95 % over members at every snapshot (`ensemble.csv`);
//! - **budget**: the mean fraction of the incident energy in the container and in every section
//!   outside it (`budget.csv`);
//! - **gamma** of the mean curve over the fit window `[N/10, N]` (never before the leak onset,
//!   as in `reproduce`), with the jackknife interval over members
//!   ([`crate::analysis::ensemble`]), and each member's own gamma over the same window
//!   (`fits.csv`); also per decade of time from the leak onset `t_on` (`[t_on, 10 t_on]`, ..., a last partial
//!   decade if it spans at least 0.3 decade);
//! - **local slope** `d ln E / d ln t` of the mean curve from its peak on, 10 log bins per
//!   decade, least squares over +-2 bins (half a decade), with its jackknife interval
//!   (`slope.csv`), and the longest stretch where it stays within +-0.05 of a constant;
//! - **alpha by level**: the time `t_X(L)` at which the binned mean curve first falls to level
//!   `L` after its peak; `alpha = t_ref(L) / t_X(L)` (so that `E_X(t) = E_ref(alpha t)`, the
//!   convention of `reproduce`), with the jackknife standard errors of `ln t_ref` and `ln t_X`
//!   combined in quadrature (the two ensembles are independent) and Student t with
//!   `min(n_ref, n_X) - 1` degrees of freedom (`alpha.csv`); beside it the collapse alpha of
//!   `reproduce` (least RMS mismatch) of the mean curves.
//!
//! Random containers get the same gamma with interval; `random.csv` lists them with their
//! designs, and STUDY.md gives the distribution of gamma and its correlation with each design
//! parameter.

use super::random::Design;
use super::{Member, SweepFile};
use crate::analysis::ensemble::{self, Band, Estimate};
use crate::analysis::{collapse, log_bins, student_t_975, Collapse, CollapseRule};
use crate::error::Error;
use crate::report::atomic::AtomicFile;
use crate::report::plot::{LineChart, Scale, Series};
use crate::reproduce::figures::{fit_window, onset_bins, BINS_PER_DECADE, ONSET_FRACTION};
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// Log bins per decade of the local slope.
pub const SLOPE_BINS_PER_DECADE: usize = 10;
/// Half width of the local-slope window, in bins (a fit over up to 5 bins, half a decade).
pub const SLOPE_HALF_WIDTH: usize = 2;
/// "Within +-0.05 of a constant" (the criterion).
pub const SLOPE_TOLERANCE: f64 = 0.05;

/// A point of the local slope with its jackknife interval.
#[derive(Clone, Copy, Debug)]
pub struct SlopeRow {
    /// Time of the point, in snapshots since the strike (`exp` of the mean `ln t` of its bin).
    pub t: f64,
    /// Local slope `d ln E_R / d ln t` of the mean curve (`-gamma` of a local power law).
    pub slope: f64,
    /// Jackknife standard error of the slope over members.
    pub se: f64,
    /// Lower end of the 95 % interval (Student t, members - 1 degrees of freedom).
    pub ci_lo: f64,
    /// Upper end of the 95 % interval.
    pub ci_hi: f64,
}

/// A fit over a stated window.
#[derive(Clone, Debug)]
pub struct WindowFit {
    /// First snapshot of the window.
    pub t_lo: usize,
    /// Last snapshot of the window (inclusive).
    pub t_hi: usize,
    /// gamma fitted to the mean curve over the window with its jackknife interval over members;
    /// None when the fit fails.
    pub est: Option<Estimate>,
}

/// Everything measured for one container.
#[derive(Clone, Debug)]
pub struct KeyResult {
    /// The container's key (`a`, `r-007`).
    pub key: String,
    /// Number of members merged.
    pub members: usize,
    /// Region names of the member files: `container` first, then the sections outside it.
    pub regions: Vec<String>,
    /// Mean incident energy over members.
    pub e0: f64,
    /// Mean, median and 5-95 % band of `E_R / E_0` over members at every snapshot.
    pub band: Vec<Band>,
    /// `budget[r][t]`: mean fraction of the incident energy in region `r`.
    pub budget: Vec<Vec<f64>>,
    /// The main fit: gamma over snapshots from `max(N/10, leak onset)` to `N` (the run length).
    pub fit: WindowFit,
    /// gamma of each member's own curve over the main fit's window (None where the fit fails).
    pub member_gamma: Vec<Option<f64>>,
    /// gamma over successive decades of time from the leak onset on (`[t_on, 10 t_on]`, ...; a
    /// last, shorter window only if it spans at least 0.3 decade).
    pub decades: Vec<WindowFit>,
    /// The local slope over time, from the peak of the mean curve on.
    pub slope: Vec<SlopeRow>,
    /// Longest stretch of the local slope within +-0.05 of a constant: first and last `t`, the
    /// constant (mid-range).
    pub constant: Option<(f64, f64, f64)>,
    /// The local slope where the mean curve first falls to each level of the sweep (interpolated
    /// in `ln t` between slope points): comparing containers at equal `E_R` rather than at equal
    /// time removes the time rescaling alpha, so under the paper's claim (one power law, curves
    /// that differ by a time scale) these agree across containers.
    pub level_slopes: Vec<(f64, Option<f64>)>,
    /// Random containers: the drawn design (None for a container from a scene file).
    pub design: Option<Design>,
    /// Largest relative energy error of any member at any output time.
    pub max_energy_error: f64,
    /// Smallest end margin of any member: grains between the furthest disturbance and the nearer
    /// chain end at the end of the run.
    pub min_end_margin: usize,
    /// Mean wall time per member (seconds).
    pub wall_per_member: f64,
}

/// alpha of one container at one level.
#[derive(Clone, Debug)]
pub struct AlphaRow {
    /// The container's key.
    pub key: String,
    /// The E_R level (fraction of the incident energy).
    pub level: f64,
    /// Time at which the reference's mean curve falls to the level (snapshots; None if it never
    /// does).
    pub t_ref: Option<f64>,
    /// Time at which this container's mean curve falls to the level (snapshots).
    pub t_key: Option<f64>,
    /// `t_ref / t_key`: the time rescaling such that `E_key(t) = E_ref(alpha t)` at this level
    /// (1 for the reference itself).
    pub alpha: Option<f64>,
    /// Lower end of the 95 % interval of alpha, from the jackknifed `ln t` of both containers
    /// (NaN for the reference itself or with too few members).
    pub ci_lo: f64,
    /// Upper end of the 95 % interval of alpha.
    pub ci_hi: f64,
}

/// The whole study.
#[derive(Clone, Debug)]
pub struct Study {
    /// The sweep's `name`.
    pub name: String,
    /// The sweep's `description`.
    pub description: Option<String>,
    /// The sweep's run digest (the member files' `sweep`).
    pub digest: String,
    /// Run length of every member, in snapshots.
    pub snapshots: u64,
    /// The perturbation, in words (for `STUDY.md`).
    pub perturbation: String,
    /// Results of the `[[containers]]` entries, in study order.
    pub containers: Vec<KeyResult>,
    /// Results of the random containers, in study order.
    pub random: Vec<KeyResult>,
    /// Key of the reference container of alpha and the collapse, if the sweep names one.
    pub reference: Option<String>,
    /// alpha of every container at every level (empty without a reference).
    pub alpha: Vec<AlphaRow>,
    /// For each container, the collapse of its mean curve onto the reference's (from the leak
    /// onsets on); None for the reference itself or when no overlap fits.
    pub collapse: Vec<(String, Option<Collapse>)>,
    /// Sum of the members' wall times.
    pub job_seconds: f64,
    /// Members not (yet) run, when merged with `--partial`.
    pub missing: Vec<String>,
}

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

fn key_result(key: &str, ms: &[&Member], levels: &[f64]) -> Result<KeyResult, Error> {
    let curves = fraction_curves(ms);
    let refs: Vec<&[f64]> = curves.iter().map(|c| &c[..]).collect();
    let band = ensemble::bands(&refs);
    let n = band.len().saturating_sub(1);
    let mean: Vec<f64> = band.iter().map(|b| b.mean).collect();
    let (onset, _) = onset_bins(&mean);
    let (lo, hi) = fit_window(n, onset);
    let g = |lo: usize, hi: usize| move |e: &[f64]| ensemble::gamma(e, lo, hi, BINS_PER_DECADE);
    let fit = WindowFit {
        t_lo: lo,
        t_hi: hi,
        est: ensemble::jackknife(&refs, g(lo, hi)),
    };
    let member_gamma = refs.iter().map(|c| g(lo, hi)(c)).collect();
    // Decades of time from the leak onset on: [t_on, 10 t_on], [10 t_on, 100 t_on], ..; the last
    // one, cut at N, only if it spans at least 0.3 decade.
    let mut decades = Vec::new();
    let mut a = onset.unwrap_or(100).max(1);
    while a < n {
        let b = (a * 10).min(n);
        if (b as f64 / a as f64).log10() >= 0.3 {
            decades.push(WindowFit {
                t_lo: a,
                t_hi: b,
                est: ensemble::jackknife(&refs, g(a, b)),
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
    let regions = ms[0].regions.clone();
    let budget = (0..regions.len())
        .map(|r| {
            let cs: Vec<Vec<f64>> = ms
                .iter()
                .map(|m| {
                    let k = m.regions.iter().position(|x| *x == regions[r]);
                    (0..=n)
                        .map(|t| k.map_or(f64::NAN, |k| m.energy[k][t] / m.meta.initial_energy))
                        .collect()
                })
                .collect();
            let rr: Vec<&[f64]> = cs.iter().map(|c| &c[..]).collect();
            ensemble::mean_curve(&rr, None)
        })
        .collect();
    let design = match &ms[0].meta.design {
        Some(v) => Some(
            serde_json::from_value::<DesignIn>(v.clone())
                .map_err(|e| Error::Other(format!("{key}: design in member file: {e}")))?
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
        budget,
        fit,
        member_gamma,
        decades,
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
    })
}

/// The design as read back from a member file.
#[derive(serde::Deserialize)]
struct DesignIn {
    key: String,
    walls: super::sweep::Walls,
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
pub fn analyse(sweep: &SweepFile, members: Vec<Member>) -> Result<Study, Error> {
    let s = &sweep.sweep;
    let mut keys: Vec<String> = Vec::new();
    for m in &members {
        if keys.last() != Some(&m.key) {
            keys.push(m.key.clone());
        }
    }
    let mut containers = Vec::new();
    let mut random = Vec::new();
    for k in &keys {
        let ms: Vec<&Member> = members.iter().filter(|m| &m.key == k).collect();
        let r = key_result(k, &ms, &s.levels)?;
        if k.starts_with("r-") {
            random.push(r);
        } else {
            containers.push(r);
        }
    }
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
    let _ = ONSET_FRACTION;
    Ok(Study {
        name: s.name.clone(),
        description: s.description.clone(),
        digest: sweep.digest.clone(),
        snapshots: s.snapshots,
        perturbation: match s.perturbation {
            super::sweep::Perturbation::StrikerSpeed { epsilon } => {
                format!("striker speed x (1 + k {epsilon:e}), member k = 0, 1, ..")
            }
            super::sweep::Perturbation::Displacement { amplitude, seed } => format!(
                "container grains displaced uniformly in +-{amplitude:e} (ChaCha8, seed {seed}, stream 2^32 + member)"
            ),
        },
        containers,
        random,
        reference: s.reference.clone(),
        alpha,
        collapse: collapses,
        job_seconds: members.iter().map(|m| m.meta.wall).sum(),
        missing: Vec::new(),
    })
}

fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

fn opt(x: Option<f64>) -> String {
    x.map_or_else(String::new, num)
}

fn csv_file(path: &Path, header: &str, rows: impl Iterator<Item = String>) -> Result<(), Error> {
    let mut f = AtomicFile::create(path)?;
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    writeln!(f, "{header}").map_err(io)?;
    for r in rows {
        writeln!(f, "{r}").map_err(io)?;
    }
    f.commit()
}

fn all(study: &Study) -> impl Iterator<Item = &KeyResult> {
    study.containers.iter().chain(&study.random)
}

/// Write the CSV tables, SVG figures and STUDY.md.
pub fn write(study: &Study, out: &Path) -> Result<(), Error> {
    csv_file(
        &out.join("ensemble.csv"),
        "key,snapshot,mean,median,p05,p95",
        all(study).flat_map(|k| {
            k.band.iter().enumerate().map(move |(t, b)| {
                format!(
                    "{},{t},{},{},{},{}",
                    k.key,
                    num(b.mean),
                    num(b.median),
                    num(b.p05),
                    num(b.p95)
                )
            })
        }),
    )?;
    csv_file(
        &out.join("budget.csv"),
        "key,region,snapshot,mean_fraction",
        study.containers.iter().flat_map(|k| {
            k.regions.iter().enumerate().flat_map(move |(r, name)| {
                k.budget[r]
                    .iter()
                    .enumerate()
                    .map(move |(t, x)| format!("{},{name},{t},{}", k.key, num(*x)))
            })
        }),
    )?;
    let mut fits = Vec::new();
    for k in all(study) {
        let row = |what: String, w: &WindowFit| {
            let e = w.est;
            format!(
                "{},{what},{},{},{},{},{},{},{}",
                k.key,
                w.t_lo,
                w.t_hi,
                opt(e.map(|e| e.value)),
                opt(e.map(|e| e.se)),
                opt(e.map(|e| e.ci_lo)),
                opt(e.map(|e| e.ci_hi)),
                e.map_or(0, |e| e.n)
            )
        };
        fits.push(row("mean".into(), &k.fit));
        for d in &k.decades {
            fits.push(row("decade".into(), d));
        }
        for (m, g) in k.member_gamma.iter().enumerate() {
            fits.push(format!(
                "{},member-{m},{},{},{},,,,1",
                k.key,
                k.fit.t_lo,
                k.fit.t_hi,
                opt(*g)
            ));
        }
    }
    csv_file(
        &out.join("fits.csv"),
        "key,fit,t_lo,t_hi,gamma,se,ci_lo,ci_hi,members",
        fits.into_iter(),
    )?;
    csv_file(
        &out.join("slope.csv"),
        "key,t,slope,se,ci_lo,ci_hi",
        all(study).flat_map(|k| {
            k.slope.iter().map(move |s| {
                format!(
                    "{},{},{},{},{},{}",
                    k.key,
                    num(s.t),
                    num(s.slope),
                    num(s.se),
                    num(s.ci_lo),
                    num(s.ci_hi)
                )
            })
        }),
    )?;
    csv_file(
        &out.join("alpha.csv"),
        "key,level,t_ref,t_key,alpha,ci_lo,ci_hi",
        study.alpha.iter().map(|a| {
            format!(
                "{},{},{},{},{},{},{}",
                a.key,
                num(a.level),
                opt(a.t_ref),
                opt(a.t_key),
                opt(a.alpha),
                num(a.ci_lo),
                num(a.ci_hi)
            )
        }),
    )?;
    if !study.random.is_empty() {
        csv_file(
            &out.join("random.csv"),
            "key,walls,sections,grains,mass_ratio,frac_p1,frac_p15,frac_p2,members,gamma,ci_lo,ci_hi,max_energy_error,layout",
            study.random.iter().map(|k| {
                let d = k.design.as_ref();
                let e = k.fit.est;
                format!(
                    "{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"",
                    k.key,
                    d.map_or("", |d| d.walls.name()),
                    d.map_or(0, |d| d.sections),
                    d.map_or(0, |d| d.grains),
                    num(d.map_or(f64::NAN, |d| d.mass_ratio)),
                    num(d.map_or(f64::NAN, |d| d.frac_p1)),
                    num(d.map_or(f64::NAN, |d| d.frac_p15)),
                    num(d.map_or(f64::NAN, |d| d.frac_p2)),
                    k.members,
                    opt(e.map(|e| e.value)),
                    opt(e.map(|e| e.ci_lo)),
                    opt(e.map(|e| e.ci_hi)),
                    num(k.max_energy_error),
                    d.map_or("", |d| d.layout.as_str())
                )
            }),
        )?;
    }
    plots(study, out)?;
    AtomicFile::write_all(out.join("STUDY.md"), report(study).as_bytes())
}

/// Log-spaced thinning of a curve for plotting (every snapshot up to 100, then ~200 per decade).
fn thin(n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (1..=n.min(100)).collect();
    let mut x = 100.0f64;
    while (x as usize) < n {
        x *= 10f64.powf(1.0 / 200.0);
        let t = (x as usize).min(n);
        if v.last() != Some(&t) {
            v.push(t);
        }
    }
    v
}

fn plots(study: &Study, out: &Path) -> Result<(), Error> {
    let mut series = Vec::new();
    for k in &study.containers {
        let idx = thin(k.band.len() - 1);
        let pts = |f: &dyn Fn(&Band) -> f64| -> Vec<(f64, f64)> {
            idx.iter()
                .map(|&t| (t as f64, f(&k.band[t])))
                .filter(|p| p.1 > 0.0)
                .collect()
        };
        series.push(Series {
            name: format!("({}) mean", k.key),
            points: pts(&|b| b.mean),
            markers: false,
            dashed: false,
        });
        series.push(Series {
            name: format!("({}) 5-95 %", k.key),
            points: pts(&|b| b.p05),
            markers: false,
            dashed: true,
        });
        series.push(Series {
            name: String::new(),
            points: pts(&|b| b.p95),
            markers: false,
            dashed: true,
        });
    }
    if !series.is_empty() {
        LineChart {
            title: "E_R / E0: ensemble mean and 5-95 % band",
            x_label: "t (snapshots)",
            y_label: "E_R / E0",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series,
        }
        .write(out.join("er_band.svg"))?;
    }
    let mut series = Vec::new();
    for k in &study.containers {
        series.push(Series {
            name: format!("({})", k.key),
            points: k.slope.iter().map(|s| (s.t, s.slope)).collect(),
            markers: true,
            dashed: false,
        });
        for (f, name) in [
            (
                &(|s: &SlopeRow| s.ci_lo) as &dyn Fn(&SlopeRow) -> f64,
                "95 % (jackknife)",
            ),
            (&|s: &SlopeRow| s.ci_hi, ""),
        ] {
            let pts: Vec<(f64, f64)> = k
                .slope
                .iter()
                .map(|s| (s.t, f(s)))
                .filter(|p| p.1.is_finite())
                .collect();
            if !pts.is_empty() {
                series.push(Series {
                    name: if name.is_empty() {
                        String::new()
                    } else {
                        format!("({}) {name}", k.key)
                    },
                    points: pts,
                    markers: false,
                    dashed: true,
                });
            }
        }
    }
    if !series.is_empty() {
        LineChart {
            title: "Local slope d ln E_R / d ln t of the ensemble mean",
            x_label: "t (snapshots)",
            y_label: "local slope",
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series,
        }
        .write(out.join("slope.svg"))?;
    }
    for k in &study.containers {
        let idx = thin(k.band.len() - 1);
        let series = k
            .regions
            .iter()
            .enumerate()
            .map(|(r, name)| Series {
                name: name.clone(),
                points: idx.iter().map(|&t| (t as f64, k.budget[r][t])).collect(),
                markers: false,
                dashed: false,
            })
            .collect();
        LineChart {
            title: &format!(
                "({}) where the energy is: mean fraction of E0 per region",
                k.key
            ),
            x_label: "t (snapshots)",
            y_label: "fraction of E0",
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series,
        }
        .write(out.join(format!("budget-{}.svg", k.key)))?;
    }
    let gammas: Vec<f64> = study
        .random
        .iter()
        .filter_map(|k| k.fit.est.map(|e| e.value))
        .collect();
    if !gammas.is_empty() {
        crate::report::plot::histogram(
            "gamma of random containers (ensemble mean, window [N/10, N])",
            "gamma",
            &gammas,
            0.1,
            out.join("gamma_hist.svg"),
        )?;
    }
    Ok(())
}

fn f3(x: Option<f64>) -> String {
    x.filter(|x| x.is_finite())
        .map_or_else(|| "n/a".into(), |x| format!("{x:.3}"))
}

fn est_text(e: Option<Estimate>) -> String {
    match e {
        Some(e) if e.se.is_finite() => {
            format!("{:.3} [{:.3}, {:.3}]", e.value, e.ci_lo, e.ci_hi)
        }
        Some(e) => format!("{:.3} (no interval: {} member)", e.value, e.n),
        None => "n/a".into(),
    }
}

/// Mean and sample standard deviation.
fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, v.sqrt())
}

/// STUDY.md: one section per function below, each a pure function of the study's results.
pub fn report(study: &Study) -> String {
    let mut s = String::new();
    header(&mut s, study);
    cost(&mut s, study);
    if !study.containers.is_empty() {
        gamma_of_mean(&mut s, study);
        gamma_per_decade(&mut s, study);
        local_slope(&mut s, study);
    }
    if study.containers.iter().any(|k| !k.level_slopes.is_empty()) {
        slope_at_levels(&mut s, study);
    }
    if !study.alpha.is_empty() {
        alpha_by_level(&mut s, study);
    }
    if !study.containers.is_empty() {
        budget(&mut s, study);
    }
    if !study.random.is_empty() {
        random_containers(&mut s, study);
    }
    let _ = writeln!(
        s,
        "\nFiles: ensemble.csv (band per snapshot), fits.csv (gamma of the mean, per decade, per \
         member), slope.csv, alpha.csv, budget.csv, random.csv; er_band.svg, slope.svg, \
         budget-<key>.svg, gamma_hist.svg."
    );
    s
}

/// A markdown table header: `| first | a | b |` and its rule.
fn table_head(s: &mut String, first: &str, columns: impl IntoIterator<Item = String>) {
    let mut head = format!("| {first} |");
    let mut rule = String::from("|---|");
    for c in columns {
        let _ = write!(head, " {c} |");
        rule.push_str("---|");
    }
    let _ = writeln!(s, "{head}\n{rule}");
}

fn header(s: &mut String, study: &Study) {
    let _ = writeln!(s, "# Study `{}`\n", study.name);
    if let Some(d) = &study.description {
        let _ = writeln!(s, "{d}\n");
    }
    if !study.missing.is_empty() {
        let _ = writeln!(
            s,
            "**PARTIAL: {} members missing** ({}); every number below uses the members present \
             (the member counts are in the cost table).\n",
            study.missing.len(),
            study.missing.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "Sweep digest `{}`. Every member runs {} snapshots; members differ by: {}. Container \
         layouts of scenes/containers/ are a RECONSTRUCTION (../shared/reference/containers.md). \
         Intervals are 95 %, from the spread over members (delete-one jackknife, Student t; \
         src/analysis/ensemble.rs), not from the residuals of one curve.\n",
        study.digest, study.snapshots, study.perturbation
    );
}

fn cost(s: &mut String, study: &Study) {
    let _ = writeln!(s, "## Cost\n");
    let _ = writeln!(
        s,
        "Sum of the members' wall times: {:.1} s (set-up included; on a machine of C cores the \
         study takes about this / C).\n",
        study.job_seconds
    );
    let _ = writeln!(
        s,
        "| key | members | wall per member (s) | max energy error | min end margin (grains) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for k in all(study) {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.1e} | {} |",
            k.key, k.members, k.wall_per_member, k.max_energy_error, k.min_end_margin
        );
    }
}

fn gamma_of_mean(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## gamma of the ensemble mean\n");
    let _ = writeln!(
        s,
        "Fit of `E_R / E0 = A t^-gamma` to the ensemble mean over the window (log bins, {} \
         per decade). Member gammas: each member's own fit over the same window, mean +- \
         standard deviation. Paper: gamma = {}.\n",
        BINS_PER_DECADE,
        crate::reproduce::paper::GAMMA
    );
    let _ = writeln!(
        s,
        "| key | window | gamma of the mean [95 %] | member gammas (mean +- sd) |"
    );
    let _ = writeln!(s, "|---|---|---|---|");
    for k in &study.containers {
        let mg: Vec<f64> = k.member_gamma.iter().flatten().copied().collect();
        let m = if mg.len() >= 2 {
            let (m, sd) = mean_sd(&mg);
            format!("{m:.3} +- {sd:.3}")
        } else {
            f3(mg.first().copied())
        };
        let _ = writeln!(
            s,
            "| {} | [{}, {}] | {} | {} |",
            k.key,
            k.fit.t_lo,
            k.fit.t_hi,
            est_text(k.fit.est),
            m
        );
    }
}

fn gamma_per_decade(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## gamma per decade of time\n");
    let _ = writeln!(s, "| key | window | gamma [95 %] |");
    let _ = writeln!(s, "|---|---|---|");
    for k in &study.containers {
        for d in &k.decades {
            let _ = writeln!(
                s,
                "| {} | [{}, {}] | {} |",
                k.key,
                d.t_lo,
                d.t_hi,
                est_text(d.est)
            );
        }
    }
}

fn local_slope(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## Local slope\n");
    let _ = writeln!(
        s,
        "d ln E_R / d ln t of the ensemble mean from its peak on ({SLOPE_BINS_PER_DECADE} log \
         bins per decade, least squares over +-{SLOPE_HALF_WIDTH} bins; slope.csv, slope.svg). \
         A power law is a flat stretch. Longest stretch within +-{SLOPE_TOLERANCE} of a \
         constant:\n"
    );
    let _ = writeln!(
        s,
        "| key | from t | to t | decades | constant slope | slope at the end [95 %] |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for k in &study.containers {
        let end = k.slope.last().map_or("n/a".into(), |e| {
            if e.se.is_finite() {
                format!("{:.3} [{:.3}, {:.3}]", e.slope, e.ci_lo, e.ci_hi)
            } else {
                format!("{:.3}", e.slope)
            }
        });
        let _ = match k.constant {
            Some((a, b, c)) => writeln!(
                s,
                "| {} | {:.0} | {:.0} | {:.2} | {:.3} | {} |",
                k.key,
                a,
                b,
                (b / a).log10(),
                c,
                end
            ),
            None => writeln!(s, "| {} | n/a | n/a | n/a | n/a | {} |", k.key, end),
        };
    }
}

fn slope_at_levels(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## Local slope at equal E_R\n");
    let _ = writeln!(
        s,
        "The local slope where the ensemble mean first falls to each level (fraction of E0): \
         equal E_R rather than equal time, so a time rescaling between containers drops out. \
         Under one universal power law these are all -gamma.\n"
    );
    let levels = study.containers[0].level_slopes.iter().map(|x| x.0);
    table_head(s, "key", levels.map(|l| format!("{} %", 100.0 * l)));
    for k in &study.containers {
        let mut line = format!("| {} |", k.key);
        for (_, v) in &k.level_slopes {
            let _ = write!(
                line,
                " {} |",
                v.map_or("not reached".into(), |v| format!("{v:.3}"))
            );
        }
        let _ = writeln!(s, "{line}");
    }
}

fn alpha_by_level(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## alpha by level\n");
    let _ = writeln!(
        s,
        "alpha = t_ref / t_key at which the ensemble means first fall to a level (fraction \
         of E0) after their peaks, reference `{}`; so that E_key(t) = E_ref(alpha t). \
         Collapse: the alpha of `reproduce` (least RMS mismatch of ln E of the mean curves \
         from the leak onset). Paper: (c) 2, (d) 0.22, (e) 9.\n",
        study.reference.as_deref().unwrap_or("")
    );
    let mut levels: Vec<f64> = Vec::new();
    for a in &study.alpha {
        if !levels.contains(&a.level) {
            levels.push(a.level);
        }
    }
    let columns = levels.iter().map(|l| format!("{} %", 100.0 * l));
    table_head(s, "key", columns.chain(["collapse".to_string()]));
    for (key, col) in &study.collapse {
        let mut line = format!("| {key} |");
        for l in &levels {
            let a = study.alpha.iter().find(|a| &a.key == key && a.level == *l);
            let cell = match a {
                Some(a) if a.alpha.is_some() && a.ci_lo.is_finite() => format!(
                    "{:.3} [{:.3}, {:.3}]",
                    a.alpha.unwrap_or(f64::NAN),
                    a.ci_lo,
                    a.ci_hi
                ),
                Some(a) if a.alpha.is_some() => format!("{:.3}", a.alpha.unwrap_or(f64::NAN)),
                _ => "not reached".into(),
            };
            let _ = write!(line, " {cell} |");
        }
        let _ = write!(line, " {} |", f3(col.map(|c| c.alpha)));
        let _ = writeln!(s, "{line}");
    }
}

fn budget(s: &mut String, study: &Study) {
    let _ = writeln!(s, "\n## Energy budget at the end of the run\n");
    let _ = writeln!(
        s,
        "Mean fraction of the incident energy per region at the last snapshot (budget.csv, \
         budget-<key>.svg). Potential energy of a contact is split between its grains.\n"
    );
    for k in &study.containers {
        let parts: Vec<String> = k
            .regions
            .iter()
            .enumerate()
            .map(|(r, n)| format!("{n} {:.4}", k.budget[r].last().copied().unwrap_or(f64::NAN)))
            .collect();
        let _ = writeln!(s, "- ({}) {}", k.key, parts.join(", "));
    }
}

/// The wall layout of a random container as a number (0 none, 1 ends, 2 ends and middle).
fn walls_code(k: &KeyResult) -> f64 {
    k.design.as_ref().map_or(f64::NAN, |d| match d.walls {
        super::sweep::Walls::None => 0.0,
        super::sweep::Walls::Ends => 1.0,
        super::sweep::Walls::EndsAndMiddle => 2.0,
    })
}

/// Mean of the finite values (NaN if none).
fn finite_mean(x: impl Iterator<Item = f64>) -> f64 {
    let w: Vec<f64> = x.filter(|x| x.is_finite()).collect();
    if w.is_empty() {
        f64::NAN
    } else {
        w.iter().sum::<f64>() / w.len() as f64
    }
}

fn random_containers(s: &mut String, study: &Study) {
    let g: Vec<(&KeyResult, f64)> = study
        .random
        .iter()
        .filter_map(|k| k.fit.est.map(|e| (k, e.value)))
        .collect();
    let _ = writeln!(s, "\n## Random containers\n");
    if g.len() >= 2 {
        random_gamma(s, study, &g);
    }
    random_end_slope(s, study);
    random_level_slopes(s, study);
    let failed = study.random.len() - g.len();
    if failed > 0 {
        let _ = writeln!(
            s,
            "\n{failed} random containers gave no fit (see fits.csv)."
        );
    }
}

/// The distribution of gamma over random containers and its correlation with the design.
fn random_gamma(s: &mut String, study: &Study, g: &[(&KeyResult, f64)]) {
    let gs: Vec<f64> = g.iter().map(|x| x.1).collect();
    let (m, sd) = mean_sd(&gs);
    let mut sorted = gs.clone();
    sorted.sort_by(f64::total_cmp);
    let half_widths = study
        .random
        .iter()
        .filter_map(|k| k.fit.est)
        .map(|e| 0.5 * (e.ci_hi - e.ci_lo));
    let _ = writeln!(
        s,
        "{} containers (random.csv, gamma_hist.svg); gamma of each ensemble mean over \
         [N/10, N]: mean {:.3}, standard deviation {:.3}, median {:.3}, range [{:.3}, \
         {:.3}]. The mean of the per-container jackknife half-widths is {:.3}: a spread \
         of gamma well above it is a property of the designs, not noise.\n",
        gs.len(),
        m,
        sd,
        ensemble::quantile(&gs, 0.5),
        sorted[0],
        sorted[sorted.len() - 1],
        finite_mean(half_widths)
    );
    let _ = writeln!(
        s,
        "Correlation of gamma with the design (Pearson r over containers):\n"
    );
    let _ = writeln!(s, "| design parameter | r |");
    let _ = writeln!(s, "|---|---|");
    let param = |f: &dyn Fn(&Design) -> f64| -> Vec<f64> {
        g.iter()
            .map(|(k, _)| k.design.as_ref().map_or(f64::NAN, f))
            .collect()
    };
    let walls: Vec<f64> = g.iter().map(|(k, _)| walls_code(k)).collect();
    for (name, x) in [
        ("interior sections", param(&|d| d.sections as f64)),
        ("grains", param(&|d| d.grains as f64)),
        ("ln(mass ratio)", param(&|d| d.mass_ratio.ln())),
        ("fraction p = 1", param(&|d| d.frac_p1)),
        ("fraction p = 1.5", param(&|d| d.frac_p15)),
        ("fraction p = 2", param(&|d| d.frac_p2)),
        ("walls (0 none, 1 ends, 2 ends and middle)", walls),
    ] {
        let _ = writeln!(s, "| {name} | {:.2} |", ensemble::pearson(&x, &gs));
    }
    let n = gs.len() as f64;
    let r_crit = if n > 2.0 {
        let t = student_t_975(n - 2.0);
        t / (n - 2.0 + t * t).sqrt()
    } else {
        f64::NAN
    };
    let _ = writeln!(
        s,
        "\nWith {} containers, |r| above about {:.2} is unlikely by chance (two-sided 5 %, \
         r = t / sqrt(n - 2 + t^2)).",
        gs.len(),
        r_crit
    );
}

/// The local slope at the end of the random containers' runs.
fn random_end_slope(s: &mut String, study: &Study) {
    let ends: Vec<(f64, f64)> = study
        .random
        .iter()
        .filter_map(|k| k.slope.last().map(|e| (e.slope, 0.5 * (e.ci_hi - e.ci_lo))))
        .collect();
    if ends.len() < 2 {
        return;
    }
    let v: Vec<f64> = ends.iter().map(|e| e.0).collect();
    let (m, sd) = mean_sd(&v);
    let _ = writeln!(
        s,
        "\nLocal slope at the end of the runs (the last slope point, t near N): mean \
         {:.3}, standard deviation {:.3} over {} containers, range [{:.3}, {:.3}]; mean \
         jackknife half-width {:.3}.",
        m,
        sd,
        v.len(),
        v.iter().copied().fold(f64::INFINITY, f64::min),
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        finite_mean(ends.iter().map(|e| e.1))
    );
}

/// The local slope of the random containers at equal E_R levels, against the wall layout.
fn random_level_slopes(s: &mut String, study: &Study) {
    let levels: Vec<f64> = study
        .random
        .first()
        .map(|k| k.level_slopes.iter().map(|x| x.0).collect())
        .unwrap_or_default();
    for (j, &level) in levels.iter().enumerate() {
        let xs: Vec<(&KeyResult, f64)> = study
            .random
            .iter()
            .filter_map(|k| k.level_slopes.get(j).and_then(|x| x.1).map(|v| (k, v)))
            .collect();
        if xs.len() < 3 {
            continue;
        }
        let vals: Vec<f64> = xs.iter().map(|x| x.1).collect();
        let (m, sd) = mean_sd(&vals);
        let walls: Vec<f64> = xs.iter().map(|(k, _)| walls_code(k)).collect();
        let _ = writeln!(
            s,
            "\nLocal slope where the mean first falls to {} % of E0 (equal E_R instead of \
             equal time, which takes the time scale alpha out): {} containers reach it; \
             mean {:.3}, standard deviation {:.3}; correlation with the wall layout r = \
             {:.2}.",
            100.0 * level,
            xs.len(),
            m,
            sd,
            ensemble::pearson(&walls, &vals)
        );
    }
}
