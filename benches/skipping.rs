//! Skipping untouched grains: one solitary wave followed for 5,000 grains in chains of 10^4 to
//! 10^6 grains (the cost must not grow with the chain). Controls: the same wave with skipping
//! switched off (what skipping saves), and precompressed chains whose every grain moves at t = 0
//! (nothing is untouched, so the cost grows with the chain length).
//!
//! The issue-2 target: the 10^6-grain run costs at most twice the 10^4-grain run. Compare the
//! medians of `skipping/single-wave-5000/1000000` and `.../10000` from one run.

mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use grainchain_engine::State;
use grainchain_engine::{self, IntegrationParams, Method, Stats};
use grainchain_engine::{ChainBuilder, ContactLaw, End, Window};
use std::hint::black_box;
use std::time::Duration;

fn wave_run(chain: &grainchain_engine::Chain, n: usize, skip: bool) -> u64 {
    // The whole run, allocation of the state included: a user pays for it too.
    let p = IntegrationParams {
        method: Method::Verlet,
        dt: 2e-3,
        skip_untouched: skip,
        ..Default::default()
    };
    let mut integ = grainchain_engine::make_integrator(&p, n);
    let mut state = State::at_rest(n);
    state.v[0] = 1.0;
    let mut win = Window::seed(chain, &state.u, &state.v, skip, p.method.uses_islands());
    let mut stats = Stats::default();
    integ.init(chain, &state, &mut win, &mut stats);
    // Follow the wave until its front passes grain 5,000 (the window of a skipping run tracks
    // the front; the same number of steps is taken without skipping).
    while state.v[..5000.min(n)]
        .iter()
        .rposition(|&x| x != 0.0)
        .unwrap_or(0)
        < 4990
    {
        let t = state.t + 0.5;
        integ
            .advance_to(chain, &mut state, &mut win, t, &mut stats)
            .unwrap();
    }
    black_box(stats.steps)
}

fn single_wave(c: &mut Criterion) {
    let law = ContactLaw::hertz(5657.0);
    for (name, skip, sizes) in [
        (
            "skipping/single-wave-5000",
            true,
            &[10_000usize, 100_000, 1_000_000][..],
        ),
        (
            "skipping/single-wave-5000-noskip",
            false,
            &[10_000usize, 100_000][..],
        ),
    ] {
        let mut g = c.benchmark_group(name);
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(4));
        for &n in sizes {
            let chain = ChainBuilder::new().grains(n, 1.0, law).build().unwrap();
            g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                b.iter(|| wave_run(&chain, n, skip))
            });
        }
        g.finish();
    }
}

fn precompressed_control(c: &mut Criterion) {
    let mut g = c.benchmark_group("skipping/precompressed-control");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    for n in [10_000usize, 100_000] {
        let law = ContactLaw::hertz(5657.0).with_precompression(0.01);
        let chain = ChainBuilder::new()
            .grains(n, 1.0, law)
            .left(End::Wall(law))
            .right(End::Wall(law))
            .build()
            .unwrap();
        let mut s0 = State::at_rest(n);
        for (i, v) in s0.v.iter_mut().enumerate() {
            *v = 1e-3 * (0.37 * i as f64).sin();
        }
        let p = IntegrationParams {
            method: Method::Verlet,
            dt: 2e-3,
            ..Default::default()
        };
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| common::advance(&chain, &s0, &p, 200.0 * p.dt));
        });
    }
    g.finish();
}

criterion_group!(benches, single_wave, precompressed_control);
criterion_main!(benches);
