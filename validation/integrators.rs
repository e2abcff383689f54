//! Tests shared by the integrators, through the engine's public API (they drive whole runs, so
//! they live above the `integrators` module, not inside it): exact skipping, orders on a smooth
//! problem, walls, the counters' one-line form.

use grainchain_engine::{
    Chain, ChainBuilder, ContactLaw, End, IntegrationParams, Method, SimulationBuilder, State,
    Stats, Window,
};

fn hertz_chain(n: usize) -> Chain {
    ChainBuilder::new()
        .grains(n, 1.0, ContactLaw::hertz(5657.0))
        .build()
        .unwrap()
}

fn run(
    chain: Chain,
    p: IntegrationParams,
    t: f64,
    kick: &[(usize, f64)],
) -> (State, Stats, Window) {
    let mut b = SimulationBuilder::new(chain).params(p).schedule(t, t / 4.0);
    for &(i, v) in kick {
        b = b.velocity(i, v);
    }
    let mut sim = b.build().unwrap();
    sim.run(|_| Ok::<(), grainchain_engine::RunError>(()))
        .unwrap();
    (sim.state().clone(), *sim.stats(), sim.window().clone())
}

fn params(method: Method, skip: bool) -> IntegrationParams {
    IntegrationParams {
        method,
        dt: 2e-4,
        rtol: 1e-7,
        atol: 1e-9,
        skip_untouched: skip,
        ..Default::default()
    }
}

/// Every single-rate method, and those that take contact events with them on.
fn methods_and_events() -> Vec<(Method, bool)> {
    let mut v: Vec<(Method, bool)> = Method::SINGLE_RATE.iter().map(|&m| (m, false)).collect();
    v.extend(
        Method::SINGLE_RATE
            .iter()
            .filter(|m| m.information().events)
            .map(|&m| (m, true)),
    );
    v
}

#[test]
fn skipping_is_bit_for_bit_exact() {
    for (m, events) in methods_and_events() {
        let with = |skip| IntegrationParams {
            events,
            ..params(m, skip)
        };
        let (a, sa, wa) = run(hertz_chain(200), with(true), 0.5, &[(0, 1.0)]);
        let (b, sb, _) = run(hertz_chain(200), with(false), 0.5, &[(0, 1.0)]);
        assert_eq!(sa.steps, sb.steps, "{m:?}: accepted steps differ");
        assert_eq!(sa.rejected, sb.rejected, "{m:?}");
        for i in 0..200 {
            assert_eq!(a.u[i].to_bits(), b.u[i].to_bits(), "{m:?}: u[{i}]");
            assert_eq!(a.v[i].to_bits(), b.v[i].to_bits(), "{m:?}: v[{i}]");
        }
        // Something was skipped, and the wave is inside the window.
        assert!(wa.hi < 200 && wa.hi > 5, "{m:?}: window {wa:?}");
        assert!(sa.grain_evals < sb.grain_evals / 4, "{m:?}");
        // With events the pieces add force evaluations: steps were cut.
        if events {
            let (_, plain, _) = run(hertz_chain(200), params(m, true), 0.5, &[(0, 1.0)]);
            assert!(sa.force_evals > plain.force_evals, "{m:?}: no step was cut");
        }
    }
}

/// A two-grain linear spring: u1 - u0 oscillates with omega = sqrt(2 k / m).
fn oscillator_error(m: Method, dt: f64) -> f64 {
    let chain = ChainBuilder::new()
        .grains(2, 1.0, ContactLaw::linear_spring(1.0))
        .build()
        .unwrap();
    let p = IntegrationParams {
        method: m,
        dt,
        rtol: dt,
        atol: dt * 1e-3,
        ..Default::default()
    };
    let (s, _, _) = run(chain, p, 4.0, &[(0, 1.0)]);
    let w = 2f64.sqrt();
    // Relative coordinate x = u0 - u1 starts at 0 with speed 1: x = sin(w t)/w.
    let exact = (w * 4.0).sin() / w;
    ((s.u[0] - s.u[1]) - exact).abs()
}

#[test]
fn orders_on_a_smooth_problem() {
    for m in [Method::Verlet, Method::BlanesMoan4, Method::Gear5] {
        let e1 = oscillator_error(m, 0.02);
        let e2 = oscillator_error(m, 0.01);
        let order = (e1 / e2).log2();
        // Within 0.3 of nominal at these step sizes (the full convergence study is in
        // validation/; this guards the coefficients).
        assert!(
            (order - m.nominal_order() as f64).abs() < 0.3,
            "{m:?}: order {order} ({e1:e}, {e2:e})"
        );
    }
}

#[test]
fn walls_reflect_and_energy_is_conserved() {
    let law = ContactLaw::hertz(5657.0);
    let chain = ChainBuilder::new()
        .grains(20, 1.0, law)
        .left(End::Wall(law))
        .right(End::Wall(law))
        .build()
        .unwrap();
    for m in Method::SINGLE_RATE {
        let p = IntegrationParams {
            method: m,
            dt: 1e-4,
            rtol: 1e-9,
            atol: 1e-12,
            ..Default::default()
        };
        let mut sim = SimulationBuilder::new(chain.clone())
            .params(p)
            .schedule(2.0, 0.5)
            .velocity(3, 1.0)
            .build()
            .unwrap();
        sim.run(|_| Ok::<(), grainchain_engine::RunError>(()))
            .unwrap();
        // 2 time units is about 10 wall-to-wall crossings: the energy error stays at the
        // integrator's level (1e-5 covers Gear5's drift; the symplectic ones are far below).
        assert!(
            sim.max_energy_error() < 1e-5,
            "{m:?}: {}",
            sim.max_energy_error()
        );
    }
}

#[test]
fn stats_and_timings_print_on_one_line() {
    let s = Stats {
        steps: 640000,
        force_evals: 3840001,
        grain_evals: 10_358_764_782,
        window_evals: 10_358_764_782 - 2 * 3840001,
        max_window: 5399,
        ..Default::default()
    };
    assert_eq!(
        s.to_string(),
        "640000 steps (0 rejected), 3840001 force evaluations, 1.036e10 grain evaluations, mean \
         window 2696, max 5399"
    );
    let t = grainchain_engine::Timings {
        integrate: std::time::Duration::from_millis(12048),
        checks: std::time::Duration::from_millis(155),
        output: std::time::Duration::from_millis(88),
    };
    assert_eq!(
        t.to_string(),
        "integrate 12.048 s, checks 0.155 s, output 0.088 s"
    );
}

/// The mean window counts what the max counts (integrated grains, margins not): on a two-grain
/// collision it was 4 (the two grains and the two margin evaluations) beside a max of 2.
#[test]
fn mean_window_is_never_above_max_window() {
    let mut sim = grainchain_engine::problems::TwoGrainCollision::default()
        .builder()
        .unwrap()
        .build()
        .unwrap();
    sim.run(|_| Ok::<(), grainchain_engine::RunError>(()))
        .unwrap();
    let st = sim.stats();
    assert_eq!(st.max_window, 2);
    assert!(st.mean_window() <= st.max_window as f64, "{st}");
    assert!(st.grain_evals > st.window_evals, "{st}");
}
