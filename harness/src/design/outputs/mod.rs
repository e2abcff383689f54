//! What `grainchain design` writes: DESIGN.md (the ranked designs, the baselines, robustness),
//! `designs.csv`, `baselines.csv`, `robustness.csv`, `pareto.csv`, the best design as a scene
//! file (`best.toml`), and three plots (`force.svg`, `convergence.svg`, `pareto.svg`); with
//! `[tolerances]` also the peaks' spreads (`tolerances`: `tolerances.csv`, `sensitivities.csv`,
//! a DESIGN.md section, `sensitivity.svg`).

mod chart;
mod rows;
mod tolerances;

pub use tolerances::{SENSITIVITIES_HEADER, TOLERANCES_HEADER};

use super::baselines::{baselines, Baseline};
use super::file::{DesignSpec, Minimize};
use super::phases::Phases;
use super::search::{self, describe, Outcome, Scored};
use crate::error::{DesignFailure, Error};
use crate::report::atomic::{csv_rows, AtomicFile};
use crate::report::csv_number as num;
use crate::report::plot::{Scale, Series};
use chart::Chart;
use grainchain_engine::file::{
    ChainFile, CustomMaterialFile, DesignRecordFile, EndFile, IntegratorFile, LawFile,
    MaterialFile, RunFile, SceneFile, SectionFile, StrikerFile, TargetFile,
};
use grainchain_engine::protector::{
    estimate_many_ticking, evaluate_many, force_history, Bead, Estimate, Evaluation, Impact, Need,
    Settings,
};
use grainchain_engine::units::{constants_name, Material, MATERIALS};
use grainchain_engine::StrikerEnd;
use indicatif::ProgressBar;
use rows::{BaselineRow, DesignRow, ParetoRow, RobustnessRow};
use std::fmt::Write as _;
use std::path::Path;

/// A reported column (a best design, a baseline): its estimate at each of the file's speeds
/// ([`Estimate`]: the run at twice the search's steps per contact time, its error against the
/// runs at the search's and at half of them, all to the end or to the step limit), and its score
/// from the finest runs (a bound less its error).
struct Reported {
    /// The score of the finer runs (the worst case over speeds by peak); `complete` is false
    /// when any peak is a lower bound.
    scored: Scored,
    /// One estimate per speed.
    estimates: Vec<Estimate>,
    /// The speed of the largest peak, whose impulse and duration the score holds.
    worst: usize,
}

impl Reported {
    /// Whether the worst-case peak is only a lower bound (a run at some speed reached its cap).
    fn bound(&self) -> bool {
        self.estimates.iter().any(|e| e.bound)
    }

    /// The error of the worst-case peak: the largest over speeds (the maximum of numbers each
    /// within its error is within the largest of them).
    fn peak_error(&self) -> f64 {
        self.estimates
            .iter()
            .map(|e| e.peak_error)
            .fold(0.0, f64::max)
    }

    /// The impulse's error at the worst-case speed (`None`: not final).
    fn impulse_error(&self) -> Option<f64> {
        self.estimates[self.worst].impulse_error
    }

    /// The duration's error at the worst-case speed (`None`: not final).
    fn duration_error(&self) -> Option<f64> {
        self.estimates[self.worst].duration_error
    }
}

/// Estimates of many columns at every speed on `threads` threads, with `to_end` each run on
/// while its peak is a bound, up to the step limit ([`estimate_many_ticking`]: `bar` moves by
/// one as each finishes); with `give_up`, each speed's runs give up above its force, N.
fn report_columns(
    problem: &DesignSpec,
    columns: &[Vec<Bead>],
    reference: &[Evaluation],
    settings: &Settings,
    (threads, to_end, give_up): (usize, bool, Option<&[f64]>),
    bar: &ProgressBar,
) -> Result<Vec<Reported>, Error> {
    let failed = |e| {
        Error::Design(DesignFailure::Evaluation {
            file: problem.path.clone(),
            source: e,
        })
    };
    let mut per_speed = Vec::new();
    for (s, imp) in problem.impacts.iter().enumerate() {
        let settings = Settings {
            give_up_above: give_up.map_or(settings.give_up_above, |g| g[s]),
            ..*settings
        };
        let r = estimate_many_ticking(
            columns,
            imp,
            &problem.protected,
            &settings,
            (threads, to_end),
            &|| bar.inc(1),
        )
        .map_err(failed)?;
        per_speed.push(
            r.into_iter()
                .collect::<Result<Vec<_>, _>>()
                .map_err(failed)?,
        );
    }
    Ok(columns
        .iter()
        .enumerate()
        .map(|(i, beads)| {
            let estimates: Vec<Estimate> = per_speed.iter().map(|s| s[i]).collect();
            let values: Vec<Evaluation> = estimates.iter().map(Estimate::reported).collect();
            let worst = (0..values.len())
                .max_by(|&a, &b| values[a].peak_force.total_cmp(&values[b].peak_force))
                .expect("at least one speed");
            let mut scored = search::scored(problem, &[], beads, &values, &[], reference);
            scored.complete = !estimates.iter().any(|e| e.bound);
            Reported {
                scored,
                estimates,
                worst,
            }
        })
        .collect())
}

/// `value ± error` with the digits the error allows: the error rounded up to one significant
/// digit (two when that digit is 1), the value to the same decimal place; both times `scale`
/// (1e3: N s to mN s). A lower bound (`value` already less its error, [`Estimate::reported`])
/// is `≥ value` rounded down to that place, so that it stays a bound; `not final` without an
/// error.
pub fn with_error(value: f64, error: Option<f64>, bound: bool, scale: f64) -> String {
    let Some(error) = error else {
        return "not final".into();
    };
    let (x, e) = (value * scale, error * scale);
    let at_least = if bound { "≥ " } else { "" };
    if !(x.is_finite() && e.is_finite()) {
        return format!("{at_least}{x} ± {e}");
    }
    if e == 0.0 {
        // Both runs gave the same bits.
        return format!("{at_least}{x} ± 0");
    }
    let exp = e.log10().floor() as i32;
    let lead = e / 10f64.powi(exp);
    // The decimal place of the error's last digit kept.
    let place = if lead < 2.0 { exp - 1 } else { exp };
    let q = 10f64.powi(place);
    // Up, but not past a whole digit that division's rounding left a hair above (2e-5 / 1e-5).
    let rounded = (e / q * (1.0 - 1e-12)).ceil() * q;
    let decimals = usize::try_from(-place).unwrap_or(0);
    if bound {
        // Down, but not past a whole digit that division's rounding left a hair below.
        let down = (x / q * (1.0 + 1e-12)).floor() * q;
        return format!("≥ {down:.decimals$}");
    }
    format!("{x:.decimals$} ± {rounded:.decimals$}")
}

/// Every output of a design run, computed once ([`DesignReport::build`]): the rows of every
/// CSV, the series of every plot, the best design's scene file and DESIGN.md's text.
/// [`DesignReport::write`] writes them and computes nothing.
pub struct DesignReport {
    designs: Vec<DesignRow>,
    baselines: Vec<BaselineRow>,
    robustness: Vec<RobustnessRow>,
    pareto: Vec<ParetoRow>,
    force: Chart,
    convergence: Chart,
    front: Chart,
    tolerances: Option<tolerances::Tables>,
    best_toml: String,
    refined: Option<Vec<super::refine::RefinedRow>>,
    robust: Option<super::robust::Tables>,
    markdown: String,
}

/// Compute every output ([`DesignReport::build`]) and write it; returns the files written
/// (relative to `out`).
pub fn write(
    problem: &DesignSpec,
    outcome: &Outcome,
    out: &Path,
    threads: usize,
    (robust, phases): (Option<super::robust::Tables>, &Phases),
) -> Result<Vec<String>, Error> {
    DesignReport::build(problem, outcome, threads, (robust, phases))?.write(out)
}

impl DesignReport {
    /// Write every output into `out`, computing nothing; returns the files written (relative to
    /// `out`), in the order DESIGN.md and the manifest list them.
    pub fn write(&self, out: &Path) -> Result<Vec<String>, Error> {
        let mut written: Vec<String> = Vec::new();
        csv_rows(&out.join("designs.csv"), &self.designs)?;
        written.push("designs.csv".into());
        csv_rows(&out.join("baselines.csv"), &self.baselines)?;
        written.push("baselines.csv".into());
        csv_rows(&out.join("robustness.csv"), &self.robustness)?;
        written.push("robustness.csv".into());
        csv_rows(&out.join("pareto.csv"), &self.pareto)?;
        written.push("pareto.csv".into());
        for (chart, name) in [
            (&self.force, "force.svg"),
            (&self.convergence, "convergence.svg"),
            (&self.front, "pareto.svg"),
        ] {
            chart.write(&out.join(name))?;
            written.push(name.into());
        }
        if let Some(t) = &self.tolerances {
            written.extend(t.write(out)?);
        }
        AtomicFile::write_all(out.join("best.toml"), self.best_toml.as_bytes())?;
        written.push("best.toml".into());
        if let Some(rows) = &self.refined {
            csv_rows(&out.join(super::refine::REFINED_CSV), rows)?;
            written.push(super::refine::REFINED_CSV.into());
        }
        if let Some(r) = &self.robust {
            written.extend(r.write(out)?);
        }
        AtomicFile::write_all(out.join("DESIGN.md"), self.markdown.as_bytes())?;
        written.push("DESIGN.md".into());
        Ok(written)
    }

    /// Compute every output of `outcome` (the search's, merged): the reported runs with their
    /// errors, the baselines, `[tolerances]`' analysis, the robustness runs, the force curves,
    /// `[refine]`'s refinement, and `robust`'s tables (a robust objective's finalists and
    /// winners, computed before).
    pub fn build(
        problem: &DesignSpec,
        outcome: &Outcome,
        threads: usize,
        (robust_tables, phases): (Option<super::robust::Tables>, &Phases),
    ) -> Result<DesignReport, Error> {
        let settings = search::settings(problem);
        let valid: Vec<&Scored> = outcome
            .all
            .iter()
            .filter(|s| s.objective.is_finite())
            .collect();
        let Some(best) = valid.first() else {
            return Err(Error::Design(DesignFailure::NoneFeasible {
                file: problem.path.clone(),
            }));
        };
        let best_beads = problem.beads(&best.genes);
        // The top designs again, each with its error (at twice the search's steps per contact
        // time, against runs at the search's and at half of them), at the engine's time cap, ten times the search's,
        // and while a peak is a bound at ten times more, up to the step limit (their numbers are
        // then exact where the stop rule ended the runs, and lower bounds where the cap did).
        let top: Vec<Vec<Bead>> = valid
            .iter()
            .take(REPORTED)
            .map(|s| problem.beads(&s.genes))
            .collect();
        let long = Settings {
            time_cap: Settings::default().time_cap,
            ..settings
        };
        let bases = baselines(problem);
        let bar = phases.bar(
            ((top.len() + bases.len()) * problem.impacts.len()) as u64,
            "the ten best and the baselines with their errors",
        );
        let mut top_scored = report_columns(
            problem,
            &top,
            &outcome.reference,
            &long,
            (threads, true, None),
            &bar,
        )?;
        // The baselines at the file's speeds, with their errors at the engine's cap, not beyond:
        // they rank nowhere, and a tapered column of 0.2 mm beads that never proves its peak would
        // take most of a minute to the step limit. A bound among them stays marked.
        let base_cols: Vec<Vec<Bead>> = bases.iter().map(|b| b.beads.clone()).collect();
        let mut base_scored = report_columns(
            problem,
            &base_cols,
            &outcome.reference,
            &long,
            (threads, false, None),
            &bar,
        )?;
        bar.finish_and_clear();
        let mono_peak = base_scored[0].scored.peak;
        // Every other design evaluated, with its error too, at the search's step and cap (not run
        // on: a bound stays marked, less its error): `designs.csv` states no number without one.
        // Each speed's runs give up above the largest peak of the ten best at that speed (a design
        // ranked below them that passes it is known to be worse there, and its lower bound is
        // enough: most of a search's designs are such, and run to the cap they would cost four
        // times the search on `multi-material.toml`).
        let give_up: Vec<f64> = (0..problem.impacts.len())
            .map(|s| {
                top_scored
                    .iter()
                    .map(|r| r.estimates[s].value.peak_force)
                    .fold(0.0, f64::max)
            })
            .collect();
        let rest: Vec<Vec<Bead>> = valid
            .iter()
            .skip(REPORTED)
            .map(|s| problem.beads(&s.genes))
            .collect();
        let bar = phases.bar(
            (rest.len() * problem.impacts.len()) as u64,
            "the other designs with their errors",
        );
        let rest_scored = report_columns(
            problem,
            &rest,
            &outcome.reference,
            &settings,
            (threads, false, Some(&give_up)),
            &bar,
        )?;
        bar.finish_and_clear();

        // `[tolerances]`: every reported column's spread at its worst speed, at the search's step and
        // the reported runs' time cap, not extended (at the search's cap most peaks of a column that
        // traps its energy are bounds; a peak-only run). For the p95 objective, each
        // reported objective takes the first-order spread at each speed from these runs and the peak
        // from the finer ones above.
        let spreads =
            match &problem.tolerances {
                None => None,
                Some(tol) => {
                    let columns: Vec<tolerances::Column> =
                        top.iter()
                            .zip(&top_scored)
                            .enumerate()
                            .map(|(i, (beads, r))| tolerances::Column {
                                kind: "design",
                                name: (i + 1).to_string(),
                                described: describe(beads),
                                beads,
                                worst: r.worst,
                            })
                            .chain(bases.iter().zip(&base_scored).map(|(b, r)| {
                                tolerances::Column {
                                    kind: "baseline",
                                    name: b.name.clone(),
                                    described: describe(&b.beads),
                                    beads: &b.beads,
                                    worst: r.worst,
                                }
                            }))
                            .collect();
                    let p95 = problem.file.objective.minimize == Minimize::P95FirstOrder;
                    let peak_only = Settings {
                        need: Need::Peak,
                        ..long
                    };
                    let a = tolerances::analyse(
                        &problem.path,
                        &columns,
                        &problem.impacts,
                        &problem.protected,
                        &peak_only,
                        tol,
                        (threads, p95, phases),
                    )?;
                    if p95 {
                        for (r, sd) in top_scored.iter_mut().chain(&mut base_scored).zip(&a.sd) {
                            let values: Vec<Evaluation> =
                                r.estimates.iter().map(Estimate::reported).collect();
                            r.scored.objective =
                                search::objective(problem, &values, sd, &outcome.reference);
                        }
                    }
                    let md =
                        tolerances::section(&columns, &a, &problem.impacts, tol, &peak_only, p95);
                    Some((tolerances::Tables::new(&columns, &a, &problem.impacts), md))
                }
            };

        // Robustness: a decade of speed either side of the first speed, and restitution 0.95.
        let v0 = problem.impacts[0].speed;
        let mut conditions: Vec<(String, Impact)> = [0.1, 0.316, 1.0, 3.16, 10.0]
            .iter()
            .map(|f| {
                (
                    format!("{} m/s", num(v0 * f)),
                    Impact {
                        speed: v0 * f,
                        ..problem.impacts[0].clone()
                    },
                )
            })
            .collect();
        conditions.push((
            format!("{} m/s, restitution 0.95", num(v0)),
            Impact {
                restitution: Some(0.95),
                restitution_pairs: Vec::new(),
                ..problem.impacts[0].clone()
            },
        ));
        let best_base = (1..base_scored.len())
            .min_by(|&a, &b| {
                base_scored[a]
                    .scored
                    .peak
                    .total_cmp(&base_scored[b].scored.peak)
            })
            .unwrap_or(0);
        let robust_cols = vec![
            best_beads.clone(),
            base_cols[0].clone(),
            base_cols[best_base].clone(),
        ];
        let robust_names = [
            "best design",
            "monodisperse",
            bases[best_base].name.as_str(),
        ];
        let mut robust: Vec<Robust> = Vec::new();
        // At the search's time cap: the robustness runs are many, and a column that traps its
        // energy costs ten times more at the long cap (`exact` says where the cap ended a run).
        for (label, imp) in &conditions {
            let r = evaluate_many(&robust_cols, imp, &problem.protected, &settings, threads)
                .map_err(|e| {
                    Error::Design(DesignFailure::Evaluation {
                        file: problem.path.clone(),
                        source: e,
                    })
                })?;
            let r: Vec<Evaluation> = r.into_iter().collect::<Result<_, _>>().map_err(|e| {
                Error::Design(DesignFailure::Evaluation {
                    file: problem.path.clone(),
                    source: e,
                })
            })?;
            robust.push(Robust {
                condition: label.clone(),
                peaks: [r[0].peak_force, r[1].peak_force, r[2].peak_force],
                bound: [!r[0].complete, !r[1].complete, !r[2].complete],
            });
        }

        // The first REPORTED rows hold the reported runs, the rest the runs at the search's cap,
        // each with its errors; in the search's order.
        let design_rows: Vec<DesignRow> = valid
            .iter()
            .enumerate()
            .map(|(i, found)| {
                let r = top_scored.get(i).or_else(|| rest_scored.get(i - REPORTED));
                let s = r.map_or(*found, |r| &r.scored);
                DesignRow {
                    rank: i + 1,
                    genes: search::genes_key(&found.genes),
                    design: describe(&problem.beads(&found.genes)),
                    objective: s.objective,
                    peak_n: s.peak,
                    peak_n_error: r.map(Reported::peak_error),
                    bound: r.map_or(!found.complete, Reported::bound),
                    peak_ratio: s.peak / mono_peak,
                    impulse_ns: s.impulse,
                    impulse_ns_error: r.and_then(Reported::impulse_error),
                    duration_s: s.duration,
                    duration_s_error: r.and_then(Reported::duration_error),
                    mass_kg: s.mass,
                    length_m: s.length,
                    complete: s.complete,
                    given_up: found.given_up,
                }
            })
            .collect();
        let baseline_rows: Vec<BaselineRow> = bases
            .iter()
            .zip(&base_scored)
            .map(|(b, r)| {
                let s = &r.scored;
                BaselineRow {
                    baseline: b.name.clone(),
                    design: describe(&b.beads),
                    objective: s.objective,
                    peak_n: s.peak,
                    peak_n_error: Some(r.peak_error()),
                    bound: r.bound(),
                    peak_ratio: s.peak / mono_peak,
                    impulse_ns: s.impulse,
                    impulse_ns_error: r.impulse_error(),
                    duration_s: s.duration,
                    duration_s_error: r.duration_error(),
                    mass_kg: s.mass,
                    length_m: s.length,
                    complete: s.complete,
                }
            })
            .collect();
        let robustness_rows: Vec<RobustnessRow> = robust
            .iter()
            .map(|r| {
                let p = r.peaks;
                RobustnessRow {
                    condition: r.condition.clone(),
                    best_peak_n: p[0],
                    monodisperse_peak_n: p[1],
                    best_baseline: robust_names[2].to_string(),
                    best_baseline_peak_n: p[2],
                    best_ratio: p[0] / p[1],
                    complete: !r.bound.iter().any(|&b| b),
                    best_bound: r.bound[0],
                    monodisperse_bound: r.bound[1],
                    best_baseline_bound: r.bound[2],
                }
            })
            .collect();
        let front = search::pareto(&outcome.all);
        let pareto_rows: Vec<ParetoRow> = front
            .iter()
            .map(|s| ParetoRow {
                mass_kg: s.mass,
                objective: s.objective,
                peak_n: s.peak,
                bound: !s.complete,
                genes: search::genes_key(&s.genes),
                design: describe(&problem.beads(&s.genes)),
            })
            .collect();

        // Plots.
        let mut curves: Vec<(String, &[Bead])> = vec![
            ("best design".into(), &best_beads),
            ("monodisperse".into(), &base_cols[0]),
        ];
        if best_base != 0 {
            curves.push((bases[best_base].name.clone(), &base_cols[best_base]));
        }
        // Three times the latest peak of the curves drawn.
        let t_end = 3.0
            * [&top_scored[0], &base_scored[0], &base_scored[best_base]]
                .iter()
                .map(|r| r.estimates[0].value.peak_time)
                .fold(0.0, f64::max);
        let mut series = Vec::new();
        for (name, beads) in &curves {
            let h = force_history(
                beads,
                &problem.impacts[0],
                &problem.protected,
                &settings,
                t_end,
                1500,
            )
            .map_err(|e| {
                Error::Design(DesignFailure::Evaluation {
                    file: problem.path.clone(),
                    source: e,
                })
            })?;
            series.push(Series {
                name: name.clone(),
                points: h.iter().map(|(t, f)| (t * 1e3, *f)).collect(),
                ..Default::default()
            });
        }
        let force = Chart {
            title: format!(
                "force on the protected face, striker at {} m/s",
                num(problem.impacts[0].speed)
            ),
            x_label: "t (ms)",
            y_label: "force (N)",
            y_scale: Scale::Linear,
            series,
        };
        let convergence = Chart {
            title: "the search: best objective after each generation".into(),
            x_label: "generation",
            y_label: "objective (relative to the monodisperse column)",
            y_scale: Scale::Linear,
            series: vec![Series {
                name: "best so far".into(),
                points: outcome
                    .convergence
                    .iter()
                    .map(|&(g, b)| (g as f64, b))
                    .collect(),
                markers: true,
                ..Default::default()
            }],
        };
        let front_chart = Chart {
            title: "every design evaluated, and the front of objective against mass".into(),
            x_label: "column mass (g)",
            y_label: "objective (relative to the monodisperse column)",
            y_scale: Scale::Log,
            series: vec![
                Series {
                    name: "designs evaluated".into(),
                    points: valid.iter().map(|s| (s.mass * 1e3, s.objective)).collect(),
                    markers: true,
                    ..Default::default()
                },
                Series {
                    name: "Pareto front".into(),
                    points: front.iter().map(|s| (s.mass * 1e3, s.objective)).collect(),
                    markers: true,
                    reference: true,
                    ..Default::default()
                },
            ],
        };
        let best_toml = scene_toml(problem, &best_beads, &top_scored[0].estimates[0])?;
        let mut md = report(
            problem,
            outcome,
            &valid,
            &top_scored,
            &bases,
            &base_scored,
            &robust,
            robust_names,
            front.len(),
            settings.need,
            spreads.as_ref().map(|s| s.1.as_str()),
        );
        let found: Vec<Vec<Bead>> = valid.iter().map(|s| problem.beads(&s.genes)).collect();
        let refined =
            super::refine::report(problem, &found, &outcome.reference, (threads, phases))?.map(
                |r| {
                    md.push_str(&r.section);
                    r.rows
                },
            );
        if let Some(r) = &robust_tables {
            md.push_str(&r.section);
        }
        Ok(DesignReport {
            designs: design_rows,
            baselines: baseline_rows,
            robustness: robustness_rows,
            pareto: pareto_rows,
            force,
            convergence,
            front: front_chart,
            tolerances: spreads.map(|s| s.0),
            best_toml,
            refined,
            robust: robust_tables,
            markdown: md,
        })
    }
}

/// How much of the first third of a column is stiffer than its last third's mean: +1 all hard
/// first, -1 all soft first (Fraternali's optima: hard at the struck end, soft by the wall).
fn hard_first(beads: &[Bead]) -> f64 {
    let n = beads.len();
    let third = (n / 3).max(1);
    let mean = |s: &[Bead]| s.iter().map(|b| b.material.young.ln()).sum::<f64>() / s.len() as f64;
    let (a, b) = (mean(&beads[..third]), mean(&beads[n - third..]));
    if a == b {
        0.0
    } else {
        (a - b).signum()
    }
}

/// One condition of the robustness runs: the peaks of the best design, the monodisperse column
/// and the best baseline, and whether each is a lower bound (its run reached the cap).
struct Robust {
    condition: String,
    peaks: [f64; 3],
    bound: [bool; 3],
}

/// The designs reported (re-run with their errors): the first ten of the ranking.
const REPORTED: usize = 10;

/// `designs.csv`'s header: the errors (`*_error`, empty where not estimated or not final) and
/// `bound` (the peak is a lower bound) beside the numbers.
pub const DESIGNS_HEADER: &str = "rank,genes,design,objective,peak_n,peak_n_error,bound,peak_ratio,impulse_ns,impulse_ns_error,duration_s,duration_s_error,mass_kg,length_m,complete,given_up";

/// `baselines.csv`'s header.
pub const BASELINES_HEADER: &str = "baseline,design,objective,peak_n,peak_n_error,bound,peak_ratio,impulse_ns,impulse_ns_error,duration_s,duration_s_error,mass_kg,length_m,complete";

/// A peak for a table: `≥ ` before a lower bound, three decimals.
fn peak_cell(peak: f64, bound: bool) -> String {
    format!("{}{peak:.3}", if bound { "≥ " } else { "" })
}

/// The table cells of a reported column's peak (N), and its impulse (mN s) and duration (ms)
/// where `need` makes them final.
fn number_cells(r: &Reported, need: Need) -> String {
    let s = &r.scored;
    let mut cells = format!(
        "| {} |",
        with_error(s.peak, Some(r.peak_error()), r.bound(), 1.0)
    );
    if need == Need::Everything {
        let _ = write!(
            cells,
            " {} |",
            with_error(s.impulse, r.impulse_error(), false, 1e3)
        );
    }
    if need != Need::Peak {
        let _ = write!(
            cells,
            " {} |",
            with_error(s.duration, r.duration_error(), false, 1e3)
        );
    }
    cells
}

/// The header cells [`number_cells`] fills.
fn number_headers(need: Need) -> (String, String) {
    let mut head = "| peak force (N) |".to_string();
    let mut rule = "|---|".to_string();
    if need == Need::Everything {
        head.push_str(" impulse (mN s) |");
        rule.push_str("---|");
    }
    if need != Need::Peak {
        head.push_str(" duration (ms) |");
        rule.push_str("---|");
    }
    (head, rule)
}

#[allow(clippy::too_many_arguments)]
fn report(
    problem: &DesignSpec,
    outcome: &Outcome,
    valid: &[&Scored],
    top: &[Reported],
    bases: &[Baseline],
    base_scored: &[Reported],
    robust: &[Robust],
    robust_names: [&str; 3],
    front: usize,
    need: Need,
    tolerances: Option<&str>,
) -> String {
    let f = &problem.file;
    let mono = base_scored[0].scored.peak;
    let (number_head, number_rule) = number_headers(need);
    let mut md = String::new();
    let _ = writeln!(md, "# Protector design: {}\n", problem.path.display());
    let _ = writeln!(
        md,
        "Written by `grainchain design {}` from {} designs evaluated (the journals in \
         `evaluations/`). Objective: minimise {:?}{}, as the worst case over the striker speeds \
         {:?} m/s, relative to the monodisperse column ({} beads of {}). Striker: {} {} mm. \
         Protected: {}. Every number below was computed by this run; `designs.csv`, \
         `baselines.csv`, `robustness.csv` and `pareto.csv` hold them all.\n",
        problem.path.display(),
        outcome.all.len(),
        format!("{:?}", f.objective.minimize).to_lowercase(),
        match f.objective.weights {
            Some(w) => format!(
                " (weights peak {}, impulse {}, duration {})",
                w.peak, w.impulse, w.duration
            ),
            None => String::new(),
        },
        f.load.speeds,
        f.space.beads,
        describe(&[problem.reference]).trim_start_matches("1 x "),
        problem.impacts[0].striker.material.name,
        problem.impacts[0].striker.diameter * 1e3,
        match problem.protected {
            grainchain_engine::protector::Protected::Wall(m) => format!("a rigid {} wall", m.name),
            grainchain_engine::protector::Protected::Target {
                mass,
                material,
                spring,
            } => format!(
                "a {mass} kg target with a {} face on a {spring} N/m spring",
                material.name
            ),
        },
    );
    if let Some(line) = dissipation(&problem.impacts[0]) {
        let _ = writeln!(md, "{line}\n");
    }
    let steps = grainchain_engine::protector::steps_for_accuracy(f.search.accuracy);
    let _ = writeln!(md, "## The best designs\n");
    let _ =
        writeln!(
        md,
        "Re-run at ten times the search's time cap, with blanes-moan4 and contact events at {} \
         steps per contact time (twice the search's {}, set by `accuracy = {:e}`); each number's \
         error (`±`) is its \
         difference from the run at {} steps, conservative for a method of order 2 or more. A peak \
         marked `≥` is a lower bound: its runs reached their time cap (extended tenfold at a time, \
         up to the step limit) before the stop rule could prove it.{}\n",
        num(2.0 * steps),
        num(steps),
        f.search.accuracy,
        num(steps),
        match need {
            Need::Peak => " Impulse and duration are not final here (the runs stop once the \
                           peak is proven): `designs.csv` holds them without an error.",
            Need::Duration => " The impulse is not final here (the runs stop once the duration \
                               is proven): `designs.csv` holds it without an error.",
            Need::Everything => "",
        }
    );
    let _ = writeln!(
        md,
        "| rank | design | objective {number_head} vs monodisperse | mass (g) | length (mm) |"
    );
    let _ = writeln!(md, "|---|---|---{number_rule}---|---|---|");
    for (i, (s, r)) in valid.iter().zip(top).enumerate() {
        let t = &r.scored;
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} {} {:.3} | {:.1} | {:.1} |",
            i + 1,
            describe(&problem.beads(&s.genes)),
            t.objective,
            number_cells(r, need),
            t.peak / mono,
            t.mass * 1e3,
            t.length * 1e3,
        );
    }
    let best = &top[0].scored;
    let _ = writeln!(md, "\n## Against the known designs\n");
    let _ = writeln!(md, "Same load, same bead count; all but the Fraternali-style pattern at the monodisperse column's mass. Errors as above; a bound here is not run past the engine's cap (`≥`).\n");
    let _ = writeln!(
        md,
        "| baseline | design {number_head} vs monodisperse | best design's peak / this | mass (g) |"
    );
    let _ = writeln!(md, "|---|---{number_rule}---|---|---|");
    for (b, r) in bases.iter().zip(base_scored) {
        let s = &r.scored;
        let _ = writeln!(
            md,
            "| {} | {} {} {:.3} | {:.3} | {:.1} |",
            b.name,
            describe(&b.beads),
            number_cells(r, need),
            s.peak / mono,
            best.peak / s.peak,
            s.mass * 1e3,
        );
    }
    let _ = writeln!(md, "\n## Robustness\n");
    let _ = writeln!(md, "The best design, the monodisperse column and the best baseline ({}) at a decade of speed either side of {} m/s, and with every contact's restitution 0.95: single runs at the search's step and time cap (no error estimate; `≥`: a lower bound, the run reached the cap).\n", robust_names[2], problem.impacts[0].speed);
    let _ = writeln!(
        md,
        "| condition | best design (N) | monodisperse (N) | {} (N) | best / monodisperse |",
        robust_names[2]
    );
    let _ = writeln!(md, "|---|---|---|---|---|");
    for r in robust {
        let (p, b) = (r.peaks, r.bound);
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.3} |",
            r.condition,
            peak_cell(p[0], b[0]),
            peak_cell(p[1], b[1]),
            peak_cell(p[2], b[2]),
            p[0] / p[1],
        );
    }
    if let Some(section) = tolerances {
        md.push('\n');
        md.push_str(section);
    }
    let best_beads = problem.beads(&valid[0].genes);
    let _ = writeln!(md, "\n## Does it look like the published optima?\n");
    let _ = writeln!(
        md,
        "Fraternali, Porter and Daraio (2010) found hard, heavy beads at the struck end and soft, \
         light ones by the wall. The best design here puts the {} beads first (mean log-modulus \
         of its first third {} its last third's).\n",
        match hard_first(&best_beads) {
            x if x > 0.0 => "harder",
            x if x < 0.0 => "softer",
            _ => "same",
        },
        match hard_first(&best_beads) {
            x if x > 0.0 => "above",
            x if x < 0.0 => "below",
            _ => "equal to",
        }
    );
    let _ = writeln!(md, "## The search\n");
    let _ = writeln!(
        md,
        "Genetic algorithm (`genetic_algorithm` crate): seed {}, population {}, at most {} \
         generations, stopping after {} without a better design; {} generations recorded; the \
         Pareto front of objective against mass has {front} designs (`pareto.svg`). Plots: \
         `force.svg` (the force on the protected face over time), `convergence.svg`. {} of the \
         designs were given up on once their peak showed that a design no heavier was at least \
         as good (`given_up` in `designs.csv`: their numbers are lower bounds; `give_up = false` \
         in `[search]` runs each to the cap).\n",
        f.search.seed,
        f.search.population,
        f.search.generations,
        f.search.stale,
        outcome.convergence.len(),
        outcome.all.iter().filter(|s| s.given_up).count()
    );
    md
}

/// A material as a scene file gives it: its key in the table, or its constants with its name
/// (left out when it is the name of its constants, which a longer-than-allowed name can be).
fn material_file(m: &Material) -> MaterialFile {
    match MATERIALS.iter().find(|(_, x)| x == m) {
        Some((key, _)) => MaterialFile::Named((*key).to_string()),
        None => MaterialFile::Custom(CustomMaterialFile {
            young: m.young,
            nu: m.poisson,
            rho: m.density,
            name: (m.name != constants_name(m.young, m.poisson, m.density))
                .then(|| m.name.to_string()),
        }),
    }
}

/// DESIGN.md's line on the contacts' dissipation (none for elastic contacts).
fn dissipation(imp: &Impact) -> Option<String> {
    if imp.is_elastic() {
        return None;
    }
    let every = match imp.restitution {
        Some(e) => format!("every contact's coefficient of restitution is {e}"),
        None => "every contact is elastic".to_string(),
    };
    let pairs: Vec<String> = imp
        .restitution_pairs
        .iter()
        .map(|p| format!("{} on {} {}", p.between[0], p.between[1], p.restitution))
        .collect();
    let but = if pairs.is_empty() {
        String::new()
    } else {
        format!(" but for these pairs' own: {}", pairs.join(", "))
    };
    Some(format!(
        "Dissipation: {every}{but} (the scale-respecting dashpot, whose restitution is the same \
         at every speed; 1 is elastic)."
    ))
}

/// A contact law's table holding only `material` (a wall's, a section's).
fn material_law(m: &Material) -> LawFile {
    LawFile {
        material: Some(material_file(m)),
        p: None,
        eta: None,
        delta0: None,
        tension: None,
        contact_damping: None,
        restitution: None,
    }
}

/// The design as an SI scene file (`grainchain run best.toml`): its runs of equal beads as
/// sections, the striker at the file's first speed, the wall or target, the evaluation's step,
/// and a run to three times the peak's time. The scene file's own schema serialised
/// (`file::SceneFile`), so that what is written is what `grainchain run` reads.
pub fn scene_toml(problem: &DesignSpec, beads: &[Bead], est: &Estimate) -> Result<String, Error> {
    use grainchain_engine::protector::Protected;
    let imp = &problem.impacts[0];
    let e = &est.reported();
    let settings = super::search::settings(problem);
    // A contact's own restitution where the impact's pairs give it another than every
    // contact's (`chain.restitution`; 1: elastic).
    let own = |a: &Material, b: &Material| {
        let e = imp.restitution_between(a, b);
        (e != imp.restitution).then(|| e.unwrap_or(1.0))
    };
    let mut sections = Vec::new();
    let mut section = |from: usize, to: usize, restitution: Option<f64>| {
        sections.push(SectionFile {
            name: Some(format!("beads {}-{to}", from + 1)),
            count: (to - from) as u64,
            mass: None,
            diameter: Some(beads[from].diameter),
            damping: None,
            law: LawFile {
                restitution,
                ..material_law(&beads[from].material)
            },
        });
    };
    let mut i = 0;
    while i < beads.len() {
        let mut j = i + 1;
        while j < beads.len() && beads[j] == beads[i] {
            j += 1;
        }
        // A section's restitution is its joint's and its inner contacts': a run whose joint
        // differs is its first bead (the joint) and the rest.
        let m = &beads[i].material;
        let inner = own(m, m);
        match (i > 0).then(|| own(&beads[i - 1].material, m)) {
            Some(joint) if joint != inner && j - i > 1 => {
                section(i, i + 1, joint);
                section(i + 1, j, inner);
            }
            Some(joint) if j - i == 1 => section(i, j, joint),
            _ => section(i, j, inner),
        }
        i = j;
    }
    let last = &beads[beads.len() - 1].material;
    let (right, target) = match problem.protected {
        Protected::Wall(m) => (
            Some(EndFile::Wall(LawFile {
                restitution: own(last, &m),
                ..material_law(&m)
            })),
            None,
        ),
        Protected::Target {
            mass,
            material,
            spring,
        } => (
            None,
            Some(TargetFile {
                mass: Some(mass),
                material: Some(material_file(&material)),
                diameter: None,
                p: None,
                eta: None,
                // A scene's spring is > 0; the design file's 0 is a free body, no spring.
                spring: (spring > 0.0).then_some(spring),
                restitution: own(last, &material),
            }),
        ),
    };
    let duration = 3.0 * e.peak_time;
    let scene = SceneFile {
        name: Some("best-design".into()),
        description: Some(describe(beads)),
        chain: ChainFile {
            interface: None,
            left: None,
            right,
            sections,
            outer: None,
            restitution: imp.restitution,
            gravity: None,
        },
        striker: Some(StrikerFile {
            end: StrikerEnd::Left,
            mass: None,
            speed: imp.speed,
            p: None,
            eta: None,
            material: Some(material_file(&imp.striker.material)),
            diameter: Some(imp.striker.diameter),
            restitution: own(&imp.striker.material, &beads[0].material),
        }),
        target,
        initial: Vec::new(),
        // The run of the reported numbers: the search's method at the finer step.
        integrator: Some(IntegratorFile {
            method: Some(settings.method),
            dt: Some(e.dt),
            events: Some(settings.events),
            ..Default::default()
        }),
        run: RunFile {
            duration,
            output_interval: duration / 1000.0,
            horizon: None,
        },
        regions: Vec::new(),
        output: None,
        design: Some(DesignRecordFile {
            accuracy: problem.file.search.accuracy,
            steps_per_contact: 2.0
                * grainchain_engine::protector::steps_for_accuracy(problem.file.search.accuracy),
            peak_force: e.peak_force,
            peak_force_error: est.peak_error,
            peak_bound: est.bound,
            impulse: e.impulse,
            impulse_error: est.impulse_error,
            duration: e.duration,
            duration_error: est.duration_error,
        }),
    };
    let text = toml::to_string(&scene).map_err(|e| Error::Design(DesignFailure::BestToml(e)))?;
    Ok(format!(
        "# The best design of {} (grainchain design), as an SI scene: run it with\n\
         # `grainchain run best.toml`; summary.json's `load` holds the force on the protected face.\n\n{text}",
        problem.path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::with_error;

    /// The error to one significant digit (two from 1.0 to 1.99), rounded up; the value to the
    /// same place; a bound rounded down to it after `≥`; no error: not final.
    #[test]
    fn numbers_carry_the_digits_their_error_allows() {
        assert_eq!(
            with_error(1.08123, Some(2.6e-4), false, 1.0),
            "1.0812 ± 0.0003"
        );
        assert_eq!(
            with_error(10.561936650056788, Some(7.66e-6), false, 1.0),
            "10.561937 ± 0.000008"
        );
        assert_eq!(
            with_error(4.0662264, Some(0.010758), false, 1.0),
            "4.066 ± 0.011"
        );
        assert_eq!(with_error(5.9377, Some(0.026359), true, 1.0), "≥ 5.93");
        assert_eq!(with_error(16.2, Some(3.2), true, 1.0), "≥ 16");
        assert_eq!(with_error(16.0, Some(3.2), true, 1.0), "≥ 16");
        assert_eq!(with_error(123.4, Some(12.0), false, 1.0), "123 ± 12");
        assert_eq!(with_error(123.4, Some(12.5), false, 1.0), "123 ± 13");
        assert_eq!(
            with_error(4.1e-3, Some(2.0e-8), false, 1e3),
            "4.10000 ± 0.00002"
        );
        assert_eq!(with_error(2.5, Some(0.0), false, 1.0), "2.5 ± 0");
        assert_eq!(with_error(2.5, None, false, 1.0), "not final");
    }
}
