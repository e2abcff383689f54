//! Designs per second on random columns (issue 49, item 4): 200 random 40-bead columns, each
//! bead steel or PTFE with a diameter drawn uniformly from 4 to 8 mm (ChaCha8, seed 49), a 6 mm
//! steel striker at 1 m/s, a steel wall, a time cap of 3 contact-time sums and the default
//! settings otherwise (blanes-moan4 with contact events at 20 steps per contact time), evaluated
//! by `protector::evaluate_many` on 1 and 2 threads. Prints the wall time (median of `ROUNDS`),
//! designs per second, the median steps per design and the cost per grain-step, and the
//! reference column's (`Case::steel_then_ptfe(40)`) on one thread for comparison, by method
//! with and without events. With `--errors`, also each setting's designs per second (1 thread,
//! one round) and its peaks' median and worst relative error against blanes-moan4 with events at
//! 640 steps per contact time: which settings are cheaper than the default at its accuracy.
//! Run: `cargo run --release --example random_columns [-- --errors]`.

use grainchain_engine::protector::{evaluate_many, Bead, Case, Impact, Protected, Settings};
use grainchain_engine::units::{PTFE, STEEL};
use grainchain_engine::Method;
use rand::{Rng, SeedableRng};
use std::time::Instant;

const DESIGNS: usize = 200;
const BEADS: usize = 40;
const ROUNDS: usize = 5;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(49);
    let designs: Vec<Vec<Bead>> = (0..DESIGNS)
        .map(|_| {
            (0..BEADS)
                .map(|_| Bead {
                    material: if rng.gen_bool(0.5) { STEEL } else { PTFE },
                    diameter: rng.gen_range(4e-3..8e-3),
                })
                .collect()
        })
        .collect();
    let impact = Impact {
        striker: Bead {
            material: STEEL,
            diameter: 6e-3,
        },
        speed: 1.0,
        restitution: None,
        restitution_pairs: Vec::new(),
    };
    let wall = Protected::Wall(STEEL);
    let settings = Settings {
        time_cap: 3.0,
        ..Settings::default()
    };
    let mut steps = Vec::new();
    for threads in [1, 2] {
        let times: Vec<f64> = (0..ROUNDS)
            .map(|_| {
                let t0 = Instant::now();
                let out = evaluate_many(&designs, &impact, &wall, &settings, threads).unwrap();
                let dt = t0.elapsed().as_secs_f64();
                steps = out.into_iter().map(|e| e.unwrap().steps as f64).collect();
                dt
            })
            .collect();
        let t = median(times);
        let grain_steps: f64 = steps.iter().sum::<f64>() * (BEADS + 1) as f64;
        println!(
            "random columns, {threads} thread(s): {t:.3} s for {DESIGNS} designs, {:.1} designs/s, \
             median {:.0} steps per design, {:.1} ns per grain-step (of one thread)",
            DESIGNS as f64 / t,
            median(steps.clone()),
            t * threads as f64 / grain_steps * 1e9
        );
    }
    if std::env::args().any(|a| a == "--errors") {
        errors(&designs, &impact, &wall, &settings);
    }
    // The reference column's grain-step by method, with and without events (the default is
    // blanes-moan4 with events): where its cost against the kernel benchmark's goes.
    let case = Case::steel_then_ptfe(40);
    for (method, events) in [
        (Method::Verlet, false),
        (Method::Verlet, true),
        (Method::BlanesMoan4, false),
        (Method::BlanesMoan4, true),
    ] {
        let settings = Settings {
            method,
            events,
            ..Settings::default()
        };
        let times: Vec<(f64, u64)> = (0..ROUNDS * 8 + 1)
            .map(|_| {
                let t0 = Instant::now();
                let e = case.evaluate(&settings).unwrap();
                (t0.elapsed().as_secs_f64(), e.steps)
            })
            .collect();
        let t = median(times.iter().map(|x| x.0).collect());
        let s = times[0].1 as f64;
        println!(
            "reference column (20 steel then 20 PTFE, 6 mm), {}, events {events}, 1 thread: \
             {:.3} ms, {s:.0} steps, {:.2} ns per grain-step",
            method.name(),
            t * 1e3,
            t / (s * 41.0) * 1e9
        );
    }
}

/// Each setting's designs per second on one thread and its peaks' relative errors against a
/// fine run of the same columns.
fn errors(designs: &[Vec<Bead>], impact: &Impact, wall: &Protected, base: &Settings) {
    let peaks = |s: &Settings, threads: usize| -> Vec<f64> {
        evaluate_many(designs, impact, wall, s, threads)
            .unwrap()
            .into_iter()
            .map(|e| e.unwrap().peak_force)
            .collect()
    };
    let fine = peaks(
        &Settings {
            steps_per_contact: 640.0,
            ..*base
        },
        2,
    );
    for (method, events, steps_per_contact) in [
        (Method::BlanesMoan4, true, 20.0),
        (Method::BlanesMoan4, true, 14.0),
        (Method::BlanesMoan4, true, 10.0),
        (Method::BlanesMoan4, false, 20.0),
        (Method::BlanesMoan4, false, 40.0),
        (Method::BlanesMoan4, false, 80.0),
        (Method::Verlet, false, 80.0),
        (Method::Verlet, false, 160.0),
    ] {
        let s = Settings {
            method,
            events,
            steps_per_contact,
            ..*base
        };
        let t0 = Instant::now();
        let got = peaks(&s, 1);
        let t = t0.elapsed().as_secs_f64();
        let mut err: Vec<f64> = got
            .iter()
            .zip(&fine)
            .map(|(p, r)| ((p - r) / r).abs())
            .collect();
        err.sort_by(f64::total_cmp);
        println!(
            "{}, events {events}, {steps_per_contact} steps per contact: {:.1} designs/s (1 thread), \
             peak error median {:.2e}, worst {:.2e}",
            method.name(),
            designs.len() as f64 / t,
            err[err.len() / 2],
            err[err.len() - 1]
        );
    }
}
