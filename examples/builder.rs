//! Build a chain in code (no scene file): a heavy-to-light interface, and count the transmitted
//! pulses.
//!
//! cargo run --release --example builder

use grainchain::chain::{ChainBuilder, ContactLaw, Section, Striker, StrikerEnd};
use grainchain::integrators::{IntegrationParams, Method};
use grainchain::observables::{self, detect_pulses, PulseRule};
use grainchain::run::{RunError, SimulationBuilder};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let law = ContactLaw::hertz(5657.0);
    let chain = ChainBuilder::new()
        .section(Section::new("heavy", 60, 10.0, law))
        .section(Section::new("light", 400, 1.0, law))
        .striker(Striker {
            end: StrikerEnd::Left,
            mass: 10.0,
            speed: 1.0,
            law: None,
        })
        .build()?;
    let params = IntegrationParams {
        method: Method::BlanesMoan4,
        dt: 2e-4,
        ..Default::default()
    };
    let mut sim = SimulationBuilder::new(chain)
        .params(params)
        .schedule(12.0, 12.0)
        .build()?;
    sim.run(|_| Ok::<(), RunError>(()))?;
    let (chain, state) = (sim.chain(), sim.state());
    let mut e = Vec::new();
    observables::grain_energies(chain, state, 0..chain.len(), &mut e);
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
