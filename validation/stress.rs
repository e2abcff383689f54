//! Numerical-stability stress tests: extremes that must run cleanly or stop with the blow-up
//! error, never hand a non-finite number to an output, never hang.

use crate::common;

use common::{record_one, Row};
use grainchain_engine::problems::SolitaryWave;
use grainchain_engine::{Chain, State};
use grainchain_engine::{ChainBuilder, ContactLaw, End, Section, Striker, StrikerEnd};
use grainchain_engine::{Frame, RunError, SimulationBuilder};
use grainchain_engine::{IntegrationParams, Method, StepError};

/// Contact time of two grains (physics.md 4), computed here.
fn contact_time(p: f64, eta: f64, mu: f64, v: f64) -> f64 {
    let dmax = ((p + 1.0) * mu * v * v / (2.0 * eta)).powf(1.0 / (p + 1.0));
    2.0 * dmax / v * common::beta(1.0 / (p + 1.0), 0.5) / (p + 1.0)
}

fn params(method: Method, dt: f64) -> IntegrationParams {
    IntegrationParams {
        method,
        dt,
        ..Default::default()
    }
}

/// What a run handed to its outputs and how it ended.
struct Outcome {
    result: Result<(), RunError>,
    /// Non-finite numbers seen in any frame (state or totals).
    non_finite: usize,
    frames: usize,
    max_energy_error: f64,
    state: State,
    window_len: usize,
    steps: u64,
}

fn run_checked(
    chain: Chain,
    p: IntegrationParams,
    duration: f64,
    interval: f64,
    init: &[(usize, f64)],
) -> Outcome {
    let mut b = SimulationBuilder::new(chain)
        .params(p)
        .schedule(duration, interval);
    for &(i, v) in init {
        b = b.velocity(i, v);
    }
    let mut sim = b.build().unwrap();
    let (mut non_finite, mut frames) = (0usize, 0usize);
    let result = sim.run(|fr: &Frame| {
        frames += 1;
        let t = fr.totals;
        non_finite += [t.kinetic, t.potential, t.total, t.momentum, fr.state.t]
            .iter()
            .filter(|x| !x.is_finite())
            .count();
        non_finite += fr
            .state
            .u
            .iter()
            .chain(&fr.state.v)
            .filter(|x| !x.is_finite())
            .count();
        Ok::<(), RunError>(())
    });
    Outcome {
        result,
        non_finite,
        frames,
        max_energy_error: sim.max_energy_error(),
        state: sim.state().clone(),
        window_len: sim.window().len(),
        steps: sim.stats().steps,
    }
}

cases! {
/// Check 12a: exponents from 1 to 4 (eta = m = 1, striker speed 1), Blanes-Moan at t_c/200.
fn exponent_range(p: f64) {
    let tc = contact_time(p, 1.0, 0.5, 1.0);
    let o = run_checked(
        SolitaryWave::unit(p, 100, 1.0).chain().unwrap(),
        params(Method::BlanesMoan4, tc / 200.0),
        30.0 * tc,
        tc,
        &[],
    );
    // Energy bound 1e-6: BM4 at t_c/200 has a relative energy error of order (2 pi/200)^4 = 1e-6
    // on smooth contacts and less on these (measured 1e-9 .. 1e-7); a defect at one exponent
    // (a wrong kernel) gives errors of order 1.
    let ok = o.result.is_ok() && o.non_finite == 0 && o.max_energy_error < 1e-6;
    record_one(
        Row::new(
            "stress: exponent range",
            format!("p={p}, 100 grains, BM4 dt=t_c/200"),
            "must run cleanly",
        )
        .expected("ok, finite outputs, |dE/E| < 1e-6")
        .measured(format!(
            "{}, {} non-finite in {} frames, |dE/E| {:.1e}",
            if o.result.is_ok() { "ok" } else { "error" },
            o.non_finite,
            o.frames,
            o.max_energy_error
        ))
        .tolerance("1e-6")
        .pass(ok),
    );
    assert!(
        ok,
        "p={p}: {:?} {} {}",
        o.result, o.non_finite, o.max_energy_error
    );
}
case_1(1.0),
case_2(1.25),
case_3(1.5),
case_4(2.0),
case_5(3.0),
case_6(4.0),
}

cases! {
/// Check 12b: mass ratios 1e-3 .. 1e3 across one interface (30 grains of mass 1, then 30 of mass
/// `r`, Hertz, eta = 1, striker of mass 1 at speed 1), Blanes-Moan at 1/200 of the contact time
/// of the lightest pair at twice the striker speed (light grains hit by heavy ones reach up to
/// twice the speed).
fn mass_ratio_range(r: f64) {
    let law = ContactLaw::hertz(1.0);
    let chain = ChainBuilder::new()
        .section(Section::new("a", 30, 1.0, law))
        .section(Section::new("b", 30, r, law))
        .striker(Striker {
            end: StrikerEnd::Left,
            mass: 1.0,
            speed: 1.0,
            law: None,
        })
        .build()
        .unwrap();
    let light = r.min(1.0);
    let dt = contact_time(1.5, 1.0, light / 2.0, 2.0) / 200.0;
    let tc1 = contact_time(1.5, 1.0, 0.5, 1.0);
    let o = run_checked(chain, params(Method::BlanesMoan4, dt), 40.0 * tc1, tc1, &[]);
    // Energy bound 1e-6, as for the exponent range: the step resolves the fastest contact.
    let ok = o.result.is_ok() && o.non_finite == 0 && o.max_energy_error < 1e-6;
    record_one(
        Row::new(
            "stress: mass ratio across an interface",
            format!("m2/m1={r:e}, BM4"),
            "must run cleanly",
        )
        .expected("ok, finite outputs, |dE/E| < 1e-6")
        .measured(format!(
            "{}, {} non-finite, |dE/E| {:.1e}, {} steps",
            if o.result.is_ok() { "ok" } else { "error" },
            o.non_finite,
            o.max_energy_error,
            o.steps
        ))
        .tolerance("1e-6")
        .pass(ok),
    );
    assert!(
        ok,
        "r={r}: {:?} {} {}",
        o.result, o.non_finite, o.max_energy_error
    );
}
case_1(1e-3),
case_2(1e-2),
case_3(0.1),
case_4(10.0),
case_5(100.0),
case_6(1e3),
}

cases! {
/// Check 12c: striker speeds 1e-6 .. 1e4 on a Hertz chain. The amplitude symmetry (physics.md 3)
/// says what to expect: with time (duration and step) scaled by kappa^(-1/5), displacements
/// scale by kappa^(4/5) and velocities by kappa, so the scaled final state equals the kappa = 1
/// run's up to round-off.
fn striker_speed_range(kappa: f64) {
    let p = 1.5;
    let n = 40;
    let steps = 20_000.0;
    let run = |k: f64| {
        let tc = contact_time(p, 1.0, 0.5, k);
        let t = 25.0 * tc;
        // A step a hair above t/steps so the run takes exactly `steps` steps.
        let dt = t / steps * (1.0 + 1e-10);
        run_checked(
            SolitaryWave::unit(p, n, k).chain().unwrap(),
            params(Method::Verlet, dt),
            t,
            t,
            &[],
        )
    };
    let a = run(1.0);
    let b = run(kappa);
    let lambda = kappa.powf(2.0 / (p + 1.0));
    let du = a
        .state
        .u
        .iter()
        .zip(&b.state.u)
        .fold(0.0f64, |m, (x, y)| m.max((x - y / lambda).abs()));
    let dv = a
        .state
        .v
        .iter()
        .zip(&b.state.v)
        .fold(0.0f64, |m, (x, y)| m.max((x - y / kappa).abs()));
    // Tolerance 1e-9 of the unit scale: both runs take the same 20,000 steps of the same scaled
    // size, so they differ only by rounding (kappa^(4/5) and the scaled step are not exact in
    // binary): about eps per operation, accumulated over 2e4 steps and amplified at most
    // modestly by the wave dynamics.
    let tol = 1e-9;
    let ok = b.result.is_ok() && b.non_finite == 0 && a.steps == b.steps && du.max(dv) < tol;
    record_one(
        Row::new(
            "stress: striker speed range",
            format!("v={kappa:e}, Hertz, 20000 Verlet steps"),
            "physics.md 3: amplitude symmetry",
        )
        .expected("scaled state = unit-speed state")
        .measured(format!(
            "max |du| {du:.1e}, |dv| {dv:.1e} (scaled), {} non-finite",
            b.non_finite
        ))
        .tolerance(format!("{tol:e}"))
        .pass(ok),
    );
    assert!(ok, "kappa={kappa}: du {du:e} dv {dv:e} {:?}", b.result);
}
case_1(1e-6),
case_2(1e-3),
case_3(1e2),
case_4(1e4),
}

/// Check 12d: a 10^6-grain chain with one solitary wave: skipping keeps the work to the wave,
/// and the first 1,000 grains are bit for bit those of a 1,000-grain chain (nothing has reached
/// grain 1,000 yet).
#[test]
fn million_grain_chain_single_wave() {
    let tc = contact_time(1.5, 1.0, 0.5, 1.0);
    let t = 100.0 * tc; // the wave travels about 200 grains
    let big = run_checked(
        SolitaryWave::unit(1.5, 1_000_000, 1.0).chain().unwrap(),
        params(Method::Verlet, tc / 100.0),
        t,
        t / 10.0,
        &[],
    );
    let small = run_checked(
        SolitaryWave::unit(1.5, 1_000, 1.0).chain().unwrap(),
        params(Method::Verlet, tc / 100.0),
        t,
        t / 10.0,
        &[],
    );
    let same = (0..1000).all(|i| {
        big.state.u[i].to_bits() == small.state.u[i].to_bits()
            && big.state.v[i].to_bits() == small.state.v[i].to_bits()
    });
    let rest_at_rest = big.state.u[1001..].iter().all(|&x| x == 0.0)
        && big.state.v[1001..].iter().all(|&x| x == 0.0);
    let ok = big.result.is_ok() && big.non_finite == 0 && same && rest_at_rest;
    record_one(
        Row::new(
            "stress: 1e6-grain chain, one wave",
            "Hertz, Verlet, wave runs ~200 grains",
            "exact skipping (ARCHITECTURE.md)",
        )
        .expected("ok; first 1000 grains = 1000-grain chain bit for bit")
        .measured(format!(
            "{}; identical: {same}; untouched grains at rest: {rest_at_rest}; window {} grains",
            if big.result.is_ok() { "ok" } else { "error" },
            big.window_len
        ))
        .tolerance("0 bits")
        .pass(ok),
    );
    assert!(ok);
}

/// Check 12e: a precompressed 10^6-grain chain with skipping off (every grain integrated),
/// 200 Verlet steps with a kick at one end: runs, finite, energy conserved.
#[test]
fn million_grain_precompressed_chain() {
    let law = ContactLaw::hertz(1.0).with_precompression(0.1);
    let chain = ChainBuilder::new()
        .grains(1_000_000, 1.0, law)
        .left(End::Wall(law))
        .right(End::Wall(law))
        .build()
        .unwrap();
    let p = IntegrationParams {
        skip_untouched: false,
        ..params(Method::Verlet, 0.01)
    };
    let o = run_checked(chain, p, 2.0, 1.0, &[(0, 0.01)]);
    // Energy bound 1e-4: Verlet at omega_max dt = 2 sqrt(1.5 * 0.1^0.5) * 0.01 = 0.014 has a
    // relative energy error of order (omega dt)^2 / 8 = 2.5e-5.
    let ok = o.result.is_ok() && o.non_finite == 0 && o.max_energy_error < 1e-4;
    record_one(
        Row::new(
            "stress: 1e6-grain precompressed chain",
            "Hertz, delta0=0.1, Verlet dt=0.01, 200 steps, nothing skipped",
            "must run cleanly",
        )
        .expected("ok, finite, |dE/E| < 1e-4")
        .measured(format!(
            "{}, window {} grains, |dE/E| {:.1e}",
            if o.result.is_ok() { "ok" } else { "error" },
            o.window_len,
            o.max_energy_error
        ))
        .tolerance("1e-4")
        .pass(ok),
    );
    assert!(ok, "{:?}", o.result);
}

cases! {
/// Check 12f: steps up to and past the stability limit. A chain of 50 two-sided linear springs
/// (k = m = 1) has omega_max = 2 sin(49 pi / 100) = 1.9990, so Verlet is stable for
/// dt < 2 / omega_max = 1.0005. Every run must either finish with finite outputs or stop with
/// the blow-up error (non-finite state or energy error over the bound); past the limit it must
/// stop. The energy bound is set to 1e6 so that the non-finite check, not the energy check, has
/// to catch the blow-up.
fn step_past_stability_limit(method: Method, dt: f64) {
    let chain = ChainBuilder::new()
        .grains(50, 1.0, ContactLaw::linear_spring(1.0))
        .build()
        .unwrap();
    let init: Vec<(usize, f64)> = (0..50).map(|i| (i, ((i * 7) % 11) as f64 - 5.0)).collect();
    let p = IntegrationParams {
        max_energy_error: 1e6,
        ..params(method, dt)
    };
    // 2000 output intervals of dt: the step is not shortened, and an unstable mode growing by a
    // factor of at least 1.04 per step reaches overflow (1e308) well within 2e4 steps.
    let o = run_checked(chain, p, 20_000.0 * dt, 10.0 * dt, &init);
    let stopped = match &o.result {
        Ok(()) => "finished".to_string(),
        Err(RunError::Step(StepError::NonFinite { step, .. })) => {
            format!("non-finite state detected at step {step}")
        }
        Err(RunError::EnergyDrift { step, rel, .. }) => {
            format!("energy error {rel:.1e} detected at step {step}")
        }
        Err(e) => format!("other error: {e}"),
    };
    let detected = matches!(
        o.result,
        Err(RunError::Step(StepError::NonFinite { .. })) | Err(RunError::EnergyDrift { .. })
    );
    // Verlet's limit is known exactly (above); the other methods' limits are smaller or not
    // known in closed form, so for them only the clearly unstable steps (3 and 10, omega dt of
    // 6 and 20) must be detected.
    let must_stop = match method {
        Method::Verlet => dt > 1.0005,
        _ => dt >= 3.0,
    };
    let must_finish = method == Method::Verlet && dt < 1.0;
    let ok = o.non_finite == 0
        && (o.result.is_ok() || detected)
        && (!must_stop || detected)
        && (!must_finish || o.result.is_ok());
    record_one(
        Row::new(
            "stress: step near and past the stability limit",
            format!("{}, dt={dt} (Verlet limit 1.0005)", method.name()),
            "must finish or stop with the blow-up error",
        )
        .expected(if must_stop {
            "blow-up detected"
        } else if must_finish {
            "finishes"
        } else {
            "finishes or blow-up detected"
        })
        .measured(format!("{stopped}; {} non-finite outputs", o.non_finite))
        .tolerance("no NaN in any output")
        .pass(ok),
    );
    assert!(
        ok,
        "{method:?} dt={dt}: {stopped}, {} non-finite",
        o.non_finite
    );
}
case_1(Method::Verlet, 0.5),
case_2(Method::Verlet, 0.99),
case_3(Method::Verlet, 1.01),
case_4(Method::Verlet, 1.5),
case_5(Method::Verlet, 3.0),
case_6(Method::Verlet, 10.0),
case_7(Method::BlanesMoan4, 0.5),
case_8(Method::BlanesMoan4, 0.99),
case_9(Method::BlanesMoan4, 1.01),
case_10(Method::BlanesMoan4, 1.5),
case_11(Method::BlanesMoan4, 3.0),
case_12(Method::BlanesMoan4, 10.0),
case_13(Method::Gear5, 0.5),
case_14(Method::Gear5, 0.99),
case_15(Method::Gear5, 1.01),
case_16(Method::Gear5, 1.5),
case_17(Method::Gear5, 3.0),
case_18(Method::Gear5, 10.0),
}

cases! {
/// Check 12g: a step far too large for a Hertz chain (grains pass through each other): the run
/// must stop with the blow-up error, not produce garbage.
fn oversized_step_on_hertz_chain(method: Method) {
    let tc = contact_time(1.5, 1.0, 0.5, 1.0);
    let o = run_checked(
        SolitaryWave::unit(1.5, 50, 1.0).chain().unwrap(),
        params(method, 2.0 * tc),
        200.0 * tc,
        2.0 * tc,
        &[],
    );
    let detected = o.result.is_err();
    let ok = detected && o.non_finite == 0;
    record_one(
        Row::new(
            "stress: oversized step on a Hertz chain",
            format!("{}, dt = 2 t_c", method.name()),
            "must stop with the blow-up error",
        )
        .expected("error, no NaN output")
        .measured(format!(
            "{}; {} non-finite outputs",
            match &o.result {
                Ok(()) => "finished (undetected)".to_string(),
                Err(e) => e.to_string(),
            },
            o.non_finite
        ))
        .tolerance("no NaN in any output")
        .pass(ok),
    );
    assert!(ok, "{method:?}: {:?}", o.result);
}
case_1(Method::Verlet),
case_2(Method::BlanesMoan4),
case_3(Method::Gear5),
}

/// Growth exponent of the energy error over a `steps`-step run of the box, with the tenths.
fn growth(method: Method, steps: u64) -> (f64, f64, Vec<f64>, usize, u64) {
    let (errs, done) = common::box_energy_errors(params(method, 0.02), steps, 2000);
    let tenths = common::tenth_maxima(&errs);
    let lt: Vec<f64> = (0..10).map(|j| (j as f64 + 0.5).ln()).collect();
    let le: Vec<f64> = tenths.iter().map(|e| e.ln()).collect();
    let (g, _, se) = common::fit_line(&lt, &le);
    let nonfinite = errs.iter().filter(|e| !e.is_finite()).count();
    (g, se, tenths, nonfinite, done)
}

fn hundred_million(method: Method) {
    let (g, se, tenths, nonfinite, steps) = growth(method, 100_000_000);
    // Bound 0.75 on the growth exponent: between a random walk (0.5) and a drift (1), as in the
    // 10^7-step conservation check (validation/conservation.rs explains it).
    let ok = g < 0.75 && nonfinite == 0 && steps >= 100_000_000;
    record_one(
        Row::new(
            "stress: 1e8 steps, energy does not drift",
            format!("{}, 4 grains between walls, dt=0.02", method.name()),
            "symplectic: no secular drift",
        )
        .expected("growth exponent < 0.75")
        .measured(format!(
            "{steps} steps; growth {g:.2} (s.e. {se:.2}); max |dE/E| first tenth {:.2e}, last \
             tenth {:.2e}",
            tenths[0], tenths[9]
        ))
        .tolerance("0.75")
        .pass(ok),
    );
    assert!(ok, "growth {g}: {tenths:?}");
}

/// Check 12h: 10^8 steps on the cheapest setup (four grains in a box, Verlet: a few seconds).
/// The energy error must not drift.
#[test]
fn hundred_million_steps_verlet() {
    hundred_million(Method::Verlet);
}

/// The same with Blanes-Moan (six force evaluations per step: about a minute), ignored in the
/// default run; `cargo test -- --ignored` runs it. Measured 2026-11-21: it FAILS, growth exponent
/// 0.88 +- 0.12 (max error 4.5e-5 in the first tenth, 4.5e-4 in the last), while the same setup
/// over 10^7 steps gives 0.49: on Hertz contacts (force only C^1 where a contact opens) the
/// per-contact errors of this method do not average out, a slow secular drift. Reported to the
/// lead; the bound is not widened.
#[test]
#[ignore = "10^8 Blanes-Moan steps (about a minute); fails: energy drifts on Hertz contacts (growth 0.88)"]
fn hundred_million_steps_blanes_moan() {
    hundred_million(Method::BlanesMoan4);
}

/// Issue 38, item 3: a light chain stepped above its stability limit (dt 0.036 for a Hertz
/// chain of unit masses and eta 5657) beside a 1e12-mass grain drifting away at its free end:
/// the light chain's energy went from 0.5 to 2.2e8 in 0.25 time units, exit 0, because the
/// error was measured against the whole chain's energy, which the idle heavy grain holds. The
/// check now leaves out of its scale the grains still in their first free flight; the blow-up
/// is caught and blamed on a light grain. The same chain with a stable step runs.
#[test]
fn a_drifting_heavy_grain_hides_no_blow_up() {
    let scene = |dt: f64, heavy_speed: f64| {
        format!(
            "[chain]\n\
             [[chain.sections]]\nname = \"light\"\ncount = 1000\nmass = 1.0\np = 1.5\neta = 5657.0\n\
             [[chain.sections]]\nname = \"heavy\"\ncount = 1\nmass = 1e12\np = 1.5\neta = 5657.0\n\
             [striker]\nend = \"left\"\nmass = 1.0\nspeed = 1.0\n\
             [[initial]]\ngrain = 1001\nvelocity = {heavy_speed:?}\n\
             [integrator]\nmethod = \"verlet\"\ndt = {dt:?}\n\
             [run]\nduration = 0.25\noutput_interval = 0.25\n"
        )
    };
    let dir = std::env::temp_dir().join(format!("grainchain-stress-drift-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |name: &str, text: String| {
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, text).unwrap();
        let out = dir.join(name);
        common::grainchain(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let (code, _, err) = run("unstable", scene(0.04, 1.0));
    assert_eq!(code, Some(1), "the blow-up went unnoticed: {err}");
    assert!(err.contains("numerical blow-up"), "{err}");
    // Blamed on a light grain (1..1000), not the heavy one (1001) whose energy is the largest.
    assert!(!err.contains("at grain 1001"), "{err}");
    // A stable step (0.001, about 1/70 of the contact time at unit speed), the heavy grain
    // drifting: no false alarm.
    let (code, _, err) = run("stable", scene(0.001, 1.0));
    assert_eq!(code, Some(0), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
