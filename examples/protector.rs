//! Evaluate a granular protector in real materials: 20 steel beads then 20 PTFE beads (6 mm)
//! against a steel wall, struck by a 6 mm steel sphere at 1 m/s; then the same column reversed
//! and a monodisperse steel column. Run: `cargo run --release --example protector`.

use grainchain_engine::protector::{evaluate, Bead, Impact, Protected, Settings};
use grainchain_engine::units::{PTFE, STEEL};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let d = 6e-3;
    let steel = Bead {
        material: STEEL,
        diameter: d,
    };
    let ptfe = Bead {
        material: PTFE,
        diameter: d,
    };
    let impact = Impact {
        striker: steel,
        speed: 1.0,
        restitution: None,
        restitution_pairs: Vec::new(),
    };
    let wall = Protected::Wall(STEEL);
    let settings = Settings::default();
    let designs = [
        (
            "20 steel, then 20 PTFE by the wall",
            [vec![steel; 20], vec![ptfe; 20]].concat(),
        ),
        (
            "20 PTFE, then 20 steel by the wall",
            [vec![ptfe; 20], vec![steel; 20]].concat(),
        ),
        ("40 steel", vec![steel; 40]),
    ];
    for (name, beads) in designs {
        let t = std::time::Instant::now();
        let e = evaluate(&beads, &impact, &wall, &settings)?;
        println!(
            "{name}: peak {:.1} N at {:.3} ms, impulse {:.4e} N s, {} steps to {:.3} ms \
             (stopped by the rule: {}), {:.2} ms",
            e.peak_force,
            e.peak_time * 1e3,
            e.impulse,
            e.steps,
            e.time * 1e3,
            e.complete,
            t.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}
