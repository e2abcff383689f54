//! A heavy-to-light interface from the catalogue of sample problems (`grainchain_engine::problems`),
//! run in code (no scene file), and the transmitted pulses counted.
//!
//! cargo run --release --example builder

use grainchain_engine::problems::MassInterface;
use grainchain_engine::RunError;
use grainchain_engine::{self, detect_pulses, PulseRule};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // 60 heavy grains (m = 10, Hertz, eta = 5657) struck by a grain of their mass at speed 1,
    // then 400 light ones (m = 1); Blanes-Moan 4 at dt = 2e-4. One output, at t = 12.
    let problem = MassInterface::default();
    let mut sim = problem.builder()?.schedule(12.0, 12.0).build()?;
    sim.run(|_| Ok::<(), RunError>(()))?;
    let (chain, state) = (sim.chain(), sim.state());
    let mut e = Vec::new();
    grainchain_engine::grain_energies(chain, state, 0..chain.len(), &mut e);
    let pulses = detect_pulses(&e, &state.v, &PulseRule::default());
    for p in pulses.iter().filter(|p| p.first > 61) {
        println!(
            "pulse at grain {:.1}: peak velocity {:.4}, energy {:.4e}",
            p.position + chain.grain_number(0) as f64,
            p.peak_velocity,
            p.energy
        );
    }
    Ok(())
}
