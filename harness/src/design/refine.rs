//! The gradient refinement of a design (issue 41, item 4): its beads' diameters made continuous
//! within an interval and moved by a bounded quasi-Newton method to lower the objective, under
//! the file's mass, length and order limits.
//!
//! **The method.** L-BFGS with a More-Thuente line search (the `argmin` crate) on the objective
//! the search minimises ([`super::search::objective`]: the worst case over the file's speeds of
//! the weighted ratios to the reference column), its gradient from
//! `protector::gradients` (exact for the discrete run: one sweep back through it) at the worst speed. The
//! interval is kept by a change of variable, `d = lo + (hi - lo) (1 + sin x) / 2` (every real
//! `x` a diameter inside it, no bound the line search can cross); the mass and length limits
//! and the graded order by a quadratic penalty, `MU` times the starting objective times the
//! squared relative excess. The refinement returns the best point that meets every limit
//! exactly ([`DesignSpec::violation`]) among all it evaluated, so a penalty that lets a step
//! overshoot never reaches the report.
//!
//! **What it cannot do.** The objective is piecewise smooth: where the largest force moves from
//! one pulse to another, or a speed overtakes another as the worst, its gradient jumps, and a
//! quasi-Newton method stops at such a kink (the line search fails or the gradient's norm does
//! not fall). That is a local refinement of a design the genetic search found, not a global
//! search.

use super::file::DesignSpec;
use super::search::{objective, settings, weights};
use crate::error::{DesignFailure, Error};
use argmin::core::{CostFunction, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use grainchain_engine::protector::{gradients, Bead, Evaluation, Gradients};
use std::f64::consts::FRAC_PI_2;
use std::sync::Mutex;

/// The weight of the limits' penalty, relative to the starting objective: a relative excess of
/// 1 % costs as much as the whole objective, far more than any gain a step can find by it.
const MU: f64 = 1e4;

/// How far inside the interval's ends the method starts, in the changed variable: `1 - cos
/// 0.045 = 0.1 %` of the half interval.
const INSIDE: f64 = 0.045;

/// L-BFGS's memory (pairs kept).
const MEMORY: usize = 7;

/// A refinement's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Refined {
    /// The design as found by the search.
    pub start: Vec<Bead>,
    /// Its objective.
    pub before: f64,
    /// The refined design (the start if nothing better met every limit).
    pub beads: Vec<Bead>,
    /// Its objective.
    pub after: f64,
    /// The diameters' interval, m.
    pub range: [f64; 2],
    /// L-BFGS iterations taken.
    pub iterations: u64,
    /// Runs with gradients (one per speed per point evaluated).
    pub runs: usize,
    /// Why it stopped (argmin's termination, or the line search's failure at a kink).
    pub stopped: String,
}

/// The problem argmin sees: the change of variable, the objective with its penalty, a cache of
/// the last point (argmin asks for the cost and the gradient of the same point separately; one
/// run gives both) and the best point that meets every limit.
struct Problem<'a> {
    spec: &'a DesignSpec,
    start: &'a [Bead],
    reference: &'a [Evaluation],
    range: [f64; 2],
    scale: f64,
    seen: &'a Seen,
}

/// A point, its cost (with the penalty) and its gradient.
type Point = (Vec<f64>, f64, Vec<f64>);

/// What the refinement keeps across argmin's calls.
struct Seen {
    last: Mutex<Option<Point>>,
    best: Mutex<(f64, Vec<f64>)>,
    runs: Mutex<usize>,
}

impl Problem<'_> {
    fn beads(&self, x: &[f64]) -> Vec<Bead> {
        problem_beads(self.start, self.range, x)
    }

    /// The objective with its penalty and its gradient in `x`, and the objective alone.
    fn evaluate(&self, x: &[f64]) -> Result<(f64, Vec<f64>), argmin::core::Error> {
        if let Some((p, c, g)) = self.seen.last.lock().expect("not poisoned").as_ref() {
            if p == x {
                return Ok((*c, g.clone()));
            }
        }
        let beads = self.beads(x);
        let spec = self.spec;
        let s = settings(spec);
        let runs: Vec<Gradients> = spec
            .impacts
            .iter()
            .map(|imp| gradients(&beads, imp, &spec.protected, &s))
            .collect::<Result<_, _>>()
            .map_err(|e| argmin::core::Error::msg(e.to_string()))?;
        *self.seen.runs.lock().expect("not poisoned") += runs.len();
        let evals: Vec<Evaluation> = runs.iter().map(|g| g.evaluation).collect();
        let obj = objective(spec, &evals, &[], self.reference);
        // The gradient of the worst speed's term.
        let (w_peak, w_impulse, w_duration) = weights(spec);
        let term = |e: &Evaluation, r: &Evaluation| {
            w_peak * ratio(e.peak_force, r.peak_force)
                + w_impulse * ratio(e.impulse, r.impulse)
                + w_duration * ratio(e.duration, r.duration)
        };
        let worst = (0..evals.len())
            .max_by(|&a, &b| {
                term(&evals[a], &self.reference[a]).total_cmp(&term(&evals[b], &self.reference[b]))
            })
            .expect("a speed");
        let (gr, r) = (&runs[worst], &self.reference[worst]);
        let [lo, hi] = self.range;
        let mut grad: Vec<f64> = (0..beads.len())
            .map(|i| {
                let d = w_peak * gr.peak.diameter[i] / nonzero(r.peak_force)
                    + w_impulse * gr.impulse.diameter[i] / nonzero(r.impulse)
                    + w_duration * gr.duration.diameter[i] / nonzero(r.duration);
                d * (hi - lo) * 0.5 * x[i].cos()
            })
            .collect();
        // The penalty on the limits, relative excesses squared.
        let mut cost = obj;
        let c = &spec.file.constraints;
        let mut limit = |total: f64, max: Option<f64>, per_bead: &dyn Fn(usize) -> f64| {
            if let Some(max) = max.filter(|&m| total > m) {
                let excess = total / max - 1.0;
                cost += MU * self.scale * excess * excess;
                for (i, g) in grad.iter_mut().enumerate() {
                    *g += MU * self.scale * 2.0 * excess / max
                        * per_bead(i)
                        * (hi - lo)
                        * 0.5
                        * x[i].cos();
                }
            }
        };
        let mass: f64 = beads.iter().map(Bead::mass).sum();
        limit(mass, c.max_mass, &|i| {
            3.0 * beads[i].mass() / beads[i].diameter
        });
        let length: f64 = beads.iter().map(|b| b.diameter).sum();
        limit(length, c.max_length, &|_| 1.0);
        if spec.file.space.order == super::file::Order::Graded {
            for i in 0..beads.len() - 1 {
                let (a, b) = (beads[i].mass(), beads[i + 1].mass());
                if b > a {
                    let excess = (b - a) / a;
                    cost += MU * self.scale * excess * excess;
                    let k = MU * self.scale * 2.0 * excess / a;
                    let dd = |j: usize| {
                        (hi - lo) * 0.5 * x[j].cos() * 3.0 * beads[j].mass() / beads[j].diameter
                    };
                    grad[i + 1] += k * dd(i + 1);
                    grad[i] -= k * b / a * dd(i);
                }
            }
        }
        if spec.violation(&beads).is_none() && evals.iter().all(|e| !e.given_up) {
            let mut best = self.seen.best.lock().expect("not poisoned");
            if obj < best.0 {
                *best = (obj, x.to_vec());
            }
        }
        *self.seen.last.lock().expect("not poisoned") = Some((x.to_vec(), cost, grad.clone()));
        Ok((cost, grad))
    }
}

/// The beads of `start` with the diameters of `x` in `range` (the change of variable).
fn problem_beads(start: &[Bead], range: [f64; 2], x: &[f64]) -> Vec<Bead> {
    let [lo, hi] = range;
    start
        .iter()
        .zip(x)
        .map(|(b, &x)| Bead {
            diameter: (lo + (hi - lo) * 0.5 * (1.0 + x.sin())).clamp(lo, hi),
            ..*b
        })
        .collect()
}

fn ratio(a: f64, b: f64) -> f64 {
    if a == 0.0 && b == 0.0 {
        0.0
    } else {
        a / b
    }
}

fn nonzero(x: f64) -> f64 {
    if x == 0.0 {
        f64::INFINITY
    } else {
        x
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, x: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        Ok(self.evaluate(x)?.0)
    }
}

impl Gradient for Problem<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, x: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        Ok(self.evaluate(x)?.1)
    }
}

/// Refine `beads` (a design of `spec`, its objective against the reference's evaluations
/// `reference`) with diameters in `range` for at most `iterations` L-BFGS iterations.
pub fn refine(
    spec: &DesignSpec,
    beads: &[Bead],
    reference: &[Evaluation],
    range: [f64; 2],
    iterations: u64,
) -> Result<Refined, Error> {
    let [lo, hi] = range;
    let fail = |why: String| {
        Error::Design(DesignFailure::Evaluation {
            file: spec.path.clone(),
            source: grainchain_engine::protector::DesignError::Bad {
                what: "refinement".into(),
                problem: why,
            },
        })
    };
    let x0: Vec<f64> = beads
        .iter()
        .map(|b| {
            if hi > lo {
                (2.0 * (b.diameter - lo) / (hi - lo) - 1.0)
                    .clamp(-1.0, 1.0)
                    .asin()
            } else {
                0.0
            }
        })
        .collect();
    let seen = Seen {
        last: Mutex::new(None),
        best: Mutex::new((f64::INFINITY, x0.clone())),
        runs: Mutex::new(0),
    };
    let mut problem = Problem {
        spec,
        start: beads,
        reference,
        range,
        scale: 1.0,
        seen: &seen,
    };
    // The start meets every limit (the search's designs do), so its cost is its objective:
    // the penalty's scale, and the number to beat.
    let (before, _) = problem.evaluate(&x0).map_err(|e| fail(e.to_string()))?;
    problem.scale = before;
    *seen.last.lock().expect("not poisoned") = None;
    let before_exact = before;
    // The search's diameters are the catalogue's, often the interval's ends, where the change
    // of variable is flat (`cos x = 0`): the method starts a little inside (`INSIDE` radians,
    // 0.1 % of the interval), the start's own objective being the number to beat.
    let inside: Vec<f64> = x0
        .iter()
        .map(|x| x.clamp(-FRAC_PI_2 + INSIDE, FRAC_PI_2 - INSIDE))
        .collect();
    let (iters, stopped) = if hi > lo && iterations > 0 {
        let solver = LBFGS::new(MoreThuenteLineSearch::new(), MEMORY);
        match Executor::new(problem, solver)
            .configure(|s| s.param(inside).max_iters(iterations))
            .run()
        {
            Ok(r) => (
                r.state().get_iter(),
                r.state()
                    .get_termination_reason()
                    .map_or("ended".into(), |t| t.to_string()),
            ),
            Err(e) => (0, format!("stopped: {e}")),
        }
    } else {
        (0, "no room: the interval is one diameter".into())
    };
    // argmin's words for a line search that found no descent: the objective's kink.
    let stopped = if stopped.contains("descent direction") {
        "no descent along the quasi-Newton direction (a kink of the objective)".to_string()
    } else {
        stopped
    };
    let (after, x) = seen.best.lock().expect("not poisoned").clone();
    let (after, refined) = if after.is_finite() && after < before_exact {
        (after, problem_beads(beads, range, &x))
    } else {
        (before_exact, beads.to_vec())
    };
    let runs = *seen.runs.lock().expect("not poisoned");
    Ok(Refined {
        start: beads.to_vec(),
        before: before_exact,
        beads: refined,
        after,
        range,
        iterations: iters,
        runs,
        stopped,
    })
}

/// The name of the refinement's CSV: each refined design's beads.
pub const REFINED_CSV: &str = "refined.csv";

/// A row of [`REFINED_CSV`]: one bead of a refined design, its diameter before and after.
#[derive(serde::Serialize)]
pub struct RefinedRow {
    rank: usize,
    bead: usize,
    material: &'static str,
    #[serde(serialize_with = "exponent")]
    diameter_before_m: f64,
    #[serde(serialize_with = "exponent")]
    diameter_after_m: f64,
}

/// `x` in exponent form, every digit that reads back to it (`6.1e-3`).
fn exponent<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&format_args!("{x:e}"))
}

/// The refinement's outputs: [`REFINED_CSV`]'s rows and DESIGN.md's section.
pub struct Refinement {
    /// Each refined design's beads, before and after.
    pub rows: Vec<RefinedRow>,
    /// DESIGN.md's section.
    pub section: String,
}

/// Refine the best `designs` of `found` (the search's ranking, best first): [`REFINED_CSV`]'s
/// rows and the DESIGN.md section, or `None` without `[refine]`.
pub fn report(
    spec: &DesignSpec,
    found: &[Vec<Bead>],
    reference: &[Evaluation],
    (threads, phases): (usize, &super::phases::Phases),
) -> Result<Option<Refinement>, Error> {
    use rayon::prelude::*;
    use std::fmt::Write as _;
    let Some(key) = &spec.file.refine else {
        return Ok(None);
    };
    let range = spec.refine_range.expect("checked with the table");
    let take = key.designs.min(found.len());
    let pool = grainchain_engine::thread_pool(threads, take).map_err(|e| {
        Error::Design(DesignFailure::Evaluation {
            file: spec.path.clone(),
            source: grainchain_engine::protector::DesignError::Bad {
                what: "threads".into(),
                problem: e.to_string(),
            },
        })
    })?;
    let bar = phases.bar(take as u64, "refinement: designs refined");
    let refined: Vec<Refined> = pool.install(|| {
        found[..take]
            .par_iter()
            .map(|b| {
                let r = refine(spec, b, reference, range, key.iterations);
                bar.inc(1);
                r
            })
            .collect::<Result<_, _>>()
    })?;
    bar.finish_and_clear();
    let rows: Vec<RefinedRow> = refined
        .iter()
        .enumerate()
        .flat_map(|(r, x)| {
            x.start
                .iter()
                .zip(&x.beads)
                .enumerate()
                .map(move |(i, (a, b))| RefinedRow {
                    rank: r + 1,
                    bead: i + 1,
                    material: a.material.name,
                    diameter_before_m: a.diameter,
                    diameter_after_m: b.diameter,
                })
        })
        .collect();
    let mut md = String::new();
    let _ = writeln!(md, "\n## Refinement by gradients\n");
    let _ = writeln!(
        md,
        "The best {take} designs with every diameter free in [{}, {}] mm, refined by L-BFGS \
         (argmin) on the objective with its exact gradient (`protector::gradients`), at most {} \
         iterations, under the same limits; the objective and worst-case peak at the search's \
         settings (single runs, as the search scores). Each refined design's diameters: `{}`.\n",
        range[0] * 1e3,
        range[1] * 1e3,
        key.iterations,
        REFINED_CSV
    );
    let _ = writeln!(
        md,
        "| rank | objective before | after | change | worst peak before (N) | after (N) | mass after (g) | iterations | runs with gradients | stopped |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|");
    let s = settings(spec);
    let worst_peak = |beads: &[Bead]| -> Result<f64, Error> {
        let mut worst = 0.0f64;
        for imp in &spec.impacts {
            let e = grainchain_engine::protector::evaluate(beads, imp, &spec.protected, &s)
                .map_err(|source| {
                    Error::Design(DesignFailure::Evaluation {
                        file: spec.path.clone(),
                        source,
                    })
                })?;
            worst = worst.max(e.peak_force);
        }
        Ok(worst)
    };
    for (r, x) in refined.iter().enumerate() {
        let _ = writeln!(
            md,
            "| {} | {:.5} | {:.5} | {:+.2} % | {:.4} | {:.4} | {:.3} | {} | {} | {} |",
            r + 1,
            x.before,
            x.after,
            100.0 * (x.after / x.before - 1.0),
            worst_peak(&x.start)?,
            worst_peak(&x.beads)?,
            x.beads.iter().map(Bead::mass).sum::<f64>() * 1e3,
            x.iterations,
            x.runs,
            x.stopped
        );
    }
    let mut order: Vec<usize> = (0..refined.len()).collect();
    order.sort_by(|&a, &b| refined[a].after.total_cmp(&refined[b].after));
    let moved = order.iter().enumerate().any(|(i, &r)| i != r);
    let _ = writeln!(
        md,
        "\nRanking after refinement: {} ({}).",
        order
            .iter()
            .map(|r| format!("#{}", r + 1))
            .collect::<Vec<_>>()
            .join(", "),
        if moved {
            "the refinement moved the ranking"
        } else {
            "the same order as the search's"
        }
    );
    Ok(Some(Refinement { rows, section: md }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::file::DesignFile;
    use crate::design::search::reference;

    fn spec(constraints: &str) -> DesignSpec {
        let text = format!(
            r#"
[space]
beads = 8
sections = 4
materials = ["steel", "ptfe"]
diameters = [0.005, 0.007]
{constraints}
[load]
striker = {{ material = "steel", diameter = 0.006 }}
speeds = [1.0]
wall = "steel"
"#
        );
        let file: DesignFile = toml::from_str(&text).unwrap();
        DesignSpec::check("refine-test.toml".into(), file).unwrap()
    }

    /// The refinement lowers the objective of a design of the catalogue, keeps every diameter
    /// in the interval and every limit, and says what it did.
    #[test]
    fn refinement_lowers_the_objective_within_the_limits() {
        let spec = spec("[constraints]\nmax_mass = 0.004\n");
        let r = reference(&spec).unwrap();
        // steel 5 mm, ptfe 7 mm, steel 5 mm, ptfe 5 mm (choices: materials first).
        let start = spec.beads(&[0, 3, 0, 2]);
        assert!(spec.violation(&start).is_none());
        let out = refine(&spec, &start, &r, [0.005, 0.007], 15).unwrap();
        eprintln!(
            "{} -> {} in {} iterations, {} runs: {}",
            out.before, out.after, out.iterations, out.runs, out.stopped
        );
        assert!(out.after <= out.before);
        assert!(spec.violation(&out.beads).is_none());
        assert!(out
            .beads
            .iter()
            .all(|b| (0.005..=0.007).contains(&b.diameter)));
        // The number reported is the refined design's objective.
        let evals: Vec<Evaluation> = spec
            .impacts
            .iter()
            .map(|imp| {
                grainchain_engine::protector::evaluate(
                    &out.beads,
                    imp,
                    &spec.protected,
                    &settings(&spec),
                )
                .unwrap()
            })
            .collect();
        let again = objective(&spec, &evals, &[], &r);
        // The run with derivatives and the evaluation agree to rounding (1e-12 relative).
        assert!(
            (again - out.after).abs() <= 1e-12 * again,
            "{again} {}",
            out.after
        );
        assert!(out.after < out.before, "no progress: {out:?}");
    }

    /// A bad `[refine]` table is an error naming its key.
    #[test]
    fn bad_refine_tables_name_their_key() {
        let text = |extra: &str| {
            format!(
                r#"
[space]
beads = 4
materials = ["steel"]
diameters = [0.006]
[load]
striker = {{ material = "steel", diameter = 0.006 }}
speeds = [1.0]
wall = "steel"
{extra}
"#
            )
        };
        for (extra, key) in [
            ("[refine]\n", "refine.diameters"),
            ("[refine]\ndiameters = [0.007, 0.005]\n", "refine.diameters"),
            ("[refine]\ndiameters = [0.0, 0.005]\n", "refine.diameters"),
            (
                "[refine]\ndiameters = [0.004, 0.008]\ndesigns = 0\n",
                "refine.designs",
            ),
            (
                "[refine]\ndiameters = [0.004, 0.008]\niterations = 0\n",
                "refine.iterations",
            ),
            (
                "[objective]\nminimize = \"duration\"\n[refine]\ndiameters = [0.004, 0.008]\n",
                "objective.minimize",
            ),
            // Exactly two numbers (issue 50: a third was dropped without a word).
            (
                "[refine]\ndiameters = [0.004, 0.006, 0.008]\n",
                "refine.diameters",
            ),
            ("[refine]\ndiameters = [0.004]\n", "refine.diameters"),
        ] {
            let file: DesignFile = toml::from_str(&text(extra)).unwrap();
            let e = DesignSpec::check("bad.toml".into(), file).unwrap_err();
            let said = e.to_string();
            assert!(
                said.contains(key) && said.contains("bad.toml"),
                "{extra}: {said}"
            );
        }
        let file: DesignFile =
            toml::from_str(&text("[refine]\ndiameters = [0.004, 0.008]\n")).unwrap();
        let spec = DesignSpec::check("good.toml".into(), file).unwrap();
        assert_eq!(spec.refine_range, Some([0.004, 0.008]));
    }
}
