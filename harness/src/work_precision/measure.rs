//! What a run of a problem yields ([`Outcome`]) and its error against the reference run
//! ([`error_of`]), the median of repeated timings and a point of the diagram ([`Point`]): shared
//! by the study's problems (`mod.rs`, `protector.rs`) and `statistics.rs`, importing none.

/// What a run of a problem yields, to compare with the reference.
pub(super) enum Outcome {
    Velocities(f64, f64),
    Arrivals(Vec<f64>, f64),
    Energy(Vec<f64>),
    /// A coefficient of restitution (NaN: the contact had not ended).
    Restitution(f64),
}

pub(super) const WAVE_PROBES: [usize; 5] = [200, 400, 600, 800, 1000];

/// Snapshots of the container problem over which E_R is compared. Beyond the predictable start
/// of the curve the container's E_R(t) is chaotic: a striker faster by one part in 1e12 moves it
/// by more than 1e-4 (`grainchain reproduce --check-step`; docs/reproduce.md, "Accuracy"), so no
/// integrator converges there and the error of every method saturates (BENCHMARKS.md,
/// "Work-precision"). The comparison stops at the predictable horizon.
pub const CONTAINER_HORIZON: usize = 150;

/// The error of `o` against the reference `r` (see the module docs for each definition), or
/// why it cannot be evaluated: the reference has no wave at a probe (the run is too short), or
/// no snapshot of the reference has E_R above 1e-3 of the incident energy up to
/// [`CONTAINER_HORIZON`]. A value the run did not produce where the reference has one (no wave
/// detected, a NaN) is an infinite error.
pub(super) fn error_of(o: &Outcome, r: &Outcome, e0: f64) -> Result<f64, String> {
    let rel = |a: f64, b: f64| {
        let d = ((a - b) / b).abs();
        if d.is_nan() {
            f64::INFINITY
        } else {
            d
        }
    };
    match (o, r) {
        (Outcome::Velocities(a, b), Outcome::Velocities(x, y)) => {
            let e = (a - x).abs().max((b - y).abs());
            Ok(if e.is_nan() { f64::INFINITY } else { e })
        }
        (Outcome::Restitution(e), Outcome::Restitution(er)) => {
            let d = (e - er).abs();
            Ok(if d.is_nan() { f64::INFINITY } else { d })
        }
        (Outcome::Arrivals(t, p), Outcome::Arrivals(tr, pr)) => {
            if let Some(k) = tr.iter().position(|x| !x.is_finite()) {
                return Err(format!(
                    "not evaluated: the reference run has no wave at probe {} (grain {}): the run is too short",
                    k + 1,
                    WAVE_PROBES[k]
                ));
            }
            if !(pr.is_finite() && *pr > 0.0) {
                return Err(
                    "not evaluated: the reference run has no peak at the last probe".into(),
                );
            }
            let mut e = rel(*p, *pr);
            for (a, b) in t.iter().zip(tr) {
                e = e.max(rel(*a, *b));
            }
            Ok(e)
        }
        (Outcome::Energy(e), Outcome::Energy(er)) => {
            let mut worst: f64 = 0.0;
            let mut compared = 0;
            for (k, b) in er.iter().enumerate().take(CONTAINER_HORIZON + 1) {
                if *b > 1e-3 * e0 {
                    compared += 1;
                    worst = worst.max(e.get(k).map_or(f64::INFINITY, |a| rel(*a, *b)));
                }
            }
            if compared == 0 {
                return Err(format!(
                    "not evaluated: no reference snapshot up to {CONTAINER_HORIZON} has E_R above 1e-3 of the incident energy"
                ));
            }
            Ok(worst)
        }
        _ => Err("not evaluated: the run and its reference differ in kind".into()),
    }
}

pub(super) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One point of the diagram.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Point {
    /// The problem's name ([`super::Benchmark::name`]; `restitution`'s carry their damping model,
    /// `protector-40`'s their number: [`super::Benchmark::labels`]).
    pub problem: &'static str,
    /// Method name, or `paper-scheme` for the paper's baseline (`reference-check`: the
    /// reference's own error, [`super::protector::REFERENCE_CHECK`]).
    pub method: String,
    /// `dt` (fixed step, effective) or `rtol` (adaptive).
    pub setting: f64,
    /// The problem's error (module docs): the largest absolute deviation of the outgoing
    /// velocities for the collisions, |e - e_ref| for `restitution`, the relative error of its
    /// number for `protector-40`, the largest relative error for the others (infinite when a
    /// compared value is NaN); NaN when the run failed.
    pub error: f64,
    /// Wall time of one run in seconds, building the simulation not counted (`protector-40`:
    /// the whole evaluation, its layout included): the median of [`super::Config::repeats`] runs (one
    /// for `paper-scheme` and `reference-check`); NaN when the run failed.
    pub seconds: f64,
    /// Accepted steps (0 when the run failed).
    pub steps: u64,
    /// Rejected steps (adaptive methods).
    pub rejected: u64,
    /// Force evaluations (`protector-40`: its steps times the method's evaluations per step).
    pub force_evals: u64,
    /// Grains evaluated, summed over the force evaluations: the work done (0 for
    /// `protector-40`: a protector evaluation does not count it).
    pub grain_evals: u64,
    /// Empty, or why the point has no error: `failed: ...` when the run failed (e.g. a blow-up
    /// at a step past stability), `not evaluated: ...` when the error is undefined (the
    /// reference has nothing to compare with, see `error_of`).
    pub failure: String,
}

impl Point {
    /// The point of a run that failed with `e`: no error, time or counters.
    pub fn failed(
        problem: &'static str,
        method: String,
        setting: f64,
        e: impl std::fmt::Display,
    ) -> Point {
        Point {
            problem,
            method,
            setting,
            error: f64::NAN,
            seconds: f64::NAN,
            steps: 0,
            rejected: 0,
            force_evals: 0,
            grain_evals: 0,
            failure: format!("failed: {e}"),
        }
    }
}
