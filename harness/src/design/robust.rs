//! A robust objective's second half (`minimize = "p95"`, `"mean"` or `"quantile"`): after the
//! nominal search and the robust one (`super::run`), the finalists and the two winners.
//!
//! - **Finalists.** The robust search ranks its candidates by the statistic of their first
//!   `screen` common draws. The best `finalists` are run again on those draws for their 95 %
//!   intervals; those whose interval reaches the best one's are confirmed on `confirm` draws of
//!   the same stream (the screening draws and more), and the one with the smallest confirmed
//!   statistic is the robust winner.
//! - **Both winners side by side.** The nominal winner (the nominal search's best) and the robust
//!   one, each on `tolerances.samples` fresh draws (another stream of the seed, none of which the
//!   search saw) at its worst speed and the engine's time cap: the mean, the 95th and 99th
//!   percentiles with their intervals, the nominal peak, and the first-order 95th percentile as a
//!   labelled approximation beside the Monte Carlo's.
//!
//! Every column runs at the search's steps per contact time, so screening, confirmation and the
//! fresh draws measure one discretised peak.

use super::draws_journal::DrawsJournal;
use super::file::{DesignSpec, Robust};
use super::phases::Phases;
use super::search::{self, describe, Outcome, Scored};
use super::tolerance::{
    evaluate_draws, evaluate_draws_counted, first_order, sampled, Draws, Sampled, Statistic,
    FRESH_STREAM,
};
use crate::error::{DesignFailure, Error};
use crate::report::atomic::csv_rows;
use crate::report::csv_number as num;
use crate::report::serialize_number;
use grainchain_engine::protector::{evaluate, gradients, Bead, Evaluation, Settings};
use indicatif::ProgressBar;
use std::fmt::Write as _;
use std::path::Path;

/// The robust outputs' files.
pub const FINALISTS_CSV: &str = "finalists.csv";
/// The two winners on fresh draws.
pub const WINNERS_CSV: &str = "winners.csv";

/// A finalist: its screening and, if its interval reached the best one's, its confirmation.
struct Finalist {
    genes: Vec<usize>,
    /// Which search ranked it among its best: `robust`, `nominal` or `both`.
    source: &'static str,
    /// Per speed, the statistic of the screening draws.
    screened: Vec<Sampled>,
    /// Per speed, the statistic of the confirming draws (`None`: its screening interval lay
    /// wholly above the best one's).
    confirmed: Option<Vec<Sampled>>,
}

/// A robust objective and its interval from each speed's statistic: the worst case over speeds
/// relative to the reference's nominal peak (the interval's ends likewise: the largest of
/// numbers each within its interval lies within the largest of the ends).
fn objective(stats: &[Sampled], reference: &[Evaluation]) -> (f64, f64, f64) {
    let worst = |f: &dyn Fn(&Sampled) -> f64| {
        stats
            .iter()
            .zip(reference)
            .map(|(x, r)| f(x) / r.peak_force)
            .fold(f64::NEG_INFINITY, f64::max)
    };
    (
        worst(&|x| x.value),
        worst(&|x| x.interval.0),
        worst(&|x| x.interval.1),
    )
}

/// A column's draws `range` at every speed, with the search's settings (no giving up).
fn draws_at_speeds(
    problem: &DesignSpec,
    beads: &[Bead],
    (draws, range): (&Draws, std::ops::Range<usize>),
    (threads, bar, journal): (usize, &ProgressBar, Option<&DrawsJournal>),
) -> Result<Vec<Vec<Evaluation>>, Error> {
    let s = search::settings(problem);
    problem
        .impacts
        .iter()
        .map(|imp| {
            evaluate_draws(
                beads,
                imp,
                &problem.protected,
                &s,
                (draws, range.clone()),
                (threads, Some(bar)),
                journal,
            )
            .map_err(|source| failed(problem, source))
        })
        .collect()
}

fn failed(problem: &DesignSpec, source: grainchain_engine::protector::DesignError) -> Error {
    Error::Design(DesignFailure::Evaluation {
        file: problem.path.clone(),
        source,
    })
}

/// The finalists: the best `finalists` designs of the robust search (`robust`, ranked by
/// screening) and of the nominal one (`nominal`, by the nominal peak; a column that is lucky at
/// its nominal sizes may be good under tolerances too, and a small robust search may not have
/// met it), ranked by their screening statistic, the best first.
fn finalists(
    problem: &DesignSpec,
    r: &Robust,
    (robust, nominal): (&[Scored], &[Scored]),
    reference: &[Evaluation],
    threads: usize,
    phases: &Phases,
) -> Result<Vec<Finalist>, Error> {
    let best = |all: &[Scored]| -> Vec<Vec<usize>> {
        all.iter()
            .filter(|s| s.objective.is_finite() && !s.given_up)
            .take(r.finalists)
            .map(|s| s.genes.clone())
            .collect()
    };
    let (from_robust, from_nominal) = (best(robust), best(nominal));
    let mut top: Vec<(Vec<usize>, &'static str)> = Vec::new();
    for g in from_robust.iter().chain(&from_nominal) {
        if top.iter().any(|(t, _)| t == g) {
            continue;
        }
        let source = match (from_robust.contains(g), from_nominal.contains(g)) {
            (true, true) => "both",
            (true, false) => "robust",
            _ => "nominal",
        };
        top.push((g.clone(), source));
    }
    let confirm = r.draws.len();
    let speeds = problem.impacts.len();
    let bar = phases.bar(
        (top.len() * r.screen * speeds) as u64,
        "finalists: their screening draws",
    );
    let mut runs = Vec::with_capacity(top.len());
    for (g, _) in &top {
        let beads = problem.beads(g);
        let e = draws_at_speeds(
            problem,
            &beads,
            (&r.draws, 0..r.screen),
            (threads, &bar, phases.journal()),
        )?;
        runs.push(e);
    }
    bar.finish_and_clear();
    let screened: Vec<Vec<Sampled>> = runs
        .iter()
        .map(|e| e.iter().map(|x| sampled(r.statistic, x)).collect())
        .collect();
    // Ranked by screening (ties by the order found: the robust search's first).
    let mut order: Vec<usize> = (0..top.len()).collect();
    order.sort_by(|&a, &b| {
        objective(&screened[a], reference)
            .0
            .total_cmp(&objective(&screened[b], reference).0)
            .then(a.cmp(&b))
    });
    let best_high = order
        .first()
        .map_or(f64::NAN, |&i| objective(&screened[i], reference).2);
    let reaches = |i: usize| !(objective(&screened[i], reference).1 > best_high);
    let more = confirm - r.screen;
    let bar = phases.bar(
        (order.iter().filter(|&&i| reaches(i)).count() * more * speeds) as u64,
        "finalists: confirming draws",
    );
    let mut runs: Vec<Option<Vec<Vec<Evaluation>>>> = runs.into_iter().map(Some).collect();
    let mut out = Vec::with_capacity(top.len());
    for &i in &order {
        let mut e = runs[i].take().expect("each once");
        let confirmed = if reaches(i) {
            let beads = problem.beads(&top[i].0);
            let rest = draws_at_speeds(
                problem,
                &beads,
                (&r.draws, r.screen..confirm),
                (threads, &bar, phases.journal()),
            )?;
            Some(
                e.iter_mut()
                    .zip(rest)
                    .map(|(a, b)| {
                        a.extend(b);
                        sampled(r.statistic, a)
                    })
                    .collect(),
            )
        } else {
            None
        };
        out.push(Finalist {
            genes: top[i].0.clone(),
            source: top[i].1,
            screened: screened[i].clone(),
            confirmed,
        });
    }
    bar.finish_and_clear();
    Ok(out)
}

/// A winner on fresh draws at its worst speed.
struct Winner {
    /// `nominal` or `robust`.
    label: &'static str,
    genes: Vec<usize>,
    beads: Vec<Bead>,
    /// The index of the speed whose nominal peak is largest.
    speed: usize,
    /// Its nominal run there.
    nominal: Evaluation,
    /// The fresh draws' peaks, sorted.
    peaks: Vec<f64>,
    /// Fresh draws whose peak is a lower bound (the cap ended the run).
    bounds: usize,
    /// The first-order 95th percentile there (an approximation), N.
    first_order_p95: f64,
}

/// One row of `winners.csv`.
#[derive(serde::Serialize)]
struct WinnerRow {
    winner: &'static str,
    genes: String,
    design: String,
    speed_m_s: String,
    #[serde(serialize_with = "serialize_number")]
    nominal_peak_n: f64,
    nominal_bound: bool,
    #[serde(serialize_with = "serialize_number")]
    mean_n: f64,
    #[serde(serialize_with = "serialize_number")]
    mean_low_n: f64,
    #[serde(serialize_with = "serialize_number")]
    mean_high_n: f64,
    #[serde(serialize_with = "serialize_number")]
    p95_n: f64,
    #[serde(serialize_with = "serialize_number")]
    p95_low_n: f64,
    #[serde(serialize_with = "serialize_number")]
    p95_high_n: f64,
    #[serde(serialize_with = "serialize_number")]
    p99_n: f64,
    #[serde(serialize_with = "serialize_number")]
    p99_low_n: f64,
    #[serde(serialize_with = "serialize_number")]
    p99_high_n: f64,
    samples: usize,
    bounds: usize,
    #[serde(serialize_with = "serialize_number")]
    first_order_p95_n: f64,
    first_order_p95_in_interval: bool,
}

/// One row of `finalists.csv`.
#[derive(serde::Serialize)]
struct FinalistRow {
    rank: usize,
    source: &'static str,
    genes: String,
    design: String,
    #[serde(serialize_with = "serialize_number")]
    screened: f64,
    #[serde(serialize_with = "serialize_number")]
    screened_low: f64,
    #[serde(serialize_with = "serialize_number")]
    screened_high: f64,
    screen_draws: usize,
    #[serde(serialize_with = "serialize_number")]
    confirmed: f64,
    #[serde(serialize_with = "serialize_number")]
    confirmed_low: f64,
    #[serde(serialize_with = "serialize_number")]
    confirmed_high: f64,
    confirm_draws: usize,
    bounds: usize,
    winner: bool,
}

impl Winner {
    fn stat(&self, s: Statistic) -> (f64, (f64, f64)) {
        (s.of_sorted(&self.peaks), s.interval(&self.peaks))
    }

    fn row(&self, problem: &DesignSpec) -> WinnerRow {
        let (mean, mi) = self.stat(Statistic::Mean);
        let (p95, pi) = self.stat(Statistic::Quantile(0.95));
        let (p99, qi) = self.stat(Statistic::Quantile(0.99));
        WinnerRow {
            winner: self.label,
            genes: search::genes_key(&self.genes),
            design: describe(&self.beads),
            speed_m_s: num(problem.impacts[self.speed].speed),
            nominal_peak_n: self.nominal.peak_force,
            nominal_bound: !self.nominal.complete,
            mean_n: mean,
            mean_low_n: mi.0,
            mean_high_n: mi.1,
            p95_n: p95,
            p95_low_n: pi.0,
            p95_high_n: pi.1,
            p99_n: p99,
            p99_low_n: qi.0,
            p99_high_n: qi.1,
            samples: self.peaks.len(),
            bounds: self.bounds,
            first_order_p95_n: self.first_order_p95,
            first_order_p95_in_interval: pi.0 <= self.first_order_p95
                && self.first_order_p95 <= pi.1,
        }
    }
}

/// A winner's fresh draws.
fn winner(
    problem: &DesignSpec,
    label: &'static str,
    genes: &[usize],
    threads: usize,
    phases: &Phases,
) -> Result<Winner, Error> {
    let tol = problem
        .tolerances
        .as_ref()
        .expect("a robust objective has them");
    let beads = problem.beads(genes);
    // The engine's time cap, so that most peaks are proven; the search's step.
    let settings = Settings {
        time_cap: Settings::default().time_cap,
        ..search::settings(problem)
    };
    let nominal: Vec<Evaluation> = problem
        .impacts
        .iter()
        .map(|imp| {
            evaluate(&beads, imp, &problem.protected, &settings)
                .map_err(|source| failed(problem, source))
        })
        .collect::<Result<_, _>>()?;
    let speed = (0..nominal.len())
        .max_by(|&a, &b| nominal[a].peak_force.total_cmp(&nominal[b].peak_force))
        .expect("at least one speed");
    let imp = &problem.impacts[speed];
    let draws = Draws::new(beads.len(), tol, tol.samples, FRESH_STREAM);
    let bar = phases.bar(
        draws.len() as u64,
        &format!("the {label} winner on fresh draws"),
    );
    let evals = evaluate_draws_counted(
        &beads,
        imp,
        &problem.protected,
        &settings,
        &draws,
        (threads, &bar, phases.journal()),
    )
    .map_err(|source| failed(problem, source))?;
    bar.finish_and_clear();
    let mut peaks: Vec<f64> = evals.iter().map(|e| e.peak_force).collect();
    peaks.sort_by(f64::total_cmp);
    // Derivatives are built for elastic contacts: with a restitution there is no first order.
    let first_order_p95 = if !imp.is_elastic() {
        f64::NAN
    } else {
        let g = gradients(&beads, imp, &problem.protected, &settings)
            .map_err(|s| failed(problem, s))?;
        first_order(&beads, imp.speed, g.evaluation.peak_force, &g.peak, tol).p95()
    };
    Ok(Winner {
        label,
        genes: genes.to_vec(),
        beads,
        speed,
        nominal: nominal[speed],
        peaks,
        bounds: evals.iter().filter(|e| !e.complete).count(),
        first_order_p95,
    })
}

/// Run the finalists and both winners of a robust objective (`problem`'s) from the nominal
/// search's outcome and the robust search's: the rows of `finalists.csv` and `winners.csv` and
/// DESIGN.md's section, written with the other outputs (`outputs::DesignReport`).
pub fn report(
    problem: &DesignSpec,
    nominal: &Outcome,
    robust: &Outcome,
    threads: usize,
    phases: &Phases,
) -> Result<Tables, Error> {
    let r = problem.robust.as_ref().expect("a robust objective");
    let reference = &robust.reference;
    let fin = finalists(
        problem,
        r,
        (&robust.all, &nominal.all),
        reference,
        threads,
        phases,
    )?;
    let Some(best) = fin
        .iter()
        .enumerate()
        .filter_map(|(i, f)| f.confirmed.as_ref().map(|c| (i, objective(c, reference).0)))
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
        .map(|(i, _)| i)
    else {
        return Err(Error::Design(DesignFailure::NoneFeasible {
            file: problem.path.clone(),
        }));
    };
    let nominal_best = nominal
        .all
        .iter()
        .find(|s| s.objective.is_finite())
        .ok_or_else(|| {
            Error::Design(DesignFailure::NoneFeasible {
                file: problem.path.clone(),
            })
        })?;
    let winners = [
        winner(problem, "nominal", &nominal_best.genes, threads, phases)?,
        winner(problem, "robust", &fin[best].genes, threads, phases)?,
    ];
    let confirm = r.draws.len();
    let rows: Vec<FinalistRow> = fin
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let (s, sl, sh) = objective(&f.screened, reference);
            let c = f.confirmed.as_ref().map(|c| objective(c, reference));
            let nan = (f64::NAN, f64::NAN, f64::NAN);
            let (c, cl, ch) = c.unwrap_or(nan);
            FinalistRow {
                rank: i + 1,
                source: f.source,
                genes: search::genes_key(&f.genes),
                design: describe(&problem.beads(&f.genes)),
                screened: s,
                screened_low: sl,
                screened_high: sh,
                screen_draws: r.screen,
                confirmed: c,
                confirmed_low: cl,
                confirmed_high: ch,
                confirm_draws: if f.confirmed.is_some() { confirm } else { 0 },
                bounds: f
                    .confirmed
                    .as_ref()
                    .unwrap_or(&f.screened)
                    .iter()
                    .map(|x| x.bounds)
                    .sum(),
                winner: i == best,
            }
        })
        .collect();
    let wrows: Vec<WinnerRow> = winners.iter().map(|w| w.row(problem)).collect();
    Ok(Tables {
        section: section(problem, r, &rows, &wrows),
        finalists: rows,
        winners: wrows,
    })
}

/// A robust objective's outputs, computed: the rows of [`FINALISTS_CSV`] and [`WINNERS_CSV`]
/// and DESIGN.md's section.
pub struct Tables {
    finalists: Vec<FinalistRow>,
    winners: Vec<WinnerRow>,
    /// DESIGN.md's section.
    pub section: String,
}

impl Tables {
    /// Write [`FINALISTS_CSV`] and [`WINNERS_CSV`]; the names written.
    pub fn write(&self, out: &Path) -> Result<Vec<String>, Error> {
        csv_rows(&out.join(FINALISTS_CSV), &self.finalists)?;
        csv_rows(&out.join(WINNERS_CSV), &self.winners)?;
        Ok(vec![FINALISTS_CSV.into(), WINNERS_CSV.into()])
    }
}

/// DESIGN.md's section of a robust objective.
fn section(problem: &DesignSpec, r: &Robust, fin: &[FinalistRow], w: &[WinnerRow]) -> String {
    let tol = problem
        .tolerances
        .as_ref()
        .expect("a robust objective has them");
    let stat = r.statistic.name();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n## Robust design: the {stat} of the peak under the tolerances\n\n\
         Tolerances (relative standard deviations): diameter {}, E {}, rho {}, speed {}; seed {}.\n\
         The robust search ranked every candidate by the {stat} of its peak over the same {} \
         draws (common random numbers), relative to the reference column's nominal peak. Its best \
         {} and the nominal search's best {} were run again on those draws for their 95 % \
         intervals, and those whose interval reached the best one's were confirmed on {} draws of \
         the same stream (`{FINALISTS_CSV}`).\n",
        num(tol.diameter),
        num(tol.young),
        num(tol.density),
        num(tol.speed),
        tol.seed,
        r.screen,
        r.finalists,
        r.finalists,
        r.draws.len()
    );
    let _ = writeln!(
        md,
        "| rank | from the search | design | screened {stat} [95 % interval] | confirmed {stat} [95 % interval] |\n|---|---|---|---|---|"
    );
    for f in fin {
        let confirmed = if f.confirm_draws > 0 {
            format!(
                "{:.4} [{:.4}, {:.4}]{}",
                f.confirmed,
                f.confirmed_low,
                f.confirmed_high,
                if f.winner { " **winner**" } else { "" }
            )
        } else {
            "not confirmed: its interval lies above the best one's".into()
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.4} [{:.4}, {:.4}] | {confirmed} |",
            f.rank, f.source, f.design, f.screened, f.screened_low, f.screened_high
        );
    }
    let _ = writeln!(
        md,
        "\n### Both winners on {} fresh draws (`{WINNERS_CSV}`)\n\n\
         Draws of another stream of the seed, none of which the search saw; at the engine's time \
         cap. Intervals are 95 %: the mean's from its standard error, the percentiles' from the \
         order statistics (distribution-free). The first-order 95th percentile (`P + 1.645 \
         sigma_1` from the peak's derivatives) is an approximation, shown beside the Monte Carlo's \
         with whether it lies within its interval.\n\n\
         | winner | design | nominal peak (N) | mean (N) | p95 (N) | p99 (N) | bounds | first-order p95 (N) |\n\
         |---|---|---|---|---|---|---|---|",
        tol.samples
    );
    for x in w {
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | {:.4} [{:.4}, {:.4}] | {:.4} [{:.4}, {:.4}] | {:.4} [{:.4}, {:.4}] | {} | {:.4}{} |",
            x.winner,
            x.design,
            x.nominal_peak_n,
            x.mean_n,
            x.mean_low_n,
            x.mean_high_n,
            x.p95_n,
            x.p95_low_n,
            x.p95_high_n,
            x.p99_n,
            x.p99_low_n,
            x.p99_high_n,
            x.bounds,
            x.first_order_p95_n,
            if x.first_order_p95_n.is_nan() {
                " (none: damped contacts)"
            } else if x.first_order_p95_in_interval {
                ""
            } else {
                " (outside the Monte Carlo's interval)"
            }
        );
    }
    if let [n, r] = w {
        let _ = writeln!(
            md,
            "\nThe robust winner's 95th percentile is {:.3} times the nominal winner's; its \
             nominal peak is {:.3} times the nominal winner's.",
            r.p95_n / n.p95_n,
            r.nominal_peak_n / n.nominal_peak_n
        );
    }
    md
}
