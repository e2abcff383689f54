//! Conservation and exactness: momentum to round-off on free chains, bounded energy error of
//! the symplectic methods over 10^7 steps, time reversal, and skipping of untouched grains
//! (exact) and sleep (approximate, error measured).

use crate::common;

use common::{record_one, Row};
use grainchain_engine::Scene;
use grainchain_engine::{Chain, State};
use grainchain_engine::{ChainBuilder, ContactLaw, Section, Striker, StrikerEnd};
use grainchain_engine::{Frame, RunError, SimulationBuilder};
use grainchain_engine::{IntegrationParams, Method, Sleep};

fn params(method: Method, dt: f64) -> IntegrationParams {
    IntegrationParams {
        method,
        dt,
        rtol: 1e-10,
        atol: 1e-12,
        ..Default::default()
    }
}

/// A deterministic pseudo-random sequence in [0, 1) (64-bit LCG, fixed seed).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

cases! {
/// Check 9a: momentum on a free chain of mixed masses and laws, every method: conserved to
/// round-off.
fn momentum_on_free_chain(method: Method) {
    let mut rng = Lcg(42);
    let mut b = ChainBuilder::new();
    for k in 0..12 {
        let p = [1.0, 1.5, 2.0, 2.5][k % 4];
        let m = 0.1 * 100f64.powf(rng.next()); // 0.1 .. 10
        b = b.section(Section::new(
            format!("s{k}"),
            10,
            m,
            ContactLaw::new(p, 1.0),
        ));
    }
    let chain = b
        .striker(Striker {
            end: StrikerEnd::Left,
            mass: 3.0,
            speed: 1.0,
            law: None,
        })
        .build()
        .unwrap();
    let mut sb = SimulationBuilder::new(chain)
        .params(params(method, 2e-3))
        .schedule(40.0, 1.0);
    // A few grains moving against the wave, so momentum has both signs.
    for i in [30usize, 60, 90] {
        sb = sb.velocity(i, -0.3 * rng.next());
    }
    let mut sim = sb.build().unwrap();
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    let mut p0 = None;
    sim.run(|fr: &Frame| {
        let m = fr.chain.mass();
        // Momentum and its scale sum(|m v|), computed here.
        let p: f64 = (0..m.len()).map(|i| m[i] * fr.state.v[i]).sum();
        let s: f64 = (0..m.len()).map(|i| (m[i] * fr.state.v[i]).abs()).sum();
        let p0 = *p0.get_or_insert(p);
        scale = scale.max(s);
        worst = worst.max((p - p0).abs());
        Ok::<(), RunError>(())
    })
    .unwrap();
    let evals = sim.stats().force_evals as f64;
    let rel = worst / scale;
    // Tolerance: every force evaluation adds equal and opposite contact impulses; each update
    // v += c a rounds once per grain, a few ulps of sum |m v| per evaluation at most, so even a
    // worst-case linear accumulation stays below 4 eps per evaluation.
    let tol = 4.0 * f64::EPSILON * evals;
    let ok = rel <= tol;
    record_one(
        Row::new(
            "momentum on a free chain",
            format!("{}, 120 grains, 4 laws, masses 0.1..10", method.name()),
            "exact: contact forces are equal and opposite",
        )
        .expected("0")
        .measured(format!("{rel:.1e} of sum|m v| ({evals} force evaluations)"))
        .tolerance(format!("{tol:.1e} (4 eps per evaluation)"))
        .pass(ok),
    );
    assert!(ok, "{method:?}: momentum drift {rel:e} > {tol:e}");
}
case_1(Method::Verlet),
case_2(Method::BlanesMoan4),
case_3(Method::Gear5),
case_4(Method::Dopri5),
}

cases! {
/// Check 9b: the energy error of the symplectic methods does not drift over 10^7 steps: four
/// Hertz grains between walls (about 10^5 contacts opening and closing), dt = 0.02 (contact
/// time about 3). The growth exponent is the slope of log(max error in each tenth of the run)
/// against log(time at its middle): 0 for a bounded error, 1/2 for a random walk, 1 for a
/// drift linear in time. Gear5 (not symplectic) is reported beside them over 10^6 steps.
fn energy_error_bounded(method: Method, steps: u64) {
    let dt = 0.02;
    let (errs, _) = common::box_energy_errors(params(method, dt), steps, 2000);
    let tenths = common::tenth_maxima(&errs);
    let lt: Vec<f64> = (0..10).map(|j| (j as f64 + 0.5).ln()).collect();
    let le: Vec<f64> = tenths.iter().map(|e| e.ln()).collect();
    let (growth, _, se) = common::fit_line(&lt, &le);
    let max = errs.iter().cloned().fold(0.0, f64::max);
    let params = format!(
        "{}, dt={dt}, {steps} steps, 4 grains in a box",
        method.name()
    );
    let measured = format!(
        "growth exponent {growth:.2} (s.e. {se:.2}); max |dE/E| first tenth {:.2e}, last tenth \
         {:.2e}, overall {max:.2e}",
        tenths[0], tenths[9]
    );
    if method.is_symplectic() {
        // Bound on the growth exponent 0.75: halfway between a random walk (1/2) and a linear
        // drift (1). Backward error analysis bounds the energy error of a symplectic method only
        // for smooth forces; a Hertz contact force is only C^1 where contacts open and close,
        // and each such event leaves a small local error of random sign, so a random walk
        // (1/2) is the expected worst case, while a drift is a defect.
        let ok = growth < 0.75;
        record_one(
            Row::new(
                "energy error does not drift",
                params,
                "symplectic methods: no secular energy drift",
            )
            .expected("growth exponent < 0.75 (bounded 0, random walk 0.5, drift 1)")
            .measured(measured)
            .tolerance("0.75")
            .pass(ok),
        );
        assert!(
            ok,
            "{method:?}: energy error grows with exponent {growth}: {tenths:?}"
        );
    } else {
        record_one(
            Row::new(
                "energy error (non-symplectic, reported)",
                params,
                "no conservation law for this method",
            )
            .expected("drift allowed")
            .measured(measured)
            .tolerance("n/a")
            .info(),
        );
    }
}
case_1(Method::Verlet, 10_000_000),
case_2(Method::BlanesMoan4, 10_000_000),
case_3(Method::Gear5, 1_000_000),
}

/// Run `state` forward for `duration`, flip the velocities, run again, flip back.
fn there_and_back(chain: &Chain, state: &State, method: Method, dt: f64, duration: f64) -> State {
    let run = |s: &State| -> State {
        let mut b = SimulationBuilder::new(chain.clone())
            .params(params(method, dt))
            .schedule(duration, duration);
        for i in 0..s.u.len() {
            b = b.displacement(i, s.u[i]).velocity(i, s.v[i]);
        }
        let mut sim = b.build().unwrap();
        sim.run(|_| Ok::<(), RunError>(())).unwrap();
        sim.state().clone()
    };
    let mut mid = run(state);
    mid.v.iter_mut().for_each(|v| *v = -*v);
    let mut end = run(&mid);
    end.v.iter_mut().for_each(|v| *v = -*v);
    end
}

cases! {
/// Check 9c: the time-reversible methods run forward and then backward return to the initial
/// state. A solitary wave in a 60-grain Hertz chain, 20,000 steps each way.
fn forward_then_backward(method: Method) {
    let chain = ChainBuilder::new()
        .grains(60, 1.0, ContactLaw::hertz(1.0))
        .build()
        .unwrap();
    let mut start = State::at_rest(60);
    start.v[0] = 1.0;
    start.u[5] = 0.3; // a compressed contact as well
    let dt = 5e-3;
    let end = there_and_back(&chain, &start, method, dt, 100.0);
    let du = start
        .u
        .iter()
        .zip(&end.u)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let dv = start
        .v
        .iter()
        .zip(&end.v)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let steps = 2.0 * 100.0 / dt;
    // Tolerance: in exact arithmetic the return is exact (the methods are symmetric). Round-off
    // adds about eps per operation per step and the chain's dynamics (a wave on a line, not
    // chaotic) does not amplify it exponentially; 100 eps per step over 40,000 steps is 1e-9 of
    // the unit speed and displacement scale.
    let tol = 100.0 * f64::EPSILON * steps;
    let ok = du <= tol && dv <= tol;
    record_one(
        Row::new(
            "forward then backward returns to the start",
            format!("{}, 60 grains, 2 x 20000 steps", method.name()),
            "exact: time-reversible method",
        )
        .expected("0")
        .measured(format!("max |du| {du:.1e}, |dv| {dv:.1e}"))
        .tolerance(format!("{tol:.1e} (100 eps per step)"))
        .pass(ok),
    );
    assert!(ok, "{method:?}: du {du:e} dv {dv:e}");
}
case_1(Method::Verlet),
case_2(Method::BlanesMoan4),
}

/// Hong's Fig. 1 layout (heavy m = 10 to light m = 1, Hertz, eta = 5657, striker of the heavy
/// mass at speed 1), kept here rather than read from scenes/ so that edits of the shipped scenes
/// do not move these checks.
const HEAVY_TO_LIGHT: &str = r#"
[chain]
[[chain.sections]]
count = 100
mass = 10.0
p = 1.5
eta = 5657.0
[[chain.sections]]
count = 900
mass = 1.0
p = 1.5
eta = 5657.0
[striker]
end = "left"
mass = 10.0
speed = 1.0
[integrator]
method = "verlet"
dt = 1e-4
[run]
duration = 12.0
output_interval = 0.125
[[regions]]
name = "light"
first = 101
last = 1000
"#;

/// The standard container (a) of Hong's Fig. 3 in the reconstructed layout of
/// docs/containers.md (linear walls m = 10; min-exponent interfaces; 120 outer
/// grains of m = 100 each side; striker m = 100 at speed 10 on the right), 280 snapshots.
fn container_scene() -> String {
    let mut s = String::from("[chain]\ninterface = \"min-exponent\"\n");
    let sec = |s: &mut String, n: u32, m: f64, p: f64| {
        s.push_str(&format!(
            "[[chain.sections]]\ncount = {n}\nmass = {m:?}\np = {p:?}\neta = 5657.0\n"
        ));
    };
    sec(&mut s, 120, 100.0, 1.5);
    for (m, p) in [
        (10.0, 1.0),
        (1.0, 1.5),
        (0.5, 2.0),
        (0.1, 1.5),
        (10.0, 1.0),
        (0.1, 1.5),
        (0.5, 2.0),
        (1.0, 1.5),
        (10.0, 1.0),
    ] {
        sec(&mut s, 20, m, p);
    }
    sec(&mut s, 120, 100.0, 1.5);
    s.push_str(
        "[striker]\nend = \"right\"\nmass = 100.0\nspeed = 10.0\n[integrator]\n\
         method = \"verlet\"\ndt = 1e-4\n[run]\nduration = 35.0\noutput_interval = 0.125\n\
         [[regions]]\nname = \"container\"\nfirst = 121\nlast = 300\n",
    );
    s
}

fn parse(text: &str, name: &str) -> Scene {
    Scene::parse(text, std::path::Path::new(name)).unwrap()
}

/// Bits of the state and totals at every output of a scene run, and the work done.
fn fingerprint(sc: &Scene) -> (Vec<u64>, u64) {
    let mut sim = sc.simulation().unwrap();
    let mut bits = Vec::new();
    sim.run(|fr: &Frame| {
        bits.push(fr.totals.total.to_bits());
        bits.push(fr.totals.momentum.to_bits());
        Ok::<(), RunError>(())
    })
    .unwrap();
    let st = sim.state();
    bits.extend(st.u.iter().map(|x| x.to_bits()));
    bits.extend(st.v.iter().map(|x| x.to_bits()));
    (bits, sim.stats().grain_evals)
}

cases! {
/// Check 11a: a scene run with and without skipping of untouched grains gives the identical
/// state, bit for bit, at every output, for every method.
fn skipping_is_exact(name: &str, method: Method) {
    let mut sc = if name == "container" {
        parse(&container_scene(), "container.toml")
    } else {
        parse(HEAVY_TO_LIGHT, "heavy-to-light.toml")
    };
    let params = IntegrationParams {
        method,
        rtol: 1e-8,
        atol: 1e-10,
        skip_untouched: true,
        ..*sc.params()
    };
    sc.set_params(params).unwrap();
    // Long enough for the waves to cross interfaces; short enough for the whole grid to run in
    // seconds without skipping.
    sc.set_schedule(4.0, 0.25).unwrap();
    let (a, work_a) = fingerprint(&sc);
    sc.set_params(IntegrationParams {
        skip_untouched: false,
        ..params
    })
    .unwrap();
    let (b, work_b) = fingerprint(&sc);
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count() + a.len().abs_diff(b.len());
    let ok = differ == 0;
    record_one(
        Row::new(
            "skipping untouched grains is exact",
            format!("{name}, {}, t=4", method.name()),
            "exact by construction (ARCHITECTURE.md)",
        )
        .expected("identical bits")
        .measured(format!(
            "{differ} of {} numbers differ; work with/without skipping {:.2}",
            a.len(),
            work_a as f64 / work_b as f64
        ))
        .tolerance("0 bits")
        .pass(ok),
    );
    assert!(ok, "{name} {method:?}: {differ} numbers differ");
}
case_1("heavy-to-light", Method::Verlet),
case_2("heavy-to-light", Method::BlanesMoan4),
case_3("heavy-to-light", Method::Gear5),
case_4("heavy-to-light", Method::Dopri5),
case_5("container", Method::Verlet),
case_6("container", Method::BlanesMoan4),
case_7("container", Method::Gear5),
case_8("container", Method::Dopri5),
}

/// Region energy (the scene's one region) at every output, and the initial energy and work.
fn region_series(sc: &Scene, sleep: Option<Sleep>, dt: f64) -> (Vec<f64>, f64, u64) {
    let mut params = *sc.params();
    params.sleep = sleep;
    params.dt = dt;
    // The scene's chain and striker, with these integration parameters.
    let chain = sc.simulation().unwrap().chain().clone();
    let r = &sc.regions()[0];
    let (a, b) = (
        chain.index_of(r.first).unwrap(),
        chain.index_of(r.last).unwrap(),
    );
    let (striker, speed) = chain.striker().unwrap();
    let mut sim = SimulationBuilder::new(chain)
        .params(params)
        .schedule(sc.duration(), sc.output_interval())
        .velocity(striker, speed)
        .build()
        .unwrap();
    let mut e = Vec::new();
    sim.run(|fr: &Frame| {
        e.push(grainchain_engine::region_energy(
            fr.chain, fr.state, fr.window, a, b,
        ));
        Ok::<(), RunError>(())
    })
    .unwrap();
    (e, sim.initial_energy(), sim.stats().grain_evals)
}

fn max_diff(a: &[f64], b: &[f64], upto: usize, scale: f64) -> f64 {
    a.iter()
        .zip(b)
        .take(upto)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

cases! {
/// Check 11b: the error sleep thresholds add, on the heavy-to-light scene (a wave train, no
/// sensitive dependence): the light section's energy at every output against the run without
/// sleep, relative to the incident energy.
fn sleep_error_wave_train(threshold: f64) {
    let sc = parse(HEAVY_TO_LIGHT, "heavy-to-light.toml");
    let dt = sc.params().dt;
    let (exact, e0, work0) = region_series(&sc, None, dt);
    let sleep = Sleep {
        velocity: threshold,
        force: threshold,
    };
    let (slept, _, work1) = region_series(&sc, Some(sleep), dt);
    let (half, _, _) = region_series(&sc, None, dt / 2.0);
    let err = max_diff(&exact, &slept, usize::MAX, e0);
    let integ = max_diff(&exact, &half, usize::MAX, e0);
    // Bound 1e-4 of the incident energy: the accuracy the paper's E_R(t) curves are held to
    // (issue 3: within 1e-4 relative of a run at an eighth of the step); sleep must not use more
    // than that. The step-halving change of the same quantity is reported beside it.
    let bound = 1e-4;
    let ok = err <= bound;
    record_one(
        Row::new(
            "sleep threshold error (wave train)",
            format!("heavy-to-light m 10:1, 96 outputs, velocity=force={threshold:e}"),
            "bound: the E_R accuracy the reproduction needs",
        )
        .expected("< 1e-4 of E0")
        .measured(format!(
            "max |dE_light|/E0 = {err:.1e} (halving dt changes it by {integ:.1e}); work {:.3} of \
             no-sleep",
            work1 as f64 / work0 as f64
        ))
        .tolerance(format!("{bound:e}"))
        .pass(ok),
    );
    assert!(ok, "sleep {threshold:e}: error {err:e}");
}
case_1(1e-9),
case_2(1e-6),
case_3(1e-4),
}

cases! {
/// Check 11c: sleep in the standard container (Fig. 3 layout). The container's energy depends
/// sensitively on small perturbations (halving the step changes E_container by ~1e-6 of E0 up to
/// snapshot 160 but by ~1e-2 by snapshot 280), so the sleep error is compared with the
/// integrator's own error, the step-halving change, over the first 200 snapshots; the whole run
/// is reported.
fn sleep_error_container(threshold: f64) {
    let sc = parse(&container_scene(), "container.toml");
    let dt = sc.params().dt;
    let (exact, e0, work0) = region_series(&sc, None, dt);
    let sleep = Sleep {
        velocity: threshold,
        force: threshold,
    };
    let (slept, _, work1) = region_series(&sc, Some(sleep), dt);
    let (half, _, _) = region_series(&sc, None, dt / 2.0);
    let upto = 201;
    let err = max_diff(&exact, &slept, upto, e0);
    let integ = max_diff(&exact, &half, upto, e0);
    let err_all = max_diff(&exact, &slept, usize::MAX, e0);
    let integ_all = max_diff(&exact, &half, usize::MAX, e0);
    // Bound: the step-halving change over the same outputs. Sleep is an approximation of the
    // same kind as the step; it must cost less accuracy than the integrator already does.
    let ok = err <= integ;
    record_one(
        Row::new(
            "sleep threshold error (container)",
            format!("Fig. 3 layout, snapshots 0-200, velocity=force={threshold:e}"),
            "bound: the integrator's own error (dt vs dt/2)",
        )
        .expected(format!("<= {integ:.1e} of E0 (dt halving)"))
        .measured(format!(
            "{err:.1e}; to snapshot 280: {err_all:.1e} (dt halving {integ_all:.1e}); work {:.3} \
             of no-sleep",
            work1 as f64 / work0 as f64
        ))
        .tolerance("step-halving change")
        .pass(ok),
    );
    assert!(
        ok,
        "sleep {threshold:e}: error {err:e} > integrator error {integ:e}"
    );
}
case_1(1e-9),
case_2(1e-6),
}
