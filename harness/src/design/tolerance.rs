//! Manufacturing tolerances (`[tolerances]` of the design file): how far a design's peak force
//! spreads when each bead's diameter, Young's modulus and density and the striker's speed are
//! off their nominal values by a relative standard deviation each.
//!
//! Two answers, which check each other:
//!
//! - **First order** ([`first_order`]), from the peak's exact derivatives
//!   ([`grainchain_engine::protector::gradients`]): `sigma_1^2 = sum_i (dP/dd_i sigma_d d_i)^2 +
//!   (dP/dE_i sigma_E E_i)^2 + (dP/drho_i sigma_rho rho_i)^2 + (dP/dv sigma_v v)^2`, every term
//!   kept ([`Term`]) so the beads and properties that dominate can be named. It is the spread of
//!   the peak's linearisation, right while the tolerances are small against the scale on which
//!   the peak bends (a pulse overtaking another, a contact that opens elsewhere); its 95th
//!   percentile is `P + 1.645 sigma_1`.
//! - **Monte Carlo** ([`monte_carlo`]): `samples` columns, every bead drawn independently
//!   (its diameter, `E` and `rho` each times `1 + sigma z`, `z` standard normal) and the speed
//!   once per column, evaluated as the design is. Every column is drawn first from one
//!   ChaCha8 stream of the seed ([`draw`]), then all are evaluated on the threads, results in
//!   order: the same bits at every thread count. Three numbers are drawn per bead and one for the
//!   speed whatever the tolerances are (a zero one multiplies by 1), so the stream's layout does
//!   not depend on which are given, and every design of a file is drawn from the same seed
//!   (common random numbers: two designs' spreads differ by their columns, less by the draws).
//!
//! `z` is cut at [`Z_MAX`] = 4 (redrawn beyond, a chance of 6.3e-5 per draw, which moves a
//! standard deviation by under 0.1 %), so with a tolerance of at most [`MAX_SIGMA`] every factor
//! lies in [0.2, 1.8]: a perturbed bead is a bead, and the design file's check
//! (`DesignSpec::check`) has already proved every such bead valid and within the step limit.
//!
//! Each column is evaluated with [`evaluate`] on a pool of its own, as
//! [`grainchain_engine::protector::evaluate_many`] evaluates a batch (which takes one impact for
//! every design; here each column has its own speed).

use super::draws_journal::{self, DrawsJournal};
use grainchain_engine::analysis::statistics::{
    mean_interval, mean_sd, quantile_interval, quantile_sorted, Z95,
};
use grainchain_engine::protector::{
    evaluate, gradients, Bead, Derivatives, DesignError, Evaluation, Gradients, Impact, Protected,
    Settings,
};
use indicatif::ProgressBar;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// The largest relative standard deviation of a tolerance: with `z` cut at [`Z_MAX`], every
/// factor `1 + sigma z` stays in `[1 - 4 sigma, 1 + 4 sigma]`, at least 0.2 here, so a perturbed
/// diameter, modulus and density stay positive (a bead stays a bead). Tolerances of real beads
/// and materials are far below it (a grade-100 ball is good to 0.1 %, a modulus to a few %),
/// and the first-order answer means little at such a spread anyway.
pub const MAX_SIGMA: f64 = 0.2;

/// Where the standard normal draws are cut (redrawn beyond): at 4 a draw is redrawn with a
/// chance of 6.3e-5.
pub const Z_MAX: f64 = 4.0;

/// The standard normal's 95th percentile, to the digits a tolerance is known to: a first-order
/// 95th percentile is `P + 1.645 sigma_1`.
pub const P95_Z: f64 = 1.645;

/// The fewest Monte Carlo columns: at 100 the standard deviation is known to about 7 % (its
/// relative standard error is `1 / sqrt(2 (n - 1))` for a normal spread).
pub const MIN_SAMPLES: usize = 100;

/// The checked tolerances: relative standard deviations (0.01 is 1 %), the Monte Carlo's
/// columns and seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Of each bead's diameter.
    pub diameter: f64,
    /// Of each bead's Young's modulus.
    pub young: f64,
    /// Of each bead's density.
    pub density: f64,
    /// Of the striker's speed (one draw per column).
    pub speed: f64,
    /// Monte Carlo columns.
    pub samples: usize,
    /// The Monte Carlo's seed.
    pub seed: u64,
}

/// A property a tolerance is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// A bead's diameter.
    Diameter,
    /// A bead's Young's modulus.
    Young,
    /// A bead's density.
    Density,
    /// The striker's speed.
    Speed,
}

impl Property {
    /// The bead properties, in the order of [`FirstOrder::terms`].
    pub const BEAD: [Property; 3] = [Property::Diameter, Property::Young, Property::Density];

    /// Its name in tables (the design file's key).
    pub fn name(self) -> &'static str {
        match self {
            Property::Diameter => "diameter",
            Property::Young => "E",
            Property::Density => "rho",
            Property::Speed => "speed",
        }
    }
}

/// One term of the first-order variance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term {
    /// The bead (0-based, struck end first); `None` for the speed.
    pub bead: Option<usize>,
    /// Which of its properties.
    pub property: Property,
    /// `(dP/dx sigma_x x)^2`, N^2.
    pub variance: f64,
}

/// The first-order spread of a design's peak.
#[derive(Clone, Debug, PartialEq)]
pub struct FirstOrder {
    /// The nominal peak, N.
    pub peak: f64,
    /// `sigma_1`, N.
    pub sd: f64,
    /// Every term: per bead its diameter, modulus and density (in [`Property::BEAD`]'s order),
    /// then the speed.
    pub terms: Vec<Term>,
}

impl FirstOrder {
    /// `P + 1.645 sigma_1`, N.
    pub fn p95(&self) -> f64 {
        self.peak + P95_Z * self.sd
    }

    /// The share of the variance of the terms that `keep` keeps (0 when there is no spread).
    fn share(&self, keep: impl Fn(&Term) -> bool) -> f64 {
        let total = self.sd * self.sd;
        if total > 0.0 {
            self.terms
                .iter()
                .filter(|t| keep(t))
                .map(|t| t.variance)
                .sum::<f64>()
                / total
        } else {
            0.0
        }
    }

    /// Bead `i`'s share of the variance (its three properties).
    pub fn bead_share(&self, i: usize) -> f64 {
        self.share(|t| t.bead == Some(i))
    }

    /// A property's share of the variance (over every bead).
    pub fn property_share(&self, p: Property) -> f64 {
        self.share(|t| t.property == p)
    }

    /// The `k` largest terms, largest first (ties by position in the column).
    pub fn top(&self, k: usize) -> Vec<Term> {
        let mut t: Vec<Term> = self
            .terms
            .iter()
            .copied()
            .filter(|t| t.variance > 0.0)
            .collect();
        t.sort_by(|a, b| b.variance.total_cmp(&a.variance));
        t.truncate(k);
        t
    }
}

/// The first-order spread of a peak `peak` of `beads` struck at `speed`, from the peak's
/// derivatives `d`.
pub fn first_order(
    beads: &[Bead],
    speed: f64,
    peak: f64,
    d: &Derivatives,
    tol: &Tolerances,
) -> FirstOrder {
    let mut terms = Vec::with_capacity(3 * beads.len() + 1);
    let sq = |x: f64| x * x;
    for (i, b) in beads.iter().enumerate() {
        let m = &b.material;
        for (property, v) in [
            (
                Property::Diameter,
                d.diameter[i] * tol.diameter * b.diameter,
            ),
            (Property::Young, d.young[i] * tol.young * m.young),
            (Property::Density, d.density[i] * tol.density * m.density),
        ] {
            terms.push(Term {
                bead: Some(i),
                property,
                variance: sq(v),
            });
        }
    }
    terms.push(Term {
        bead: None,
        property: Property::Speed,
        variance: sq(d.speed * tol.speed * speed),
    });
    let sd = terms.iter().map(|t| t.variance).sum::<f64>().sqrt();
    FirstOrder { peak, sd, terms }
}

/// A standard normal number cut at [`Z_MAX`] (redrawn beyond).
fn z(rng: &mut ChaCha8Rng) -> f64 {
    loop {
        let z: f64 = rng.sample(StandardNormal);
        if z.abs() <= Z_MAX {
            return z;
        }
    }
}

/// Common random numbers: the factors of `count` Monte Carlo columns of a given number of beads,
/// drawn first from one ChaCha8 stream (stream `stream` of `tol.seed`; per column each bead's
/// diameter, modulus and density factor `1 + sigma z` in turn, then the speed's), and then applied
/// to any column of that many beads. Every candidate of a search is perturbed by the same draws,
/// so two candidates' statistics differ by their columns, not by sampling noise.
#[derive(Clone, Debug, PartialEq)]
pub struct Draws {
    beads: usize,
    /// Per column, per bead: the diameter's, modulus's and density's factors.
    factors: Vec<[f64; 3]>,
    /// Per column: the speed's factor.
    speed: Vec<f64>,
}

/// The stream of the draws a search screens and confirms its candidates on.
pub const SEARCH_STREAM: u64 = 0;

/// The stream of the fresh draws the winners are judged on after the search (none of which the
/// search saw).
pub const FRESH_STREAM: u64 = 1;

impl Draws {
    /// `count` columns of `beads` beads.
    pub fn new(beads: usize, tol: &Tolerances, count: usize, stream: u64) -> Draws {
        let mut rng = ChaCha8Rng::seed_from_u64(tol.seed);
        rng.set_stream(stream);
        let mut factors = Vec::with_capacity(beads * count);
        let mut speed = Vec::with_capacity(count);
        for _ in 0..count {
            for _ in 0..beads {
                let (zd, ze, zr) = (z(&mut rng), z(&mut rng), z(&mut rng));
                factors.push([
                    1.0 + tol.diameter * zd,
                    1.0 + tol.young * ze,
                    1.0 + tol.density * zr,
                ]);
            }
            speed.push(1.0 + tol.speed * z(&mut rng));
        }
        Draws {
            beads,
            factors,
            speed,
        }
    }

    /// The number of columns.
    pub fn len(&self) -> usize {
        self.speed.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.speed.is_empty()
    }

    /// Column `j` of `beads` (as many as the draws were made for) struck as `impact`.
    pub fn column(&self, j: usize, beads: &[Bead], impact: &Impact) -> (Vec<Bead>, Impact) {
        assert_eq!(
            beads.len(),
            self.beads,
            "draws made for another column length"
        );
        let f = &self.factors[j * self.beads..(j + 1) * self.beads];
        let column = beads
            .iter()
            .zip(f)
            .map(|(b, f)| {
                let mut p = *b;
                p.diameter *= f[0];
                p.material.young *= f[1];
                p.material.density *= f[2];
                p
            })
            .collect();
        let speed = impact.speed * self.speed[j];
        (
            column,
            Impact {
                speed,
                ..impact.clone()
            },
        )
    }
}

/// The Monte Carlo's columns: `tol.samples` perturbed copies of `beads` with their impacts, the
/// search's stream of [`Draws`].
pub fn draw(beads: &[Bead], impact: &Impact, tol: &Tolerances) -> Vec<(Vec<Bead>, Impact)> {
    let d = Draws::new(beads.len(), tol, tol.samples, SEARCH_STREAM);
    (0..d.len()).map(|j| d.column(j, beads, impact)).collect()
}

/// The Monte Carlo's summary of the peak force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonteCarlo {
    /// The mean, N.
    pub mean: f64,
    /// The sample standard deviation (divided by `samples - 1`), N.
    pub sd: f64,
    /// The 95th percentile, N: linear interpolation between the order statistics (Hyndman and
    /// Fan's type 7, numpy's default `percentile`): with the peaks sorted `x_0 <= ... <= x_{n-1}`
    /// and `h = 0.95 (n - 1)`, `x_floor(h) + (h - floor(h)) (x_floor(h)+1 - x_floor(h))`.
    pub p95: f64,
    /// Columns evaluated.
    pub samples: usize,
    /// Columns whose peak is only a lower bound (the run reached its time cap before the stop
    /// rule proved it); they count in the numbers above with that bound.
    pub bounds: usize,
}

/// Summarise the peaks of evaluated columns.
pub fn summarise(evals: &[Evaluation]) -> MonteCarlo {
    let mut peaks: Vec<f64> = evals.iter().map(|e| e.peak_force).collect();
    let (mean, sd) = mean_sd(&peaks);
    peaks.sort_by(f64::total_cmp);
    MonteCarlo {
        mean,
        sd,
        p95: quantile_sorted(&peaks, 0.95),
        samples: evals.len(),
        bounds: evals.iter().filter(|e| !e.complete).count(),
    }
}

/// The Monte Carlo of a design ([`draw`], then every column evaluated with `settings` on
/// `threads` threads, in order).
pub fn monte_carlo(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    tol: &Tolerances,
    threads: usize,
) -> Result<MonteCarlo, DesignError> {
    let draws = Draws::new(beads.len(), tol, tol.samples, SEARCH_STREAM);
    let evals = evaluate_draws_counted(
        beads,
        impact,
        protected,
        settings,
        &draws,
        (threads, &ProgressBar::hidden(), None),
    )?;
    Ok(summarise(&evals))
}

/// Every draw of `draws` applied to `beads` at `impact` ([`evaluate_draws`]), `bar` moving by
/// one as each finishes.
pub fn evaluate_draws_counted(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    draws: &Draws,
    (threads, bar, journal): (usize, &ProgressBar, Option<&DrawsJournal>),
) -> Result<Vec<Evaluation>, DesignError> {
    evaluate_draws(
        beads,
        impact,
        protected,
        settings,
        (draws, 0..draws.len()),
        (threads, Some(bar)),
        journal,
    )
}

/// A statistic of the peak over Monte Carlo columns: what a robust objective minimises.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Statistic {
    /// The mean.
    Mean,
    /// A quantile in (0, 1), type 7 ([`quantile_sorted`]).
    Quantile(f64),
}

impl Statistic {
    /// Its name in tables: `mean`, `p95`, `q0.99`.
    pub fn name(self) -> String {
        match self {
            Statistic::Mean => "mean".into(),
            Statistic::Quantile(q) if (q * 100.0).fract() == 0.0 => format!("p{}", q * 100.0),
            Statistic::Quantile(q) => format!("q{q}"),
        }
    }

    /// Its value on peaks sorted in increasing order.
    pub fn of_sorted(self, s: &[f64]) -> f64 {
        match self {
            Statistic::Mean => mean_sd(s).0,
            Statistic::Quantile(q) => quantile_sorted(s, q),
        }
    }

    /// Its 95 % confidence interval on peaks sorted in increasing order
    /// ([`mean_interval`], [`quantile_interval`]).
    pub fn interval(self, s: &[f64]) -> (f64, f64) {
        match self {
            Statistic::Mean => mean_interval(s, Z95),
            Statistic::Quantile(q) => quantile_interval(s, q, Z95),
        }
    }

    /// Whether the statistic of `n` peaks is already known to be at least `t`, when `above` of
    /// them are known to be at least `t` and the known ones sum to at least `sum`: for a
    /// quantile, once `n - floor(q (n - 1))` peaks are (the order statistic below its position,
    /// and so the interpolated quantile, is then at least `t`); for the mean, once `sum >= n t`.
    pub fn settled_above(self, n: usize, above: usize, sum: f64, t: f64) -> bool {
        match self {
            Statistic::Mean => sum >= n as f64 * t,
            Statistic::Quantile(q) => {
                let below = (q * (n - 1) as f64).floor() as usize;
                above >= n - below
            }
        }
    }
}

/// A statistic of a design's peak over Monte Carlo columns at one impact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampled {
    /// The statistic, N; when `given_up`, a lower bound of it.
    pub value: f64,
    /// Its 95 % confidence interval, N (NaN when `given_up`).
    pub interval: (f64, f64),
    /// Columns the statistic is of.
    pub samples: usize,
    /// Columns whose peak is only a lower bound (the run reached its time cap); they count with
    /// that bound.
    pub bounds: usize,
    /// Whether the columns run settled the statistic at or above the give-up level before all
    /// were run ([`Statistic::settled_above`]).
    pub given_up: bool,
}

/// The statistic of evaluated columns' peaks.
pub fn sampled(statistic: Statistic, evals: &[Evaluation]) -> Sampled {
    let mut peaks: Vec<f64> = evals.iter().map(|e| e.peak_force).collect();
    peaks.sort_by(f64::total_cmp);
    Sampled {
        value: statistic.of_sorted(&peaks),
        interval: statistic.interval(&peaks),
        samples: evals.len(),
        bounds: evals.iter().filter(|e| !e.complete).count(),
        given_up: false,
    }
}

/// The statistic of `beads` over the first `n` of `draws` at `impact`, the columns run one after
/// another on this thread (a search's candidates run on the threads). With a finite
/// `settings.give_up_above` each run gives up there, and the columns stop once the statistic is
/// settled at or above it ([`Statistic::settled_above`]): then `value` is that level, a lower
/// bound, and `given_up` is set.
pub fn sampled_here(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    (draws, n): (&Draws, usize),
    statistic: Statistic,
) -> Result<Sampled, DesignError> {
    let t = settings.give_up_above;
    let mut evals = Vec::with_capacity(n);
    let (mut above, mut sum) = (0, 0.0);
    for j in 0..n {
        let (column, imp) = draws.column(j, beads, impact);
        let e = evaluate(&column, &imp, protected, settings)?;
        above += usize::from(e.peak_force >= t);
        sum += e.peak_force;
        evals.push(e);
        if t.is_finite() && statistic.settled_above(n, above, sum, t) {
            return Ok(Sampled {
                value: t,
                interval: (f64::NAN, f64::NAN),
                samples: evals.len(),
                bounds: evals.iter().filter(|e| !e.complete).count(),
                given_up: true,
            });
        }
    }
    // Not settled: a column that gave up holds only a lower bound of its peak, which the
    // statistic may read, so each is run again to its end (rare: fewer columns gave up than
    // settle it).
    let whole = Settings {
        give_up_above: f64::INFINITY,
        ..*settings
    };
    for (j, e) in evals.iter_mut().enumerate() {
        if e.given_up {
            let (column, imp) = draws.column(j, beads, impact);
            *e = evaluate(&column, &imp, protected, &whole)?;
        }
    }
    Ok(sampled(statistic, &evals))
}

/// Draws `range` of `draws` applied to `beads` at `impact`, evaluated on `threads` threads,
/// in order (the same bits at every thread count), `bar` (if any) moving by one as each
/// finishes. With a `journal`, a column it holds is taken from it and every other one is
/// appended to it as it finishes (a failure to write it is kept there: [`DrawsJournal::check`]).
pub fn evaluate_draws(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    (draws, range): (&Draws, std::ops::Range<usize>),
    (threads, bar): (usize, Option<&ProgressBar>),
    journal: Option<&DrawsJournal>,
) -> Result<Vec<Evaluation>, DesignError> {
    use rayon::prelude::*;
    let pool =
        grainchain_engine::thread_pool(threads, range.len()).map_err(|e| DesignError::Bad {
            what: "threads".into(),
            problem: e.to_string(),
        })?;
    pool.install(|| {
        range
            .into_par_iter()
            .map(|j| {
                let (column, imp) = draws.column(j, beads, impact);
                let e = match journal {
                    None => evaluate(&column, &imp, protected, settings)?,
                    Some(journal) => {
                        let key = draws_journal::key(&column, &imp, protected, settings);
                        match journal.get(&key) {
                            Some(e) => e,
                            None => {
                                let e = evaluate(&column, &imp, protected, settings)?;
                                journal.put(&key, &e);
                                e
                            }
                        }
                    }
                };
                if let Some(b) = bar {
                    b.inc(1);
                }
                Ok(e)
            })
            .collect()
    })
}

/// A design's spread both ways.
#[derive(Clone, Debug, PartialEq)]
pub struct Spread {
    /// The nominal run with the peak's derivatives.
    pub gradients: Gradients,
    /// The first-order spread.
    pub first: FirstOrder,
    /// The Monte Carlo.
    pub monte_carlo: MonteCarlo,
}

/// [`first_order`] and [`monte_carlo`] of a design at one impact.
pub fn spread(
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    tol: &Tolerances,
    threads: usize,
) -> Result<Spread, DesignError> {
    let g = gradients(beads, impact, protected, settings)?;
    spread_of(
        g,
        beads,
        impact,
        protected,
        settings,
        tol,
        (threads, &ProgressBar::hidden(), None),
    )
}

/// [`spread`] of a design whose run with derivatives `g` (at `impact`, `settings`) is known, its
/// Monte Carlo on `work`'s threads, moving its bar, through its journal if any.
pub fn spread_of(
    g: Gradients,
    beads: &[Bead],
    impact: &Impact,
    protected: &Protected,
    settings: &Settings,
    tol: &Tolerances,
    work: (usize, &ProgressBar, Option<&DrawsJournal>),
) -> Result<Spread, DesignError> {
    let first = first_order(beads, impact.speed, g.evaluation.peak_force, &g.peak, tol);
    let draws = Draws::new(beads.len(), tol, tol.samples, SEARCH_STREAM);
    let evals = evaluate_draws_counted(beads, impact, protected, settings, &draws, work)?;
    let monte_carlo = summarise(&evals);
    Ok(Spread {
        gradients: g,
        first,
        monte_carlo,
    })
}

/// The corners of a bead's perturbations (each of its diameter, modulus and density at `1 - 4
/// sigma` or `1 + 4 sigma`; one value of a property without a tolerance): the extremes [`draw`]
/// can reach, which the design file's check proves valid and bounds against the step limit
/// (a contact time is a product of powers of the pair's masses and Hertz constant, so its
/// extremes lie at these corners but for unusual pairs; a column past the limit all the same is
/// refused by its evaluation, an error, not a panic).
pub fn corners(b: &Bead, tol: &Tolerances) -> Vec<Bead> {
    let f = |s: f64| {
        if s > 0.0 {
            vec![1.0 - Z_MAX * s, 1.0 + Z_MAX * s]
        } else {
            vec![1.0]
        }
    };
    let mut out = Vec::with_capacity(8);
    for fd in f(tol.diameter) {
        for fe in f(tol.young) {
            for fr in f(tol.density) {
                let mut p = *b;
                p.diameter *= fd;
                p.material.young *= fe;
                p.material.density *= fr;
                out.push(p);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainchain_engine::protector::Case;

    fn tol(samples: usize, seed: u64) -> Tolerances {
        Tolerances {
            diameter: 0.01,
            young: 0.02,
            density: 0.005,
            speed: 0.03,
            samples,
            seed,
        }
    }

    /// numpy's default percentile (type 7) on a few cases worked by hand.
    #[test]
    fn draws_are_seeded_and_cut() {
        let case = Case::steel_then_ptfe(6);
        let t = tol(200, 7);
        let a = draw(&case.beads, &case.impact, &t);
        assert_eq!(a, draw(&case.beads, &case.impact, &t));
        assert_ne!(a, draw(&case.beads, &case.impact, &tol(200, 8)));
        assert_eq!(a.len(), 200);
        let mut zs = Vec::new();
        for (column, imp) in &a {
            for (p, b) in column.iter().zip(&case.beads) {
                let zd = (p.diameter / b.diameter - 1.0) / t.diameter;
                assert!(zd.abs() <= Z_MAX + 1e-9, "{zd}");
                assert_eq!(p.material.poisson, b.material.poisson);
                zs.push(zd);
            }
            let zv = (imp.speed / case.impact.speed - 1.0) / t.speed;
            assert!(zv.abs() <= Z_MAX + 1e-9);
            assert_eq!(imp.striker, case.impact.striker);
        }
        // 1200 standard normal draws: their mean within 4 standard errors (4 / sqrt(1200) =
        // 0.115) of 0, their variance within 4 of its (sqrt(2 / 1199) = 0.041) of 1.
        let n = zs.len() as f64;
        let mean = zs.iter().sum::<f64>() / n;
        let var = zs.iter().map(|z| (z - mean) * (z - mean)).sum::<f64>() / (n - 1.0);
        assert!(
            mean.abs() < 0.115 && (var - 1.0).abs() < 0.164,
            "{mean} {var}"
        );
        let only_d = Tolerances {
            young: 0.0,
            density: 0.0,
            speed: 0.0,
            ..t
        };
        let b = draw(&case.beads, &case.impact, &only_d);
        for ((ca, ia), (cb, ib)) in a.iter().zip(&b) {
            assert_eq!(ib.speed, case.impact.speed);
            for ((pa, pb), nominal) in ca.iter().zip(cb).zip(&case.beads) {
                // The same stream: the same diameters whichever other tolerances are given.
                assert_eq!(pa.diameter, pb.diameter);
                assert_eq!(pb.material, nominal.material);
            }
            assert_ne!(ia.speed, ib.speed);
        }
    }

    /// The variance's terms add up, the shares to 1, and the top terms come largest first.
    #[test]
    fn first_order_terms_add_up() {
        let beads = Case::steel_then_ptfe(3).beads;
        let d = Derivatives {
            diameter: vec![1e3, -2e3, 0.0],
            density: vec![1e-3, 0.0, 2e-3],
            young: vec![1e-10, 3e-10, 0.0],
            poisson: vec![0.0; 3],
            speed: 5.0,
            striker_mass: 0.0,
        };
        let t = tol(100, 1);
        let f = first_order(&beads, 2.0, 10.0, &d, &t);
        assert_eq!(f.terms.len(), 10);
        let by_hand = (1e3 * 0.01 * 6e-3f64).powi(2) + (5.0 * 0.03 * 2.0f64).powi(2);
        assert!(f.terms[0].variance == (1e3 * 0.01 * 6e-3f64).powi(2));
        assert!(f.sd * f.sd > by_hand);
        let beads_and_speed: f64 =
            (0..3).map(|i| f.bead_share(i)).sum::<f64>() + f.property_share(Property::Speed);
        // Sums of a few shares: rounding of a few operations.
        assert!((beads_and_speed - 1.0).abs() < 1e-12, "{beads_and_speed}");
        let top = f.top(3);
        assert_eq!(top.len(), 3);
        assert!(top[0].variance >= top[1].variance && top[1].variance >= top[2].variance);
        assert_eq!(f.p95(), 10.0 + 1.645 * f.sd);
    }
}
