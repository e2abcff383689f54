//! Issue-2 speed targets: Velocity Verlet throughput on an all-moving Hertz chain, and the cost
//! of one solitary wave in a long chain against a short one (skipping untouched grains).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use grainchain::chain::{ChainBuilder, ContactLaw, End, Window};
use grainchain::integrators::{self, IntegrationParams, Method, Stats};
use grainchain::state::State;
use std::hint::black_box;

/// A Hertz chain between two walls with every grain moving (deterministic velocities).
fn all_moving(n: usize) -> (grainchain::Chain, State) {
    let law = ContactLaw::hertz(5657.0);
    let chain = ChainBuilder::new()
        .grains(n, 1.0, law)
        .left(End::Wall(law))
        .right(End::Wall(law))
        .build()
        .unwrap();
    let mut s = State::at_rest(n);
    for i in 0..n {
        s.v[i] = 0.5 * (0.37 * i as f64).sin() + 0.01;
    }
    (chain, s)
}

fn verlet_throughput(c: &mut Criterion) {
    let mut g = c.benchmark_group("core/verlet-hertz-all-moving");
    for n in [1000usize] {
        let (chain, s0) = all_moving(n);
        let steps = 200u64;
        g.throughput(Throughput::Elements(n as u64 * steps));
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            let p = IntegrationParams {
                method: Method::Verlet,
                dt: 1e-4,
                ..Default::default()
            };
            let mut integ = integrators::make(&p, n);
            let mut state = s0.clone();
            let mut win = Window::seed(&chain, &state.u, &state.v, true);
            let mut stats = Stats::default();
            integ.init(&chain, &state, &mut win, &mut stats);
            b.iter(|| {
                let t = state.t + steps as f64 * p.dt;
                integ
                    .advance_to(&chain, &mut state, &mut win, t, &mut stats)
                    .unwrap();
                black_box(&state.v[0]);
            });
        });
    }
    g.finish();
}

fn single_wave(c: &mut Criterion) {
    let mut g = c.benchmark_group("core/single-wave-5000-grains");
    g.sample_size(10);
    for n in [10_000usize, 1_000_000] {
        let law = ContactLaw::hertz(5657.0);
        let chain = ChainBuilder::new().grains(n, 1.0, law).build().unwrap();
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                let p = IntegrationParams {
                    method: Method::Verlet,
                    dt: 2e-3,
                    ..Default::default()
                };
                let mut integ = integrators::make(&p, n);
                let mut state = State::at_rest(n);
                state.v[0] = 1.0;
                let mut win = Window::seed(&chain, &state.u, &state.v, true);
                let mut stats = Stats::default();
                integ.init(&chain, &state, &mut win, &mut stats);
                // Advance until the wave front passes grain 5,000.
                while win.hi < 5000 {
                    let t = state.t + 0.5;
                    integ
                        .advance_to(&chain, &mut state, &mut win, t, &mut stats)
                        .unwrap();
                }
                black_box(stats.steps)
            });
        });
    }
    g.finish();
}

criterion_group!(benches, verlet_throughput, single_wave);
criterion_main!(benches);
