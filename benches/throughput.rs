//! Integrator throughput: nanoseconds per grain-step for every integrator and contact law on
//! all-moving chains of 100 to 100,000 grains.
//!
//! Benchmark ids are stable (`throughput/<method>/p<exponent>/<grains>`) so baselines compare
//! across commits: `cargo bench --bench throughput -- --save-baseline main`, then on a branch
//! `cargo bench --bench throughput -- --baseline main`. Criterion's throughput is in grain-steps
//! per second: ns per grain-step = 1e9 / (elements/s).

mod common;

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};
use grainchain_engine::Method;
use std::time::Duration;

fn throughput(c: &mut Criterion) {
    for method in Method::SINGLE_RATE {
        let mut g = c.benchmark_group(format!("throughput/{}", method.name()));
        g.warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(1))
            .sample_size(10);
        for p in [1.0, 1.5, 2.0, 2.5] {
            for n in [100usize, 1_000, 10_000, 100_000] {
                let (chain, s0) = common::all_moving(n, p);
                let prm = common::params(method);
                // About 2e6 grain-steps per iteration.
                let t = prm.dt * (2_000_000 / n).max(10) as f64;
                // The same work every iteration: count it once.
                let steps = common::advance(&chain, &s0, &prm, t).steps;
                g.throughput(Throughput::Elements(steps * n as u64));
                g.bench_with_input(BenchmarkId::new(format!("p{p}"), n), &n, |b, _| {
                    b.iter_batched(
                        || (),
                        |_| common::advance(&chain, &s0, &prm, t),
                        BatchSize::PerIteration,
                    )
                });
            }
        }
        g.finish();
    }
}

criterion_group!(benches, throughput);
criterion_main!(benches);
