//! The numbers of issue 41's closing note, for the best designs of `designs/multi-material.toml`
//! and `designs/steel-ptfe.toml` (their genes as `grainchain design` found them): the peak's
//! first-order spread from its gradients and a seeded Monte Carlo of 1,000 perturbed columns
//! under 1 % diameter and 5 % modulus tolerances (each bead drawn independently), the three
//! beads and properties that dominate the spread, and the nominal peak before and after the
//! gradient refinement (diameters free in the catalogue's range, 4-8 mm, for multi-material;
//! 5-7 mm for steel-ptfe, whose catalogue has one size). Each part is timed.
//! Run: `cargo run --release --example protector_tolerances` (minutes on 2 cores).

use grainchain::design::file::DesignSpec;
use grainchain::design::refine::refine;
use grainchain::design::search::{reference, settings};
use grainchain::design::tolerance::{spread, Tolerances};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let threads = 2;
    for (file, genes, range) in [
        (
            "designs/multi-material.toml",
            vec![16, 3, 5, 16, 3, 16, 16, 16, 16, 16],
            [0.004, 0.008],
        ),
        (
            "designs/steel-ptfe.toml",
            vec![1, 1, 0, 1, 0, 0, 1, 1],
            [0.005, 0.007],
        ),
    ] {
        let spec = DesignSpec::load(file)?;
        let beads = spec.beads(&genes);
        let s = settings(&spec);
        let impact = spec.impacts[0].clone();
        let tol = Tolerances {
            diameter: 0.01,
            young: 0.05,
            density: 0.0,
            speed: 0.0,
            samples: 1000,
            seed: 1,
        };
        let t0 = Instant::now();
        let one = grainchain_engine::protector::evaluate(&beads, &impact, &spec.protected, &s)?;
        let t_eval = t0.elapsed().as_secs_f64();
        let t0 = Instant::now();
        let sp = spread(&beads, &impact, &spec.protected, &s, &tol, threads)?;
        let t_spread = t0.elapsed().as_secs_f64();
        println!("== {file}: the best design ({} beads)", beads.len());
        println!(
            "nominal peak {:.6} N (complete: {}), one evaluation {:.3} s",
            one.peak_force, one.complete, t_eval
        );
        println!(
            "first order: sd {:.6} N ({:.3} %), p95 {:.6} N",
            sp.first.sd,
            100.0 * sp.first.sd / sp.first.peak,
            sp.first.p95()
        );
        let mc = &sp.monte_carlo;
        println!(
            "Monte Carlo ({} columns, {} bounds): mean {:.6} N, sd {:.6} N, p95 {:.6} N",
            mc.samples, mc.bounds, mc.mean, mc.sd, mc.p95
        );
        for t in sp.first.top(3) {
            println!(
                "  bead {} {}: {:.1} % of the first-order variance",
                t.bead.map_or("-".to_string(), |b| (b + 1).to_string()),
                t.property.name(),
                100.0 * t.variance / (sp.first.sd * sp.first.sd)
            );
        }
        println!("tolerance analysis: {t_spread:.1} s on {threads} threads");
        let t0 = Instant::now();
        let r = reference(&spec)?;
        let refined = refine(&spec, &beads, &r, range, 10)?;
        let after =
            grainchain_engine::protector::evaluate(&refined.beads, &impact, &spec.protected, &s)?;
        println!(
            "refinement in [{}, {}] mm: objective {:.5} -> {:.5}, peak {:.6} N -> {:.6} N, \
             mass {:.2} g -> {:.2} g, {} iterations, {} runs with gradients, {:.1} s: {}",
            range[0] * 1e3,
            range[1] * 1e3,
            refined.before,
            refined.after,
            one.peak_force,
            after.peak_force,
            beads.iter().map(|b| b.mass()).sum::<f64>() * 1e3,
            refined.beads.iter().map(|b| b.mass()).sum::<f64>() * 1e3,
            refined.iterations,
            refined.runs,
            t0.elapsed().as_secs_f64(),
            refined.stopped
        );
    }
    Ok(())
}
