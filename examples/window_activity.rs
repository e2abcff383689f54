//! How much of the window is really moving: at every `EVERY`-th output, the integrated grains,
//! the grains faster than 1e-3, 1e-8 and 1e-12, the islands, and the energy of a region.
//! This is the measurement behind the islands issue (BENCHMARKS.md, "Islands"): in the
//! containers' outer chains most of the window is a dense train of waves, not grains at rest.
//!
//! cargo run --release --example window_activity -- scenes/containers/a-standard.toml 500

use grainchain_engine::RunError;
use grainchain_engine::Scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or_else(|| "scenes/containers/a-standard.toml".into());
    let every: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(500);
    let scene = Scene::load(&path)?;
    let region = scene.regions().first().cloned();
    let mut sim = scene.simulation()?;
    let range = region
        .as_ref()
        .and_then(|r| Some(sim.chain().index_of(r.first)?..sim.chain().index_of(r.last)? + 1));
    println!("output,integrated,islands,faster_1e-3,faster_1e-8,faster_1e-12,region_energy");
    sim.run(|fr| {
        if fr.index % every != 0 {
            return Ok::<(), RunError>(());
        }
        let v = &fr.state.v;
        let count = |thr: f64| fr.window.range().filter(|&i| v[i].abs() > thr).count();
        let e: f64 = range.clone().map_or(0.0, |r| {
            r.map(|i| grainchain_engine::grain_energy(fr.chain, fr.state, i))
                .sum()
        });
        println!(
            "{},{},{},{},{},{},{:.6e}",
            fr.index,
            fr.window.len(),
            fr.window.islands().len(),
            count(1e-3),
            count(1e-8),
            count(1e-12),
            e
        );
        Ok(())
    })?;
    Ok(())
}
