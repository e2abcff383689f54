//! The paper's mechanism over an ensemble (sweep key `mechanism`): from the members' reflections
//! and pulse speeds ([`crate::batch::mechanism`]), per container and time bin (t in snapshots):
//!
//! - `N_r`: reflections per unit time, weighted by energy, `sum of incident / sum of E_R dt`
//!   (summed over members): for one wave it is its hits per unit time, for many it is their
//!   energy-weighted mean, which is what `dE_R/dt = -N_r f E_R` needs;
//! - `f`: the leak fraction per reflection, `sum of transmitted / sum of incident`;
//! - the raw count of reflections per member per unit time, the energy that came in, the mean
//!   speed of the pulses inside;
//! - the paper's model, `dE_R/dt = -N_r(t) f E_R` with `f` constant (its mean over the model's
//!   span), integrated bin by bin from the first bin edge after the mean curve's peak; beside it
//!   the same with the measured `f(t)`, which is the energy balance of the reflections alone
//!   (it misses only the energy that came in);
//! - per decade, the power-law exponent of `N_r`, of the raw count, of `f` and of the speed, each
//!   as the mean of the members' own least-squares exponents with a 95 % Student-t interval;
//!   the model's `E_R` over the simulation's at the decade's end;
//! - the leak law: `f` against the incident energy over the member's initial energy (pooled
//!   amplitude bins with at least [`MIN_HITS`] reflections), fitted as a power law;
//! - the back-pressure: over the late window of the gauges, each member's face force against its
//!   `N_r`, `f` and speed (Pearson's r over every member of every container).

use crate::batch::mechanism::{amplitude_edge, AmplitudeBin, MemberMechanism, TimeBin};
use crate::batch::Member;
use grainchain_engine::analysis::ensemble::pearson;
use grainchain_engine::analysis::statistics::mean_sd;
use grainchain_engine::analysis::{fit_power_law, student_t_975, LogPoint, PowerFit};

/// Fewest reflections in a pooled amplitude bin of the leak law.
pub const MIN_HITS: u64 = 20;

/// One time bin of a container.
#[derive(Clone, Debug)]
pub struct MechanismRow {
    /// First and last output of the bin (`[lo, hi)`).
    pub lo: u64,
    /// Upper edge.
    pub hi: u64,
    /// Reflections per member per snapshot.
    pub count_rate: f64,
    /// `N_r`, per snapshot.
    pub nr: f64,
    /// `f`.
    pub f: f64,
    /// Energy that came in over the bin per member, over the mean initial energy.
    pub inflow: f64,
    /// Mean speed of the pulses inside, grains per snapshot (energy-weighted).
    pub speed: f64,
    /// The simulation's mean `E_R / E0` at the bin's upper edge.
    pub e_sim: f64,
    /// The paper's model (constant `f`) at the upper edge (NaN before the model starts).
    pub e_paper: f64,
    /// The model with the measured `f(t)`.
    pub e_measured: f64,
    /// The balance: the measured-`f` model plus the energy that came in, bin by bin (the
    /// reflections' and inflow's bookkeeping, which must give the simulation back).
    pub e_balance: f64,
}

/// A power-law exponent over members with its 95 % interval.
#[derive(Clone, Copy, Debug)]
pub struct Exponent {
    /// Mean of the members' exponents.
    pub value: f64,
    /// Lower end of the 95 % interval (Student t, members - 1 degrees of freedom).
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Members with an exponent.
    pub n: usize,
}

/// One decade of a container.
#[derive(Clone, Debug)]
pub struct DecadeRow {
    /// The decade `[from, to]`, in snapshots.
    pub from: u64,
    /// Its end.
    pub to: u64,
    /// Exponent of `N_r`, of the raw count, of `f` and of the speed.
    pub nr: Option<Exponent>,
    /// Of the raw count.
    pub count: Option<Exponent>,
    /// Of `f`.
    pub f: Option<Exponent>,
    /// Of the speed.
    pub speed: Option<Exponent>,
    /// Of the leak rate `N_r f` (transmitted over the time integral of `E_R`): -1 for a power
    /// law of `E_R`.
    pub rate: Option<Exponent>,
    /// The energy that came in over the energy the reflections sent out (pooled).
    pub inflow_share: f64,
    /// The paper's model's `E_R` over the simulation's at the decade's end.
    pub ratio_paper: f64,
    /// The measured-`f` model's.
    pub ratio_measured: f64,
    /// The balance's (the measured-`f` model plus the energy that came in).
    pub ratio_balance: f64,
}

/// One amplitude bin of the leak law.
#[derive(Clone, Debug)]
pub struct LeakRow {
    /// Lower edge of the incident energy over the initial energy.
    pub lo: f64,
    /// Upper edge.
    pub hi: f64,
    /// Pooled sums.
    pub sums: AmplitudeBin,
}

/// The mechanism of one container.
#[derive(Clone, Debug)]
pub struct Mechanism {
    /// The container's key.
    pub key: String,
    /// Members.
    pub members: usize,
    /// Where the models start (an output).
    pub start: u64,
    /// The constant `f` of the paper's model (over the model's span).
    pub f_mean: f64,
    /// Per time bin.
    pub rows: Vec<MechanismRow>,
    /// Per decade from the model's start.
    pub decades: Vec<DecadeRow>,
    /// The leak law's bins.
    pub leak: Vec<LeakRow>,
    /// `f = A a^b` over the bins with enough reflections: `b` is `-gamma` of the fit.
    pub leak_law: Option<PowerFit>,
    /// Over the gauges' late window, per member: face force (mean of the two faces), `N_r`,
    /// `f`, speed, and the energy that came in over the energy sent out.
    pub late: Vec<[f64; 5]>,
}

/// What the mechanism needs of a container's other results.
#[derive(Clone, Debug)]
pub struct KeyInput<'a> {
    /// The container's key.
    pub key: &'a str,
    /// The mean over members of `E_R / E0` at every snapshot.
    pub mean: Vec<f64>,
    /// The gauges' late window (first and last snapshot) and each member's mean face force
    /// over it (the two faces' mean), when the members have gauges.
    pub late: Option<((usize, usize), Vec<f64>)>,
}

/// The mechanism of every container whose members counted it.
pub fn analyse(keys: &[KeyInput<'_>], members: &[Member]) -> Vec<Mechanism> {
    let mut out = Vec::new();
    for k in keys {
        let ms: Vec<(&Member, &MemberMechanism)> = members
            .iter()
            .filter(|m| m.key == k.key)
            .filter_map(|m| Some((m, m.meta.mechanism.as_ref()?)))
            .collect();
        if ms.is_empty() {
            continue;
        }
        out.push(of_key(k, &ms));
    }
    out
}

/// Sum of a member's container energy over outputs `[lo, hi)`.
fn energy_sum(m: &Member, lo: u64, hi: u64) -> f64 {
    let e = &m.energy[0];
    let hi = (hi as usize).min(e.len());
    e[(lo as usize).min(hi)..hi].iter().sum()
}

fn of_key(k: &KeyInput<'_>, ms: &[(&Member, &MemberMechanism)]) -> Mechanism {
    let edges = ms[0].1.edges.clone();
    let bins = edges.len().saturating_sub(1);
    let n = ms.len() as f64;
    let e0 = ms.iter().map(|(m, _)| m.meta.initial_energy).sum::<f64>() / n;
    let mean = &k.mean;
    let peak = mean
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map_or(0, |(i, _)| i as u64);
    let start = edges.iter().copied().find(|&e| e >= peak).unwrap_or(0);
    let sum = |b: usize, f: &dyn Fn(&TimeBin) -> f64| -> f64 {
        ms.iter().map(|(_, x)| x.time.get(b).map_or(0.0, f)).sum()
    };
    let es = |b: usize| -> f64 {
        ms.iter()
            .map(|(m, _)| energy_sum(m, edges[b], edges[b + 1]))
            .sum()
    };
    // The constant f of the paper's model: over the model's span.
    let span: Vec<usize> = (0..bins).filter(|&b| edges[b] >= start).collect();
    let f_mean = span
        .iter()
        .map(|&b| sum(b, &|t| t.transmitted))
        .sum::<f64>()
        / span.iter().map(|&b| sum(b, &|t| t.incident)).sum::<f64>();
    let at = |t: u64| mean.get(t as usize).copied().unwrap_or(f64::NAN);
    let (mut paper, mut measured, mut balance) = (f64::NAN, f64::NAN, f64::NAN);
    let mut rows = Vec::with_capacity(bins);
    for b in 0..bins {
        let (lo, hi) = (edges[b], edges[b + 1]);
        let (inc, tr, e) = (sum(b, &|t| t.incident), sum(b, &|t| t.transmitted), es(b));
        let nr = inc / e;
        let f = tr / inc;
        if lo == start {
            paper = at(lo);
            measured = at(lo);
            balance = at(lo);
        }
        if lo >= start {
            let dt = (hi - lo) as f64;
            paper *= (-nr * f_mean * dt).exp();
            measured *= (-(tr / e) * dt).exp();
            balance += (sum(b, &|t| t.inflow) - tr) / n / e0;
        }
        rows.push(MechanismRow {
            lo,
            hi,
            count_rate: sum(b, &|t| t.hits as f64) / (n * (hi - lo) as f64),
            nr,
            f,
            inflow: sum(b, &|t| t.inflow) / n / e0,
            speed: sum(b, &|t| t.speed_weighted) / sum(b, &|t| t.speed_weight),
            e_sim: at(hi),
            e_paper: if lo >= start { paper } else { f64::NAN },
            e_measured: if lo >= start { measured } else { f64::NAN },
            e_balance: if lo >= start { balance } else { f64::NAN },
        });
    }
    // Decades from the model's start: five time bins each (the bins are a fifth of a decade).
    let per = crate::batch::mechanism::TIME_BINS_PER_DECADE as usize;
    let mut decades = Vec::new();
    let mut i = edges.iter().position(|&e| e == start).unwrap_or(0);
    while i + 1 < edges.len() {
        let j = (i + per).min(edges.len() - 1);
        let (from, to) = (edges[i].max(1), edges[j]);
        // A last, shorter decade only if it spans at least 0.3 of one (as the study's gamma).
        if ((to as f64) / (from as f64)).log10() < 0.3 {
            break;
        }
        let inside: Vec<usize> = (i..j).collect();
        let exponent = |value: &dyn Fn(&Member, &TimeBin, usize) -> f64| {
            member_exponent(ms, &edges, &inside, value)
        };
        let end = &rows[j - 1];
        decades.push(DecadeRow {
            from,
            to,
            nr: exponent(&|m, t, b| t.incident / energy_sum(m, edges[b], edges[b + 1])),
            count: exponent(&|_, t, b| t.hits as f64 / (edges[b + 1] - edges[b]) as f64),
            f: exponent(&|_, t, _| t.transmitted / t.incident),
            speed: exponent(&|_, t, _| t.speed_weighted / t.speed_weight),
            rate: exponent(&|m, t, b| t.transmitted / energy_sum(m, edges[b], edges[b + 1])),
            inflow_share: inside.iter().map(|&b| sum(b, &|t| t.inflow)).sum::<f64>()
                / inside
                    .iter()
                    .map(|&b| sum(b, &|t| t.transmitted))
                    .sum::<f64>(),
            ratio_paper: end.e_paper / end.e_sim,
            ratio_measured: end.e_measured / end.e_sim,
            ratio_balance: end.e_balance / end.e_sim,
        });
        i = j;
    }
    // The leak law.
    let amp = ms[0].1.amplitude.len();
    let leak: Vec<LeakRow> = (0..amp)
        .map(|j| {
            let mut s = AmplitudeBin::default();
            for (_, x) in ms {
                if let Some(a) = x.amplitude.get(j) {
                    s.hits += a.hits;
                    s.incident += a.incident;
                    s.transmitted += a.transmitted;
                }
            }
            LeakRow {
                lo: amplitude_edge(j),
                hi: amplitude_edge(j + 1),
                sums: s,
            }
        })
        .filter(|r| r.sums.hits > 0)
        .collect();
    let points: Vec<LogPoint> = leak
        .iter()
        .filter(|r| r.sums.hits >= MIN_HITS && r.sums.transmitted > 0.0)
        .map(|r| LogPoint {
            ln_t: (r.lo * r.hi).sqrt().ln(),
            ln_e: (r.sums.transmitted / r.sums.incident).ln(),
            count: r.sums.hits as usize,
        })
        .collect();
    let leak_law = fit_power_law(&points);
    // Late window: the gauges'.
    let late = match &k.late {
        Some((window, forces)) => {
            let (lo, hi) = (window.0 as u64, window.1 as u64);
            let inside: Vec<usize> = (0..bins)
                .filter(|&b| edges[b] >= lo && edges[b + 1] <= hi + 1)
                .collect();
            ms.iter()
                .enumerate()
                .map(|(i, (m, x))| {
                    let s = |f: &dyn Fn(&TimeBin) -> f64| -> f64 {
                        inside.iter().map(|&b| f(&x.time[b])).sum()
                    };
                    let e: f64 = inside
                        .iter()
                        .map(|&b| energy_sum(m, edges[b], edges[b + 1]))
                        .sum();
                    [
                        forces[i],
                        s(&|t| t.incident) / e,
                        s(&|t| t.transmitted) / s(&|t| t.incident),
                        s(&|t| t.speed_weighted) / s(&|t| t.speed_weight),
                        s(&|t| t.inflow) / s(&|t| t.transmitted),
                    ]
                })
                .collect()
        }
        None => Vec::new(),
    };
    Mechanism {
        key: k.key.to_string(),
        members: ms.len(),
        start,
        f_mean,
        rows,
        decades,
        leak,
        leak_law,
        late,
    }
}

/// The mean over members of each member's least-squares exponent of `value` against `t` (the
/// bins' geometric middles) over the bins `inside`, with its 95 % interval; bins with a value
/// that is not positive and finite are left out, members with fewer than 3 bins too.
fn member_exponent(
    ms: &[(&Member, &MemberMechanism)],
    edges: &[u64],
    inside: &[usize],
    value: &dyn Fn(&Member, &TimeBin, usize) -> f64,
) -> Option<Exponent> {
    let slopes: Vec<f64> = ms
        .iter()
        .filter_map(|(m, x)| {
            let pts: Vec<(f64, f64)> = inside
                .iter()
                .filter_map(|&b| {
                    let y = value(m, &x.time[b], b);
                    let t = ((edges[b] * edges[b + 1]) as f64).sqrt();
                    (y > 0.0 && y.is_finite()).then(|| (t.ln(), y.ln()))
                })
                .collect();
            slope(&pts)
        })
        .collect();
    let n = slopes.len();
    if n < 2 {
        return None;
    }
    let (mean, sd) = mean_sd(&slopes);
    let q = student_t_975((n - 1) as f64) * sd / (n as f64).sqrt();
    Some(Exponent {
        value: mean,
        lo: mean - q,
        hi: mean + q,
        n,
    })
}

/// Least-squares slope of `y` against `x` (at least 3 points).
fn slope(p: &[(f64, f64)]) -> Option<f64> {
    if p.len() < 3 {
        return None;
    }
    let n = p.len() as f64;
    let (mx, my) = (
        p.iter().map(|q| q.0).sum::<f64>() / n,
        p.iter().map(|q| q.1).sum::<f64>() / n,
    );
    let sxx: f64 = p.iter().map(|q| (q.0 - mx).powi(2)).sum();
    let sxy: f64 = p.iter().map(|q| (q.0 - mx) * (q.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Pearson's r of the face force against `N_r`, `f`, the speed and the inflow share over every
/// member of every container (late window), and the number of members.
pub fn back_pressure(all: &[Mechanism]) -> Option<([f64; 4], usize)> {
    let late: Vec<&[f64; 5]> = all
        .iter()
        .flat_map(|m| &m.late)
        .filter(|x| x.iter().all(|v| v.is_finite()))
        .collect();
    if late.len() < 3 {
        return None;
    }
    let force: Vec<f64> = late.iter().map(|x| x[0]).collect();
    let r = |i: usize| pearson(&force, &late.iter().map(|x| x[i]).collect::<Vec<f64>>());
    Some(([r(1), r(2), r(3), r(4)], late.len()))
}

/// `mechanism.csv`, `leak.csv` and the four figures into `out`.
pub fn write(all: &[Mechanism], out: &std::path::Path) -> Result<(), crate::error::Error> {
    use crate::report::atomic::csv_file;
    use crate::report::csv_number as num;
    csv_file(
        &out.join("mechanism.csv"),
        "key,t_lo,t_hi,reflections_per_snapshot,n_r,f,inflow,speed,e_sim,e_model_paper,e_model_measured_f,e_balance",
        all.iter().flat_map(|m| {
            m.rows.iter().map(move |r| {
                format!(
                    "{},{},{},{},{},{},{},{},{},{},{},{}",
                    m.key,
                    r.lo,
                    r.hi,
                    num(r.count_rate),
                    num(r.nr),
                    num(r.f),
                    num(r.inflow),
                    num(r.speed),
                    num(r.e_sim),
                    num(r.e_paper),
                    num(r.e_measured),
                    num(r.e_balance)
                )
            })
        }),
    )?;
    csv_file(
        &out.join("leak.csv"),
        "key,amplitude_lo,amplitude_hi,reflections,incident,transmitted,f",
        all.iter().flat_map(|m| {
            m.leak.iter().map(move |r| {
                format!(
                    "{},{},{},{},{},{},{}",
                    m.key,
                    num(r.lo),
                    num(r.hi),
                    r.sums.hits,
                    num(r.sums.incident),
                    num(r.sums.transmitted),
                    num(r.sums.transmitted / r.sums.incident)
                )
            })
        }),
    )?;
    plots(all, out)
}

fn mid(r: &MechanismRow) -> f64 {
    ((r.lo * r.hi) as f64).sqrt()
}

/// The outer medium of a key (`long` of `a-long`; empty for a key without one).
fn medium_of(key: &str) -> &str {
    key.split_once('-').map_or("", |(_, m)| m)
}

/// The figures, one set per outer medium (`mechanism_nr-<medium>.svg`, ...) when the keys
/// name several (`<container>-<medium>`), else one set: five to ten curves read at a glance,
/// twenty do not.
fn plots(all: &[Mechanism], out: &std::path::Path) -> Result<(), crate::error::Error> {
    let mut media: Vec<&str> = all.iter().map(|m| medium_of(&m.key)).collect();
    media.sort();
    media.dedup();
    if media.len() < 2 {
        return plots_of(&all.iter().collect::<Vec<_>>(), "", "", out);
    }
    for medium in media {
        let of: Vec<&Mechanism> = all.iter().filter(|m| medium_of(&m.key) == medium).collect();
        plots_of(&of, &format!("-{medium}"), &format!(" ({medium})"), out)?;
    }
    Ok(())
}

fn plots_of(
    all: &[&Mechanism],
    suffix: &str,
    words: &str,
    out: &std::path::Path,
) -> Result<(), crate::error::Error> {
    use crate::report::plot::{LineChart, Scale, Series};
    let line = |name: &str, points: Vec<(f64, f64)>| Series {
        name: name.to_string(),
        points,
        markers: true,
        ..Default::default()
    };
    // N_r against t with the 1/t line through the first container's N_r at t = 100.
    let mut series: Vec<Series> = all
        .iter()
        .map(|m| {
            line(
                &m.key,
                m.rows
                    .iter()
                    .filter(|r| r.lo >= m.start)
                    .map(|r| (mid(r), r.nr))
                    .collect(),
            )
        })
        .collect();
    // The 1/t line over the first container's span, through its first point.
    let finite: Vec<(f64, f64)> = series.first().map_or_else(Vec::new, |s| {
        s.points
            .iter()
            .copied()
            .filter(|p| p.1 > 0.0 && p.1.is_finite())
            .collect()
    });
    if let Some(&(t0, y0)) = finite.first() {
        let c = y0 * t0;
        series.push(Series {
            name: "1/t (the paper)".into(),
            // A point at every bin, so that the part inside the frame is drawn.
            points: finite.iter().map(|p| (p.0, c / p.0)).collect(),
            reference: true,
            dashed: true,
            ..Default::default()
        });
    }
    LineChart {
        title: &format!(
            "reflections per unit time N_r (energy-weighted), from the peak of E_R{words}"
        ),
        x_label: "t (snapshots)",
        y_label: "N_r (per snapshot)",
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        series,
        ..Default::default()
    }
    .write(out.join(format!("mechanism_nr{suffix}.svg")))?;
    LineChart {
        title: &format!("mean speed of the pulses inside the container (energy-weighted){words}"),
        x_label: "t (snapshots)",
        y_label: "speed (grains per snapshot)",
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        series: all
            .iter()
            .map(|m| line(&m.key, m.rows.iter().map(|r| (mid(r), r.speed)).collect()))
            .collect(),
        ..Default::default()
    }
    .write(out.join(format!("mechanism_speed{suffix}.svg")))?;
    LineChart {
        title: &format!("leak fraction per reflection against the incident energy{words}"),
        x_label: "incident energy / initial energy",
        y_label: "f (transmitted / incident)",
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        series: all
            .iter()
            .map(|m| {
                line(
                    &m.key,
                    m.leak
                        .iter()
                        .filter(|r| r.sums.hits >= MIN_HITS)
                        .map(|r| ((r.lo * r.hi).sqrt(), r.sums.transmitted / r.sums.incident))
                        .collect(),
                )
            })
            .collect(),
        ..Default::default()
    }
    .write(out.join(format!("mechanism_leak{suffix}.svg")))?;
    let mut series = Vec::new();
    for m in all {
        let from: Vec<&MechanismRow> = m.rows.iter().filter(|r| r.lo >= m.start).collect();
        series.push(Series {
            name: format!("{} simulated", m.key),
            points: from.iter().map(|r| (r.hi as f64, r.e_sim)).collect(),
            ..Default::default()
        });
        series.push(Series {
            name: String::new(),
            points: from.iter().map(|r| (r.hi as f64, r.e_paper)).collect(),
            dashed: true,
            same_color: true,
            ..Default::default()
        });
    }
    LineChart {
        title: &format!(
            "E_R / E0: simulated (solid), the paper's model with constant f (dashed){words}"
        ),
        x_label: "t (snapshots)",
        y_label: "E_R / E0",
        x_scale: Scale::Log,
        y_scale: Scale::Log,
        series,
        ..Default::default()
    }
    .write(out.join(format!("mechanism_model{suffix}.svg")))
}

/// An exponent as `value [lo, hi]`, or a dash.
fn exp_text(e: Option<Exponent>) -> String {
    e.map_or("–".into(), |e| {
        format!("{:.2} [{:.2}, {:.2}]", e.value, e.lo, e.hi)
    })
}

/// STUDY.md's section "The paper's mechanism".
pub fn section(all: &[Mechanism]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n## The paper's mechanism\n\nHong (2005) explains the power law so: energy leaks when a \
         solitary wave is partly transmitted at a container wall, each reflection slows the \
         wave, so the reflections per unit time fall as `<N_r(t)> ~ 1/t`, and \
         `dE_R/dt ~ -<N_r(t)> E_R` gives `t^-gamma`. Measured here at the container's two edges \
         after every step (the counting rule: `engine/src/integrators/reflections.rs`; the bins: \
         `src/batch/mechanism.rs`; this section: `src/study/outputs/mechanism.rs`). `N_r` is \
         energy-weighted (sum of incident energies over the time integral of `E_R`: one wave's \
         hits per unit time, the energy-weighted mean of many), `f` = transmitted / incident, t \
         in snapshots from the strike; each exponent is the mean of the members' own \
         least-squares exponents over the decade's time bins with its 95 % Student-t interval. \
         The paper's model integrates `dE_R/dt = -N_r(t) f E_R` with `f` constant (its mean from \
         the peak of `E_R` on) from the first bin edge after that peak; the model with the \
         measured `f(t)` is the reflections' energy balance (it misses only energy that came \
         in).\n"
    );
    let _ = writeln!(s, "### Exponents per decade\n");
    let _ = writeln!(
        s,
        "| key | decade (snapshots) | N_r | reflections counted | f | leak rate N_r f | speed | in / out | E_R model / simulated: constant f | measured f(t) | balance |\n|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for m in all {
        for d in &m.decades {
            let _ = writeln!(
                s,
                "| {} | {}–{} | {} | {} | {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} |",
                m.key,
                d.from,
                d.to,
                exp_text(d.nr),
                exp_text(d.count),
                exp_text(d.f),
                exp_text(d.rate),
                exp_text(d.speed),
                d.inflow_share,
                d.ratio_paper,
                d.ratio_measured,
                d.ratio_balance
            );
        }
    }
    let worst = all
        .iter()
        .flat_map(|m| &m.rows)
        .filter(|r| r.e_balance.is_finite())
        .map(|r| (r.e_balance - r.e_sim).abs())
        .fold(0.0, f64::max);
    let _ = writeln!(
        s,
        "\nThe balance is within {worst:.1e} of `E0` of the simulated mean `E_R / E0` at every bin \
         edge of every container (the work through an edge is summed with the trapezoid rule, \
         second order in the step): a ratio in the last column far from 1 is a small `E_R`, \
         not missing energy."
    );
    let decades: Vec<&DecadeRow> = all.iter().flat_map(|m| &m.decades).collect();
    let holds = |e: Option<Exponent>, x: f64| e.is_some_and(|e| e.lo <= x && x <= e.hi);
    let _ = writeln!(
        s,
        "\nOf {} container-decades, the 95 % interval of `N_r`'s exponent holds -1 in {}, that \
         of `f`'s holds 0 in {}, that of the leak rate's holds -1 in {}.",
        decades.len(),
        decades.iter().filter(|d| holds(d.nr, -1.0)).count(),
        decades.iter().filter(|d| holds(d.f, 0.0)).count(),
        decades.iter().filter(|d| holds(d.rate, -1.0)).count()
    );
    let _ = writeln!(
        s,
        "\nUnder the paper's mechanism the exponent of `N_r` is -1 and that of `f` is 0; a power \
         law of `E_R` needs the leak rate's to be -1 (`in / out`: the energy that came back in \
         over the energy the reflections sent out, which both models leave out; the balance adds it \
         back, a check that the reflections and the inflow account for every change of \
         `E_R`). Figures (one set per outer medium when the keys name several, \
         `-<medium>`): mechanism_nr.svg (with the 1/t line), mechanism_speed.svg, \
         mechanism_leak.svg, mechanism_model.svg.\n"
    );
    let _ = writeln!(s, "### The leak law\n");
    let _ = writeln!(
        s,
        "`f` against `a` = incident energy / initial energy, pooled over members in bins of a \
         quarter decade with at least {MIN_HITS} reflections, fitted as `f = A a^b` (interval: \
         the fit's, Student t). The least and largest `f` of those bins say whether a power law \
         describes it at all (a U-shaped `f` fits `b` near 0 without being constant).\n"
    );
    let _ = writeln!(
        s,
        "| key | members | constant f | b [95 %] | A | bins | reflections | least f (at a) | largest f (at a) |\n|---|---|---|---|---|---|---|---|---|"
    );
    for m in all {
        let hits: u64 = m.leak.iter().map(|r| r.sums.hits).sum();
        // f at its least and largest over the fitted bins: a U is no power law, whatever b says.
        let fitted: Vec<(f64, f64)> = m
            .leak
            .iter()
            .filter(|r| r.sums.hits >= MIN_HITS)
            .map(|r| ((r.lo * r.hi).sqrt(), r.sums.transmitted / r.sums.incident))
            .collect();
        let least = fitted.iter().cloned().min_by(|a, b| a.1.total_cmp(&b.1));
        let most = fitted.iter().cloned().max_by(|a, b| a.1.total_cmp(&b.1));
        let at =
            |x: Option<(f64, f64)>| x.map_or("–".into(), |(a, f)| format!("{f:.3} ({a:.1e})"));
        let (least, most) = (at(least), at(most));
        match &m.leak_law {
            Some(l) => {
                let _ = writeln!(
                    s,
                    "| {} | {} | {:.4} | {:.3} [{:.3}, {:.3}] | {:.3e} | {} | {hits} | {least} | {most} |",
                    m.key, m.members, m.f_mean, -l.gamma, -l.ci_hi, -l.ci_lo, l.a, l.n
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "| {} | {} | {:.4} | – | – | 0 | {hits} | {least} | {most} |",
                    m.key, m.members, m.f_mean
                );
            }
        }
    }
    let _ = writeln!(s, "\n### The back-pressure\n");
    let _ = writeln!(
        s,
        "Over the gauges' late window (the outer-medium section's), per container the mean over \
         members of the face force (the two faces' mean), `N_r`, `f` and the speed:\n"
    );
    let _ = writeln!(
        s,
        "| key | face force | N_r | f | speed | in / out |\n|---|---|---|---|---|---|"
    );
    for m in all {
        if m.late.is_empty() {
            continue;
        }
        let col = |i: usize| {
            let v: Vec<f64> = m
                .late
                .iter()
                .map(|x| x[i])
                .filter(|x| x.is_finite())
                .collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let _ = writeln!(
            s,
            "| {} | {:.4e} | {:.4e} | {:.4} | {:.3} | {:.3} |",
            m.key,
            col(0),
            col(1),
            col(2),
            col(3),
            col(4)
        );
    }
    if let Some((r, n)) = back_pressure(all) {
        let _ = writeln!(
            s,
            "\nPearson's r of the face force, over {n} members of every container: with `N_r` \
             {:.2}, with `f` {:.2}, with the speed {:.2}, with in / out {:.2}.",
            r[0], r[1], r[2], r[3]
        );
    }
    s
}
