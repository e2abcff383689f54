//! How far multirate runs of container (a) drift from the single-rate run, snapshot by snapshot,
//! beside a chaos twin (striker speed x (1 + 1e-12)): `cargo run --release --example
//! multirate_drift [RATIO] [SNAPSHOTS] [MARGIN]`. Prints the largest |dE_R| / E0 per window of 20
//! snapshots for the twin and for the multirate run.
use grainchain::batch::scenes::{perturb_striker, set_snapshots, SceneSource};
use grainchain::batch::Stepping;
use grainchain_engine::problems::Container;
use grainchain_engine::Recorder;
use grainchain_engine::Scene;
use std::path::Path;

/// Container (a), striker speed x (1 + eps), `snapshots` long; with `multirate` = (ratio,
/// margin) the fast region of `grainchain study` (container to striker, plus the margin).
fn scene(multirate: Option<(u64, u64)>, eps: f64, snapshots: u64) -> Scene {
    let path = Container::A.path(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"));
    let src = SceneSource::load(&path).expect("scene file");
    let mut c = src.container();
    perturb_striker(c.file_mut(), eps);
    set_snapshots(c.file_mut(), snapshots);
    if multirate.is_some() {
        c.mark_fast_region().expect("a container scene");
    }
    c.integrator(Stepping::decide(multirate, false), None);
    c.build().expect("scene")
}

fn e_r(s: &Scene) -> (Vec<f64>, f64) {
    let mut sim = s.simulation().expect("simulation");
    let (a, b) = Container::grains(s).expect("region `container` in the chain");
    let rec = Recorder::new()
        .region("c", a, b)
        .record(&mut sim)
        .expect("run");
    (
        rec.region("c").expect("region").energy.clone(),
        sim.initial_energy(),
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let ratio: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(16);
    let n: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(400);
    let margin: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(20);
    let (a, e0) = e_r(&scene(None, 0.0, n));
    let (twin, _) = e_r(&scene(None, 1e-12, n));
    let (m, _) = e_r(&scene(Some((ratio, margin)), 0.0, n));
    println!("snapshots  max|E_R| /E0  twin max|dE_R|/E0  multirate max|dE_R|/E0");
    for w in (0..=n as usize).step_by(20) {
        let hi = (w + 20).min(a.len());
        let d = |x: &[f64]| {
            (w..hi)
                .map(|t| (x[t] - a[t]).abs() / e0)
                .fold(0.0, f64::max)
        };
        let top = (w..hi).map(|t| a[t] / e0).fold(0.0, f64::max);
        println!(
            "{w:>5}-{:<5} {top:>10.4} {:>18.3e} {:>22.3e}",
            hi - 1,
            d(&twin),
            d(&m)
        );
    }
}
