//! Run a scene from Rust and print its energy time series: the library API behind `grainchain run`.
//!
//! cargo run --release --example run_scene -- scenes/single-solitary-wave.toml

use grainchain_engine::RunError;
use grainchain_engine::Scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "scenes/single-solitary-wave.toml".into());
    let scene = Scene::load(&path)?;
    let mut sim = scene.simulation()?;
    println!("time,kinetic,potential,total,window");
    sim.run(|fr| {
        let t = fr.totals;
        println!(
            "{},{:.9e},{:.9e},{:.9e},{}",
            fr.state.t,
            t.kinetic,
            t.potential,
            t.total,
            fr.window.len()
        );
        Ok::<(), RunError>(())
    })?;
    eprintln!(
        "{} steps, max |dE/E0| = {:.2e}",
        sim.stats().steps,
        sim.max_energy_error()
    );
    Ok(())
}
