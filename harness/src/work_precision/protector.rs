//! `protector-40`: run time against error of one protector evaluation
//! ([`grainchain_engine::protector::evaluate`]) on the 40-bead reference column of
//! `benches/protector.rs` ([`Case::steel_then_ptfe`]`(40)`: 20 steel then 20 PTFE beads of 6 mm
//! on a steel wall, a 6 mm steel striker at 1 m/s), per method and steps per contact time
//! (issue 40: every protector number with a stated error).
//!
//! Each number is read from the run that makes it final ([`Need`]): the peak force from a run
//! stopped for the peak (the search's default, whose time is the `protector/reference`
//! bench's); so a point's time is what that number costs. The impulse and the time above half
//! the peak are not final on this column ([`QUANTITIES`] says why). The points are labelled
//! `protector-40-peak` (one label per number); the error is `|x - x_ref| / x_ref`
//! against blanes-moan4 with the same stop at [`REFERENCE_STEPS`]`[1]` steps per contact time
//! (4 times finer than the sweep's finest, 64 times the default's). The reference's own error is stated by a point of
//! method [`REFERENCE_CHECK`]: blanes-moan4 at half those steps against it.
//! A run that ends at its time cap, not by the stop rule, gives no final number: its point is
//! `not evaluated`.

use super::config;
use super::measure::{median, Point};
use crate::error::Error;
use grainchain_engine::protector::{lay_out, Case, DesignError, Evaluation, Need, Settings};
use grainchain_engine::{Method, RunError};
use std::time::Instant;

/// The problem's name on the command line.
pub const NAME: &str = "protector-40";

/// Beads of the column.
pub const BEADS: usize = 40;

/// The labels of the points and the stop each number needs, in the study's order: the peak
/// only. On this column a run stopped for the time above half the peak ([`Need::Duration`]) or
/// for the impulse ([`Need::Everything`]) reaches its time cap (100 contact-time sums,
/// 0.163 s) before the stop rule can prove its number final (the PTFE half keeps energy that
/// could still reach the wall), so those are numbers up to a cap that moves with the step
/// (by up to `check_every` steps), not final ones, and have no error to state.
pub const QUANTITIES: [(&str, Need); 1] = [("protector-40-peak", Need::Peak)];

/// The method name of the points that state the reference's own error.
pub const REFERENCE_CHECK: &str = "reference-check";

/// Steps per contact time of the two references (blanes-moan4, the same stop as the points):
/// the check's and the reference's, 2 and 4 times the sweep's finest
/// (`config::protector_steps`). Not finer: at 20480 the column's step bound (1.9e8 steps)
/// passes [`grainchain_engine::protector::MAX_EVALUATION_STEPS`] and `evaluate` refuses it.
/// Quick mode: 1280 and 2560.
pub const REFERENCE_STEPS: [u64; 2] = [5120, 10240];

/// Quick mode's references (a smoke run: seconds, not minutes).
const QUICK_REFERENCE_STEPS: [u64; 2] = [1280, 2560];

/// The settings of an evaluation: the defaults but for the method, the step and the stop.
pub fn settings(method: Method, steps_per_contact: u64, need: Need) -> Settings {
    Settings {
        need,
        method,
        steps_per_contact: steps_per_contact as f64,
        ..Settings::default()
    }
}

/// The number a label measures, or why it is not final.
pub fn value(e: &Evaluation, need: Need) -> Result<f64, String> {
    if !e.complete {
        return Err(format!(
            "not evaluated: the run reached its time cap at {:.4e} s, not the stop rule, so \
             its {} is not final",
            e.time,
            what(need)
        ));
    }
    Ok(match need {
        Need::Peak => e.peak_force,
        Need::Everything => e.impulse,
        Need::Duration => e.duration,
    })
}

fn what(need: Need) -> &'static str {
    match need {
        Need::Peak => "peak force",
        Need::Everything => "impulse",
        Need::Duration => "duration above half the peak",
    }
}

/// `|x - r| / |r|`.
pub fn relative(x: f64, r: f64) -> f64 {
    (x - r).abs() / r.abs()
}

fn engine_error(e: DesignError) -> Error {
    match e {
        DesignError::Run(r) => Error::Run(r),
        other => Error::Run(RunError::Settings(other.to_string())),
    }
}

/// One evaluation timed (wall time of the whole `evaluate` call, as the bench times it).
fn timed(case: &Case, s: &Settings) -> Result<(Evaluation, f64), DesignError> {
    let t0 = Instant::now();
    let e = case.evaluate(s)?;
    Ok((e, t0.elapsed().as_secs_f64()))
}

fn point(label: &'static str, method: &str, e: &Evaluation, m: Method, seconds: f64) -> Point {
    Point {
        problem: label,
        method: method.to_string(),
        setting: e.dt,
        error: f64::NAN,
        seconds,
        steps: e.steps,
        rejected: 0,
        // `evaluate` returns no counters: its steps times the method's evaluations per step.
        force_evals: e.steps * u64::from(m.information().evaluations_per_step),
        // Not counted by `evaluate` (the column has 42 grains with the striker).
        grain_evals: 0,
        failure: String::new(),
    }
}

/// The points of `protector-40`: per label ([`QUANTITIES`]) the reference check, then verlet's
/// and blanes-moan4's sweeps (`config::protector_steps`), coarsest first.
pub fn run(
    quick: bool,
    repeats: usize,
    progress: &mut impl FnMut(&str),
) -> Result<Vec<Point>, Error> {
    let case = Case::steel_then_ptfe(BEADS);
    let levels = if quick {
        QUICK_REFERENCE_STEPS
    } else {
        REFERENCE_STEPS
    };
    // Per label: the reference's value, and the points (the reference check first).
    let mut refs = Vec::new();
    let mut by_label: Vec<Vec<Point>> = Vec::new();
    for (label, need) in QUANTITIES {
        let mut reference = Vec::new();
        for n in levels {
            progress(&format!(
                "{label}: reference, blanes-moan4 at {n} steps per contact"
            ));
            // With events: the peak located between steps (O(h^3), not the O(h^2) of sampling).
            let s = Settings {
                events: true,
                ..settings(Method::BlanesMoan4, n, need)
            };
            reference.push(timed(&case, &s).map_err(engine_error)?);
        }
        let ((check, secs), (fine, _)) = (reference[0], reference[1]);
        let r = value(&fine, need).map_err(|why| {
            Error::Run(RunError::Settings(format!("{label}: the reference: {why}")))
        })?;
        let mut p = point(label, REFERENCE_CHECK, &check, Method::BlanesMoan4, secs);
        match value(&check, need) {
            Ok(x) => p.error = relative(x, r),
            Err(why) => p.failure = why,
        }
        refs.push(r);
        by_label.push(vec![p]);
    }
    for (m, events) in [
        (Method::Verlet, false),
        (Method::BlanesMoan4, false),
        (Method::Verlet, true),
        (Method::BlanesMoan4, true),
    ] {
        let name = if events {
            format!("{}+events", m.name())
        } else {
            m.name().to_string()
        };
        let mut steps = config::protector_steps(m);
        if quick {
            steps = vec![steps[0], steps[steps.len() / 2]];
        }
        for n in steps {
            for (k, (label, need)) in QUANTITIES.into_iter().enumerate() {
                progress(&format!("{label}: {name} at {n} steps per contact"));
                let s = Settings {
                    events,
                    ..settings(m, n, need)
                };
                let mut times = Vec::new();
                let mut result = None;
                for _ in 0..repeats.max(1) {
                    match timed(&case, &s) {
                        Ok((e, secs)) => {
                            times.push(secs);
                            result = Some(Ok(e));
                        }
                        Err(e) => {
                            result = Some(Err(e));
                            break;
                        }
                    }
                }
                let p = match result.expect("at least one run") {
                    Ok(e) => {
                        let mut p = point(label, &name, &e, m, median(times));
                        match value(&e, need) {
                            Ok(x) => p.error = relative(x, refs[k]),
                            Err(why) => p.failure = why,
                        }
                        p
                    }
                    Err(e) => Point::failed(
                        label,
                        name.clone(),
                        // The step the layout asked for (NaN if even that failed).
                        lay_out(&case.beads, &case.impact, &case.protected, &s)
                            .map_or(f64::NAN, |l| l.dt),
                        e,
                    ),
                };
                by_label[k].push(p);
            }
        }
    }
    Ok(by_label.into_iter().flatten().collect())
}
