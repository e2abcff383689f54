//! Evaluating granular protectors (`grainchain_engine::protector`): what one evaluation of a
//! design costs, the quantity a design search pays 100,000 times.
//!
//! - `protector/reference`: the issue-27 target case, 20 steel then 20 PTFE beads of 6 mm (the
//!   design of `examples/protector.rs`; `protector::Case::steel_then_ptfe(40)`) against a steel wall, struck by a 6 mm steel sphere at
//!   1 m/s; `Settings::default()` (the peak, exact stop); one evaluation per iteration, one
//!   thread. Target: at most 5 ms median.
//! - `protector/reference-verlet160`: the same with velocity Verlet at 160 steps per contact
//!   time and no contact events, the default before events (issue 40), for the ratio.
//! - `protector/reference-gradients`: the reference's evaluation with every derivative of its
//!   numbers (`protector::gradients`: the run recorded, then one sweep back carrying five
//!   adjoints), for its cost against `protector/reference`.
//! - `protector/reference-gradients-forward`: the same by forward mode
//!   (`protector::gradients_forward`: 41 masses, 41 Hertz constants, the speed and the step
//!   carried through the run), the reverse run's oracle, for the ratio.
//! - `protector/beads/<n>`: the same half steel, half PTFE pattern at 10 to 160 beads (the cost
//!   per evaluation against the bead count).
//! - `protector/many64/<threads>`: `evaluate_many` of 64 random designs (seeded: 5-40 beads of
//!   steel, PTFE, brass or tungsten carbide, 3-9 mm) on 1 and 2 threads.
//!
//! Ids are stable, so a branch compares against a saved baseline (`-- --save-baseline main`,
//! then `-- --baseline main`).

use criterion::{
    criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode, Throughput,
};
use grainchain_engine::protector::{
    evaluate_many, gradients, gradients_forward, Bead, Case, Settings,
};
use grainchain_engine::units::{BRASS, PTFE, STEEL, TUNGSTEN_CARBIDE};
use rand::{Rng, SeedableRng};
use std::hint::black_box;
use std::time::Duration;

/// 64 random designs (seed 27): 5-40 beads of four materials, 3-9 mm.
fn random_designs() -> Vec<Vec<Bead>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(27);
    let materials = [STEEL, PTFE, BRASS, TUNGSTEN_CARBIDE];
    (0..64)
        .map(|_| {
            let n = rng.gen_range(5..=40);
            (0..n)
                .map(|_| Bead {
                    material: materials[rng.gen_range(0..materials.len())],
                    diameter: [3e-3, 4.5e-3, 6e-3, 9e-3][rng.gen_range(0..4)],
                })
                .collect()
        })
        .collect()
}

fn protector(c: &mut Criterion) {
    let settings = Settings::default();
    // The load and the wall of every group: the reference case's.
    let (imp, wall) = {
        let c = Case::steel_then_ptfe(40);
        (c.impact, c.protected)
    };
    let mut g = c.benchmark_group("protector");
    g.warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .sample_size(30);
    let reference = Case::steel_then_ptfe(40);
    g.bench_function("reference", |b| {
        b.iter(|| black_box(&reference).evaluate(&settings).unwrap())
    });
    let before = Settings {
        method: grainchain_engine::Method::Verlet,
        events: false,
        steps_per_contact: 160.0,
        ..settings
    };
    g.bench_function("reference-verlet160", |b| {
        b.iter(|| black_box(&reference).evaluate(&before).unwrap())
    });
    g.bench_function("reference-gradients", |b| {
        let r = black_box(&reference);
        b.iter(|| gradients(&r.beads, &r.impact, &r.protected, &settings).unwrap())
    });
    g.bench_function("reference-gradients-forward", |b| {
        let r = black_box(&reference);
        b.iter(|| gradients_forward(&r.beads, &r.impact, &r.protected, &settings).unwrap())
    });
    g.finish();

    // From 80 beads on, an evaluation runs to the time cap (about 0.1 s: BENCHMARKS.md), and a
    // batch of 64 takes seconds: flat sampling, 10 samples, so the group ends in about a minute.
    let mut g = c.benchmark_group("protector/beads");
    g.warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .sampling_mode(SamplingMode::Flat)
        .sample_size(10);
    for n in [10usize, 20, 40, 80, 160] {
        let case = Case::steel_then_ptfe(n);
        g.bench_with_input(BenchmarkId::from_parameter(n), &case, |b, case| {
            b.iter(|| black_box(case).evaluate(&settings).unwrap())
        });
    }
    g.finish();

    let designs = random_designs();
    let mut g = c.benchmark_group("protector/many64");
    g.warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(5))
        .sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .throughput(Throughput::Elements(designs.len() as u64));
    for threads in [1usize, 2] {
        g.bench_with_input(
            BenchmarkId::from_parameter(threads),
            &threads,
            |b, &threads| {
                b.iter(|| {
                    let r = evaluate_many(black_box(&designs), &imp, &wall, &settings, threads);
                    // Every design evaluates (an error would time a short cut, not the work).
                    assert!(r.unwrap().iter().all(Result::is_ok));
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, protector);
criterion_main!(benches);
