//! How fast does a change far out in the outer chains travel back to the container? The
//! measurement behind the causal horizon's speed (`run.horizon`, issue 15).
//!
//! For a container scene: run it once as it is, keeping the bits of E_R (the `container`
//! region's energy) at every snapshot; then, for each cut distance D and cut time k0, run it again
//! and at snapshot k0 drop every grain further than D grains from the container from the
//! integration (`Simulation::drop_outside`: they stay where they are, fixed walls), and find the
//! first snapshot at which E_R differs in any bit. The disturbance starts at the cut when the
//! leaked waves are there (at k0, or when the front of the window first reaches the cut, if
//! later), so the back-signal speed is D / (first difference - start). Both sides are cut at
//! once; the nearer-arriving side decides.
//!
//! ```text
//! cargo run --release --example back_signal -- SNAPSHOTS D1,D2,.. K1,K2,.. SCENE...
//! cargo run --release --example back_signal -- 4000 150,300,600 0,1000,2000 scenes/containers/*.toml
//! ```
//!
//! Prints one row per scene, D and k0: the front's arrival at D (snapshot), the first differing
//! snapshot (or `none` by the end), and the speed in grains per snapshot and per time unit.

use grainchain_engine::region_energy;
use grainchain_engine::Scene;
use std::ops::ControlFlow;
use std::path::Path;

fn list(s: &str) -> Vec<u64> {
    s.split(',')
        .map(|x| x.trim().parse().expect("a number"))
        .collect()
}

/// E_R bits at every snapshot up to `n`, and the first snapshot at which the window (the grains
/// ever integrated) reaches `d` grains from the container on either side, per `d`.
fn reference(scene: &Scene, n: u64, ds: &[u64]) -> (Vec<u64>, Vec<Option<u64>>) {
    let c = scene
        .region_grains("container")
        .expect("a `container` region");
    let (c0, c1) = (*c.start(), *c.end());
    let mut sim = scene.simulation().expect("scene builds");
    let mut bits = Vec::new();
    let mut front = vec![None; ds.len()];
    sim.run_until(|fr| {
        bits.push(region_energy(fr.chain, fr.state, fr.window, c0, c1).to_bits());
        let (lo, hi) = (fr.window.ever_lo, fr.window.ever_hi);
        for (f, &d) in front.iter_mut().zip(ds) {
            let d = d as usize;
            if f.is_none() && (lo + d <= c0 || hi > c1 + d) {
                *f = Some(fr.index);
            }
        }
        if fr.index >= n {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })
    .expect("reference run");
    (bits, front)
}

/// First snapshot at which E_R differs from `bits` when everything beyond `d` grains of the
/// container is dropped at snapshot `k0`.
fn first_difference(scene: &Scene, n: u64, bits: &[u64], d: usize, k0: u64) -> Option<u64> {
    let c = scene
        .region_grains("container")
        .expect("a `container` region");
    let (c0, c1) = (*c.start(), *c.end());
    let mut sim = scene.simulation().expect("scene builds");
    let mut differs = None;
    let mut cut = false;
    loop {
        let finished = sim
            .run_until(|fr| {
                let e = region_energy(fr.chain, fr.state, fr.window, c0, c1).to_bits();
                if e != bits[fr.index as usize] {
                    differs = Some(fr.index);
                    return ControlFlow::Break(());
                }
                if fr.index >= n || (!cut && fr.index == k0) {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            })
            .expect("cut run");
        if differs.is_some() || finished || cut {
            return differs;
        }
        sim.drop_outside(c0.saturating_sub(d), c1 + 1 + d);
        cut = true;
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        eprintln!("usage: back_signal SNAPSHOTS D1,D2,.. K1,K2,.. SCENE...");
        std::process::exit(2);
    }
    let n: u64 = args[0].parse().expect("SNAPSHOTS");
    let ds = list(&args[1]);
    let ks = list(&args[2]);
    println!("| scene | D | cut at | front at D | first difference | start | grains per snapshot | grains per time unit |");
    println!("|---|---|---|---|---|---|---|---|");
    for path in &args[3..] {
        let scene = Scene::load(Path::new(path)).expect("scene");
        let (bits, front) = reference(&scene, n, &ds);
        let dt = scene.output_interval();
        for (i, &d) in ds.iter().enumerate() {
            for &k0 in &ks {
                let first = first_difference(&scene, n, &bits, d as usize, k0);
                let start = front[i].map(|f| f.max(k0));
                let (speed, per_time) = match (first, start) {
                    (Some(f), Some(s)) if f > s => {
                        let v = d as f64 / (f - s) as f64;
                        (format!("{v:.3}"), format!("{:.2}", v / dt))
                    }
                    _ => ("-".into(), "-".into()),
                };
                let show = |x: Option<u64>| x.map_or("none".to_string(), |x| x.to_string());
                println!(
                    "| {} | {d} | {k0} | {} | {} | {} | {speed} | {per_time} |",
                    scene.name(),
                    show(front[i]),
                    show(first),
                    show(start)
                );
            }
        }
    }
}
