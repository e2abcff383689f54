//! `container-a-statistics`: choosing the container scenes' step from ensemble statistics.
//!
//! Past about snapshot 200 the energy left in container (a), E_R(t), is chaotic (a striker faster
//! by 1e-12 moves it by more than 1e-4, [`super::CONTAINER_HORIZON`]): no step pins the curve
//! down, and what a step's accuracy can still change is the statistics of an ensemble. So every
//! setting runs the same ensemble, members `k = 0..M` with the striker's speed times
//! `1 + k 1e-12` (the perturbation of `grainchain study`, [`TWIN_EPS`]), and is compared with the
//! ensemble of a reference setting (blanes-moan4 at a quarter of the scene's step):
//!
//! - window means: per member the mean of `E_R / E_0` (`E_0` the incident energy) over snapshot
//!   windows `[200,400)`, `[400,1000)`, `[1000,2000)`, `[2000,4000]` ([`windows`]); their mean
//!   over members with its standard error `s / sqrt(M)`;
//! - gamma per decade: the power law fitted to the ensemble-mean `E_R` over snapshots
//!   `[100,1000]` and `[1000,4000]` ([`decades`]) with the decay analysis' log bins
//!   ([`decay::BINS_PER_DECADE`]), its standard error by the delete-one jackknife over members
//!   ([`ensemble::jackknife`]). Like every decay fit of the project ([`decay::fit_window`]) a
//!   window never starts before the leak onset: the first decade starts at the onset of the
//!   reference's ensemble mean (about snapshot 222; before it the wave is still arriving and
//!   `ln E_R` climbs from 1e-18), the same window for every setting;
//! - each against the reference ([`compare`]): error `|mean - ref_mean|`,
//!   `z = error / sqrt(se^2 + ref_se^2)`, and `inside` when the mean lies inside the reference's
//!   95 % interval `ref_mean +- 1.96 ref_se`;
//! - the pre-chaos error of member 0: `container-a`'s error (the largest relative deviation of
//!   E_R from the reference's member 0 over the snapshots up to [`super::CONTAINER_HORIZON`]
//!   where the reference exceeds 1e-3 of the incident energy);
//! - cost: the median wall time of a member's run (set-up included; the members run two at a
//!   time on [`Pool`]) and the median number of grain evaluations per member.
//!
//! Every run has the causal horizon on (`[run] horizon = {}`): exact bit for bit, it only makes
//! the runs cheaper. The verdict is the cheapest setting (wall time per member) whose every
//! window mean and decade gamma is `inside`. Every number but the timings is independent of the
//! thread count: members are independent runs and the pool keeps results in job order.
//!
//! Quick mode: 2 members over 300 snapshots, one window `[150,300]` and one decade
//! `[onset,300]` (a smoke run: the ensemble has barely left the predictable range).

use super::{error_of, median, Config, Outcome};
use crate::batch::scenes::{perturb_striker, set_snapshots, TWIN_EPS};
use crate::batch::Stepping;
use crate::batch::{run_job, Job, Pool, SceneSource};
use crate::error::Error;
use crate::report::plot::{LineChart, Scale, Series};
use crate::report::AtomicFile;
use grainchain_engine::analysis::statistics::{mean, mean_se};
use grainchain_engine::analysis::{decay, ensemble, leak_onset};
use grainchain_engine::file::HorizonFile;
use grainchain_engine::problems::Container;
use grainchain_engine::Method;
use grainchain_engine::Scene;
use serde::Serialize;
use std::path::Path;

/// The problem's name (`--only container-a-statistics`).
pub const NAME: &str = "container-a-statistics";

/// Members of each ensemble (quick mode: [`QUICK_MEMBERS`]).
pub const MEMBERS: usize = 8;
/// Members in quick mode.
pub const QUICK_MEMBERS: usize = 2;
/// Snapshots of each run (quick mode: [`QUICK_SNAPSHOTS`]).
pub const SNAPSHOTS: u64 = 4000;
/// Snapshots in quick mode.
pub const QUICK_SNAPSHOTS: u64 = 300;
/// The scene's step, 160 steps per snapshot.
pub const SCENE_DT: f64 = 7.8125e-4;
/// Grains added on each side of the multirate fast region (as `grainchain study` does).
pub const MULTIRATE_MARGIN: u64 = 20;
/// The two-sided 95 % quantile of the normal distribution: `inside` is
/// `|mean - ref_mean| <= Z95 ref_se`.
pub const Z95: f64 = 1.96;

/// Window means: snapshots `lo..hi`, the window ending at the run's last snapshot including it.
const WINDOWS: [(usize, usize); 4] = [(200, 400), (400, 1000), (1000, 2000), (2000, 4000)];
/// Decades of the gamma fits: snapshots `lo..=hi` (`lo` raised to the leak onset).
const DECADES: [(usize, usize); 2] = [(100, 1000), (1000, 4000)];

/// One integrator setting.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Setting {
    /// Method: blanes-moan4, verlet, or multirate (blanes-moan4 in the fast region).
    pub method: Method,
    /// The (fast region's) step asked for.
    pub dt: f64,
    /// Outer step over `dt` of multirate; 1 for a single-rate method.
    pub ratio: u64,
}

impl Setting {
    const fn single(method: Method, dt: f64) -> Self {
        Setting {
            method,
            dt,
            ratio: 1,
        }
    }

    const fn multirate(dt: f64, ratio: u64) -> Self {
        Setting {
            method: Method::Multirate,
            dt,
            ratio,
        }
    }

    /// `blanes-moan4 dt 7.8125e-4`, `multirate-16 dt 7.8125e-4`.
    pub fn label(&self) -> String {
        if self.ratio > 1 {
            format!("{}-{} dt {:e}", self.method.name(), self.ratio, self.dt)
        } else {
            format!("{} dt {:e}", self.method.name(), self.dt)
        }
    }
}

/// The reference: blanes-moan4 at a quarter of the scene's step.
pub const REFERENCE: Setting = Setting::single(Method::BlanesMoan4, SCENE_DT / 4.0);

/// The candidates, in the order of the outputs.
pub const CANDIDATES: [Setting; 9] = [
    Setting::single(Method::BlanesMoan4, SCENE_DT),
    Setting::single(Method::BlanesMoan4, 2.0 * SCENE_DT),
    Setting::single(Method::BlanesMoan4, 4.0 * SCENE_DT),
    Setting::multirate(SCENE_DT, 8),
    Setting::multirate(SCENE_DT, 16),
    Setting::multirate(SCENE_DT, 32),
    Setting::multirate(2.0 * SCENE_DT, 8),
    Setting::single(Method::Verlet, 2e-4),
    Setting::single(Method::Verlet, 1e-4),
];

/// A snapshot range, both ends included.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Span {
    /// First snapshot.
    pub first: usize,
    /// Last snapshot (included).
    pub last: usize,
}

/// The windows of the means for a run of `n` snapshots, with their names: those of
/// `[200,400)`, `[400,1000)`, `[1000,2000)`, `[2000,4000]` that fit (the one ending at `n`
/// includes it), or `[n/2, n]` when none does (quick mode: `[150,300]`).
pub fn windows(n: usize) -> Vec<(String, Span)> {
    let mut out: Vec<(String, Span)> = WINDOWS
        .iter()
        .filter(|w| w.1 <= n)
        .map(|&(lo, hi)| {
            if hi == n {
                (
                    format!("E_R/E0 [{lo},{hi}]"),
                    Span {
                        first: lo,
                        last: hi,
                    },
                )
            } else {
                (
                    format!("E_R/E0 [{lo},{hi})"),
                    Span {
                        first: lo,
                        last: hi - 1,
                    },
                )
            }
        })
        .collect();
    if out.is_empty() {
        let lo = n / 2;
        out.push((format!("E_R/E0 [{lo},{n}]"), Span { first: lo, last: n }));
    }
    out
}

/// The decades of the gamma fits for a run of `n` snapshots, each starting no earlier than
/// `onset` (the leak onset of the reference's ensemble mean): those of `[100,1000]`,
/// `[1000,4000]` that fit, or `[100, n]` when none does. A decade that the onset swallows whole
/// is kept (its fit is NaN, so it fails).
pub fn decades(n: usize, onset: usize) -> Vec<(String, Span)> {
    let mut spans: Vec<(usize, usize)> = DECADES.iter().copied().filter(|d| d.1 <= n).collect();
    if spans.is_empty() {
        spans.push((100.min(n), n));
    }
    spans
        .into_iter()
        .map(|(lo, hi)| {
            let lo = lo.max(onset);
            (
                format!("gamma [{lo},{hi}]"),
                Span {
                    first: lo,
                    last: hi,
                },
            )
        })
        .collect()
}

/// A statistic of a setting's ensemble against the reference's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// The setting's value (mean over members, or of the mean curve).
    pub mean: f64,
    /// Its standard error over members.
    pub se: f64,
    /// The reference's value.
    pub ref_mean: f64,
    /// The reference's standard error.
    pub ref_se: f64,
    /// `|mean - ref_mean|`.
    pub error: f64,
    /// `error / sqrt(se^2 + ref_se^2)`: 0 when the error is 0, infinite when it is not but both
    /// errors are 0, NaN when a value is.
    pub z: f64,
    /// `mean` inside the reference's 95 % interval, `ref_mean +- 1.96 ref_se` (false when a
    /// value is NaN).
    pub inside: bool,
}

/// Compare a setting's `(mean, se)` with the reference's (see [`Comparison`]).
pub fn compare(mean: f64, se: f64, ref_mean: f64, ref_se: f64) -> Comparison {
    let error = (mean - ref_mean).abs();
    let z = if error == 0.0 {
        0.0
    } else {
        error / (se * se + ref_se * ref_se).sqrt()
    };
    Comparison {
        mean,
        se,
        ref_mean,
        ref_se,
        error,
        z,
        inside: error <= Z95 * ref_se,
    }
}

/// One statistic of a setting.
#[derive(Clone, Debug, Serialize)]
pub struct Quantity {
    /// `E_R/E0 [200,400)`, `gamma [222,1000]`.
    pub name: String,
    /// Against the reference.
    pub comparison: Comparison,
}

/// The ensemble of one setting.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    /// The setting.
    pub setting: Setting,
    /// The step taken (fixed-step methods shorten the step asked for to divide the snapshot
    /// interval).
    pub dt: f64,
    /// Window means, then gamma per decade ([`windows`], [`decades`]); empty when a run failed.
    pub quantities: Vec<Quantity>,
    /// Median wall time of a member's run (seconds, set-up included).
    pub seconds_per_member: f64,
    /// Median grain evaluations of a member's run.
    pub grain_evals: u64,
    /// Member 0's largest relative deviation from the reference's member 0 up to
    /// [`super::CONTAINER_HORIZON`] (NaN with a `failure`).
    pub pre_chaos_error: f64,
    /// Empty, or why the setting has no statistics (`failed: ...`) or no pre-chaos error
    /// (`not evaluated: ...`).
    pub failure: String,
}

impl Candidate {
    /// The largest `|z|` over windows and decades (infinite when one is NaN or there is none).
    pub fn max_abs_z(&self) -> f64 {
        if self.quantities.is_empty() {
            return f64::INFINITY;
        }
        self.quantities
            .iter()
            .map(|q| {
                let z = q.comparison.z.abs();
                if z.is_nan() {
                    f64::INFINITY
                } else {
                    z
                }
            })
            .fold(0.0, f64::max)
    }

    /// Every window mean and decade gamma inside the reference's interval.
    pub fn all_inside(&self) -> bool {
        !self.quantities.is_empty() && self.quantities.iter().all(|q| q.comparison.inside)
    }
}

/// The result of `container-a-statistics`.
#[derive(Clone, Debug, Serialize)]
pub struct Statistics {
    /// Members per ensemble.
    pub members: usize,
    /// Snapshots per run.
    pub snapshots: u64,
    /// The leak onset of the reference's ensemble mean (snapshots; 0 when none): the earliest
    /// start of a decade fit.
    pub onset: usize,
    /// The reference, compared with itself (errors 0).
    pub reference: Candidate,
    /// The candidates, in `CANDIDATES` order.
    pub candidates: Vec<Candidate>,
    /// Index into `candidates` of the cheapest one with every statistic inside ([`Self::verdict`]).
    pub verdict: Option<usize>,
}

/// What one member's run gives.
struct MemberRun {
    energy: Vec<f64>,
    e0: f64,
    seconds: f64,
    grain_evals: u64,
    dt: f64,
}

/// The scene of `member` of `setting`: container (a) over `snapshots` snapshots, the causal
/// horizon on, the striker's speed times `1 + member 1e-12`.
fn member_scene(
    src: &SceneSource,
    setting: Setting,
    member: usize,
    snapshots: u64,
) -> Result<Scene, Error> {
    let mut c = src.container();
    let f = c.file_mut();
    set_snapshots(f, snapshots);
    if member > 0 {
        perturb_striker(f, member as f64 * TWIN_EPS);
    }
    f.run.horizon = Some(HorizonFile::default());
    if setting.ratio > 1 {
        c.mark_fast_region()?;
        c.integrator(
            Stepping::Multirate {
                ratio: setting.ratio,
                margin: MULTIRATE_MARGIN,
            },
            None,
        );
    }
    // The setting's method and step replace the scene's.
    let i = c.file_mut().integrator.get_or_insert_with(Default::default);
    i.method = Some(setting.method);
    i.dt = Some(setting.dt);
    if setting.ratio <= 1 {
        // The container scenes run multirate themselves: a single-rate setting drops it.
        i.multirate = None;
    }
    c.build()
}

/// Run `container-a-statistics` (full or quick, [`Config::quick`]) on [`Config::threads`]
/// threads. `progress(label)` is called once before the runs.
pub fn run(cfg: &Config, progress: impl FnMut(&str)) -> Result<Statistics, Error> {
    let (members, snapshots) = if cfg.quick {
        (QUICK_MEMBERS, QUICK_SNAPSHOTS)
    } else {
        (MEMBERS, SNAPSHOTS)
    };
    let src = SceneSource::load(Container::A.path(&cfg.scenes))?;
    run_settings(
        &src,
        REFERENCE,
        &CANDIDATES,
        members,
        snapshots,
        cfg.threads,
        progress,
    )
}

/// [`run`] with the settings, ensemble size, run length and threads given.
fn run_settings(
    src: &SceneSource,
    reference: Setting,
    candidates: &[Setting],
    members: usize,
    snapshots: u64,
    threads: usize,
    mut progress: impl FnMut(&str),
) -> Result<Statistics, Error> {
    let settings: Vec<Setting> = std::iter::once(reference)
        .chain(candidates.iter().copied())
        .collect();
    let mut jobs = Vec::new();
    let mut labels = Vec::new();
    for s in &settings {
        for k in 0..members {
            let label = format!("{} member {k}", s.label());
            jobs.push(Job {
                label: label.clone(),
                scene: member_scene(src, *s, k, snapshots)?,
                regions: vec!["container".to_string()],
                unprotected: Vec::new(),
                unprotected_at: None,
                snapshots: Vec::new(),
                require_untouched_ends: (true, true),
                gauges: None,
                mechanism: false,
            });
            labels.push(label);
        }
    }
    progress(&format!(
        "{NAME}: {} runs ({} settings x {members} members, {snapshots} snapshots)",
        jobs.len(),
        settings.len()
    ));
    let pool = Pool {
        threads,
        progress: true,
        title: NAME.to_string(),
    };
    // A failed run (a blow-up) fails its setting, not the study: it is kept as an error.
    let runs = pool.run(&labels, jobs.len() as u64 * snapshots, |j, tick| {
        Ok(run_job(&jobs[j], tick).and_then(|d| {
            Ok(MemberRun {
                energy: d.region("container")?.energy.to_vec(),
                e0: d.run.initial_energy,
                seconds: d.wall,
                grain_evals: d.run.stats.grain_evals,
                dt: d.run.dt,
            })
        }))
    })?;
    let mut runs = runs.into_iter();
    let mut per_setting: Vec<Result<Vec<MemberRun>, Error>> = settings
        .iter()
        .map(|_| runs.by_ref().take(members).collect())
        .collect();
    // Without the reference nothing can be compared: its failure is the study's.
    let reference_runs = std::mem::replace(&mut per_setting[0], Ok(Vec::new()))?;
    let candidate_runs: Vec<Result<Vec<MemberRun>, String>> = per_setting
        .into_iter()
        .skip(1)
        .map(|r| r.map_err(|e| format!("failed: {e}")))
        .collect();
    Ok(analyse(
        &settings,
        reference_runs,
        &candidate_runs,
        snapshots as usize,
        members,
    ))
}

/// The statistics of one setting's members: window means (mean, se), then decade gammas
/// (jackknife).
fn statistics_of(
    members: &[MemberRun],
    windows: &[(String, Span)],
    decades: &[(String, Span)],
) -> Vec<(f64, f64)> {
    let curves: Vec<Vec<f64>> = members
        .iter()
        .map(|m| m.energy.iter().map(|e| e / m.e0).collect())
        .collect();
    let refs: Vec<&[f64]> = curves.iter().map(|c| &c[..]).collect();
    let mut out = Vec::new();
    for (_, w) in windows {
        let means: Vec<f64> = curves
            .iter()
            .map(|c| match c.get(w.first..=w.last) {
                Some(x) => mean(x),
                None => f64::NAN,
            })
            .collect();
        out.push(mean_se(&means));
    }
    for (_, d) in decades {
        let est = ensemble::jackknife(&refs, |e| {
            ensemble::gamma(e, d.first, d.last, decay::BINS_PER_DECADE)
        });
        out.push(est.map_or((f64::NAN, f64::NAN), |e| (e.value, e.se)));
    }
    out
}

fn analyse(
    settings: &[Setting],
    reference_runs: Vec<MemberRun>,
    runs: &[Result<Vec<MemberRun>, String>],
    snapshots: usize,
    members: usize,
) -> Statistics {
    let reference = &reference_runs;
    let mean = {
        let curves: Vec<Vec<f64>> = reference
            .iter()
            .map(|m| m.energy.iter().map(|e| e / m.e0).collect())
            .collect();
        let refs: Vec<&[f64]> = curves.iter().map(|c| &c[..]).collect();
        ensemble::mean_curve(&refs, None)
    };
    let onset = leak_onset(&mean, decay::ONSET_FRACTION).unwrap_or(0);
    let windows = windows(snapshots);
    let decades = decades(snapshots, onset);
    let names: Vec<&String> = windows.iter().chain(&decades).map(|w| &w.0).collect();
    let ref_stats = statistics_of(reference, &windows, &decades);
    let ref_member0 = Outcome::Energy(reference[0].energy.clone());
    let candidate = |s: Setting, r: Result<&[MemberRun], &String>| -> Candidate {
        match r {
            Ok(m) => {
                let stats = statistics_of(m, &windows, &decades);
                let quantities = names
                    .iter()
                    .zip(stats.iter().zip(&ref_stats))
                    .map(|(name, (c, r))| Quantity {
                        name: name.to_string(),
                        comparison: compare(c.0, c.1, r.0, r.1),
                    })
                    .collect();
                let (pre_chaos_error, failure) = match error_of(
                    &Outcome::Energy(m[0].energy.clone()),
                    &ref_member0,
                    reference[0].e0,
                ) {
                    Ok(e) => (e, String::new()),
                    Err(why) => (f64::NAN, why),
                };
                let mut evals: Vec<u64> = m.iter().map(|x| x.grain_evals).collect();
                evals.sort_unstable();
                Candidate {
                    setting: s,
                    dt: m[0].dt,
                    quantities,
                    seconds_per_member: median(m.iter().map(|x| x.seconds).collect()),
                    grain_evals: evals[evals.len() / 2],
                    pre_chaos_error,
                    failure,
                }
            }
            Err(why) => Candidate {
                setting: s,
                dt: s.dt,
                quantities: Vec::new(),
                seconds_per_member: f64::NAN,
                grain_evals: 0,
                pre_chaos_error: f64::NAN,
                failure: why.clone(),
            },
        }
    };
    let candidates: Vec<Candidate> = settings[1..]
        .iter()
        .zip(runs)
        .map(|(&s, r)| candidate(s, r.as_deref()))
        .collect();
    let reference = candidate(settings[0], Ok(reference));
    let verdict = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.all_inside() && c.seconds_per_member.is_finite())
        .min_by(|a, b| a.1.seconds_per_member.total_cmp(&b.1.seconds_per_member))
        .map(|(i, _)| i);
    Statistics {
        members,
        snapshots: snapshots as u64,
        onset,
        reference,
        candidates,
        verdict,
    }
}

impl Statistics {
    /// The cheapest candidate whose every window mean and decade gamma is inside the
    /// reference's 95 % interval.
    pub fn verdict(&self) -> Option<&Candidate> {
        self.verdict.map(|i| &self.candidates[i])
    }

    /// The text of `work_precision_statistics.csv`: one row per setting (the reference first,
    /// compared with itself) and window or decade.
    pub fn csv(&self) -> Result<Vec<u8>, Error> {
        use crate::report::csv_number as num;
        let err = |source| Error::Csv {
            what: "work_precision_statistics.csv".into(),
            source,
        };
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record([
            "role",
            "method",
            "dt",
            "ratio",
            "quantity",
            "mean",
            "se",
            "ref_mean",
            "ref_se",
            "error",
            "z",
            "inside",
            "seconds_per_member",
            "grain_evals",
            "pre_chaos_error",
            "failure",
        ])
        .map_err(err)?;
        let rows = std::iter::once(("reference", &self.reference))
            .chain(self.candidates.iter().map(|c| ("candidate", c)));
        for (role, c) in rows {
            let common = |quantity: &str| {
                vec![
                    role.to_string(),
                    c.setting.method.name().to_string(),
                    num(c.dt),
                    c.setting.ratio.to_string(),
                    quantity.to_string(),
                ]
            };
            let cost = [
                num(c.seconds_per_member),
                c.grain_evals.to_string(),
                num(c.pre_chaos_error),
                c.failure.clone(),
            ];
            if c.quantities.is_empty() {
                let mut row = common("");
                row.extend(std::iter::repeat_n(String::new(), 7));
                row.extend(cost.iter().cloned());
                w.write_record(&row).map_err(err)?;
            }
            for q in &c.quantities {
                let k = &q.comparison;
                let mut row = common(&q.name);
                row.extend([
                    num(k.mean),
                    num(k.se),
                    num(k.ref_mean),
                    num(k.ref_se),
                    num(k.error),
                    num(k.z),
                    k.inside.to_string(),
                ]);
                row.extend(cost.iter().cloned());
                w.write_record(&row).map_err(err)?;
            }
        }
        w.into_inner().map_err(|e| Error::Io {
            path: "work_precision_statistics.csv".into(),
            source: e.into_error(),
        })
    }

    /// The chart as SVG: wall time per member against the largest `|z|` over windows and
    /// decades, log-log, one curve per method (and multirate step) through its settings, which
    /// its legend entry lists from the cheapest to the dearest. No line marks a pass: `inside`
    /// compares with the reference's interval alone, so a point left of `|z| = 1.96` can fail
    /// (and a point right of it pass).
    pub fn chart_svg(&self) -> Result<String, Error> {
        let mut families: Vec<(String, Vec<&Candidate>)> = Vec::new();
        for c in &self.candidates {
            let key = match c.setting.ratio {
                1 => c.setting.method.name().to_string(),
                _ => format!("{} dt {:.1e}", c.setting.method.name(), c.setting.dt),
            };
            match families.iter_mut().find(|f| f.0 == key) {
                Some(f) => f.1.push(c),
                None => families.push((key, vec![c])),
            }
        }
        let series = families
            .into_iter()
            .map(|(key, mut cs)| {
                cs.sort_by(|a, b| a.seconds_per_member.total_cmp(&b.seconds_per_member));
                let settings: Vec<String> = cs
                    .iter()
                    .map(|c| match c.setting.ratio {
                        1 => format!("{:.1e}", c.setting.dt),
                        r => r.to_string(),
                    })
                    .collect();
                let what = if cs[0].setting.ratio == 1 {
                    "dt"
                } else {
                    "ratio"
                };
                Series {
                    name: format!("{key}, {what} {}", settings.join(" ")),
                    points: cs
                        .iter()
                        .map(|c| (c.max_abs_z(), c.seconds_per_member))
                        .collect(),
                    markers: true,
                    ..Default::default()
                }
            })
            .collect();
        let title = format!("work-precision: {NAME}");
        LineChart {
            title: &title,
            x_label: "largest |z| over windows and decades",
            y_label: "wall time per member (s)",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series,
            ..Default::default()
        }
        .to_svg()
    }

    /// Write `work_precision_statistics.csv` and `work_precision_container-a-statistics.svg`.
    pub fn write(&self, out: &Path) -> Result<(), Error> {
        AtomicFile::write_all(out.join("work_precision_statistics.csv"), &self.csv()?)?;
        AtomicFile::write_all(
            out.join(format!("work_precision_{NAME}.svg")),
            self.chart_svg()?.as_bytes(),
        )
    }

    /// The results as text: per setting its cost and pre-chaos error, then each statistic
    /// against the reference; last the verdict.
    pub fn table(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{NAME}: {} members x {} snapshots; reference {} ({:.3} s, {} grain evaluations per member)",
            self.members,
            self.snapshots,
            self.reference.setting.label(),
            self.reference.seconds_per_member,
            self.reference.grain_evals,
        );
        for c in &self.candidates {
            let _ = writeln!(
                s,
                "{:<28} {:>8.3} s/member {:>12} grain evals  pre-chaos error {:.3e}  max |z| {:.2}  {}{}",
                c.setting.label(),
                c.seconds_per_member,
                c.grain_evals,
                c.pre_chaos_error,
                c.max_abs_z(),
                if c.all_inside() { "all inside" } else { "NOT all inside" },
                if c.failure.is_empty() {
                    String::new()
                } else {
                    format!("  ({})", c.failure)
                },
            );
            for q in &c.quantities {
                let k = &q.comparison;
                let _ = writeln!(
                    s,
                    "    {:<20} {:>9.5} +- {:<9.2e} ref {:>9.5} +- {:<9.2e} z {:>6.2}  {}",
                    q.name,
                    k.mean,
                    k.se,
                    k.ref_mean,
                    k.ref_se,
                    k.z,
                    if k.inside { "inside" } else { "outside" }
                );
            }
        }
        let _ = match self.verdict() {
            Some(c) => writeln!(
                s,
                "verdict: {} ({:.3} s per member), the cheapest with every statistic inside the reference's 95 % interval",
                c.setting.label(),
                c.seconds_per_member
            ),
            None => writeln!(
                s,
                "verdict: no candidate has every statistic inside the reference's 95 % interval"
            ),
        };
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_ensembles_agree_and_a_shifted_one_does_not() {
        let a = [0.31, 0.29, 0.35, 0.27, 0.30, 0.33, 0.28, 0.32];
        let (m, se) = mean_se(&a);
        let same = compare(m, se, m, se);
        assert_eq!(same.error, 0.0);
        assert_eq!(same.z, 0.0);
        assert!(same.inside);
        // Shifted by 3 standard errors: outside, z = 3 / sqrt(2).
        let b: Vec<f64> = a.iter().map(|x| x + 3.0 * se).collect();
        let (mb, seb) = mean_se(&b);
        assert!((seb - se).abs() < 1e-15);
        let shifted = compare(mb, seb, m, se);
        assert!(!shifted.inside);
        assert!((shifted.error - 3.0 * se).abs() < 1e-12);
        assert!((shifted.z - 3.0 / 2f64.sqrt()).abs() < 1e-9);
        // Shifted by 1.9 standard errors: still inside.
        assert!(compare(m + 1.9 * se, se, m, se).inside);
        // Identical members (no spread): only the identical mean is inside.
        assert!(compare(1.0, 0.0, 1.0, 0.0).inside);
        assert!(!compare(1.0 + 1e-15, 0.0, 1.0, 0.0).inside);
        // A missing value is never inside.
        assert!(!compare(f64::NAN, se, m, se).inside);
        assert!(compare(f64::NAN, se, m, se).z.is_nan());
    }

    #[test]
    fn windows_and_decades_fit_the_run() {
        let w: Vec<String> = windows(4000).into_iter().map(|w| w.0).collect();
        assert_eq!(
            w,
            [
                "E_R/E0 [200,400)",
                "E_R/E0 [400,1000)",
                "E_R/E0 [1000,2000)",
                "E_R/E0 [2000,4000]"
            ]
        );
        assert_eq!(
            windows(4000)[0].1,
            Span {
                first: 200,
                last: 399
            }
        );
        assert_eq!(
            windows(4000)[3].1,
            Span {
                first: 2000,
                last: 4000
            }
        );
        assert_eq!(
            windows(300),
            [(
                "E_R/E0 [150,300]".to_string(),
                Span {
                    first: 150,
                    last: 300
                }
            )]
        );
        let d = decades(4000, 222);
        assert_eq!(d[0].0, "gamma [222,1000]");
        assert_eq!(
            d[1].1,
            Span {
                first: 1000,
                last: 4000
            }
        );
        assert_eq!(
            decades(300, 222)[0].1,
            Span {
                first: 222,
                last: 300
            }
        );
    }

    /// Every number but the timings is the same on one thread and on two.
    #[test]
    fn statistics_do_not_depend_on_the_thread_count() {
        let src = SceneSource::load(
            Container::A.path(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes")),
        )
        .unwrap();
        let reference = Setting::single(Method::BlanesMoan4, 2.0 * SCENE_DT);
        let candidates = [
            Setting::single(Method::BlanesMoan4, 4.0 * SCENE_DT),
            Setting::multirate(2.0 * SCENE_DT, 8),
        ];
        let run =
            |threads| run_settings(&src, reference, &candidates, 2, 300, threads, |_| {}).unwrap();
        let (one, two) = (run(1), run(2));
        assert_eq!(one.onset, two.onset);
        for (a, b) in std::iter::once((&one.reference, &two.reference))
            .chain(one.candidates.iter().zip(&two.candidates))
        {
            assert!(a.failure.is_empty(), "{}", a.failure);
            assert_eq!(a.quantities.len(), 2);
            for (p, q) in a.quantities.iter().zip(&b.quantities) {
                assert_eq!(p.name, q.name);
                assert_eq!(format!("{:?}", p.comparison), format!("{:?}", q.comparison));
            }
            assert_eq!(a.grain_evals, b.grain_evals);
            assert_eq!(a.pre_chaos_error.to_bits(), b.pre_chaos_error.to_bits());
        }
        // The reference against itself.
        for q in &one.reference.quantities {
            assert_eq!(q.comparison.error, 0.0);
            assert!(q.comparison.inside);
        }
        assert_eq!(one.reference.pre_chaos_error, 0.0);
    }
}
