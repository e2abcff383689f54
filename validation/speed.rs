//! Impact speed: a chain of Hertz contacts has no scale of its own, so container (e) (all Hertz)
//! struck 32 times faster, in time units half as long, is the same run with every energy 1024
//! times larger, bit for bit, chaos and all. `batch::ContainerScene::striker_speed` is what a
//! study's `speed` uses.

use crate::common;

use common::{record, Row};
use grainchain::batch::scenes::{self, SceneSource};
use grainchain::batch::Stepping;
use grainchain_engine::Recorder;
use std::path::Path;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Container (e)'s energy at every snapshot when struck at `v` (its scene as shipped:
/// multirate 8, causal horizon), `snapshots` long, outer chains of 3000 grains.
fn container_energy(v: Option<f64>, snapshots: u64) -> Vec<f64> {
    let src = SceneSource::load(Path::new(ROOT).join("scenes/containers/e-no-walls.toml")).unwrap();
    let mut c = src.container();
    scenes::set_snapshots(c.file_mut(), snapshots);
    c.outer_chains(3000, 3000).unwrap();
    if let Some(v) = v {
        let scale = c.striker_speed(v).unwrap();
        c.integrator(Stepping::Scene, Some(scale));
    }
    let scene = c.build().unwrap();
    let r = scene.region_grains("container").unwrap();
    let mut sim = scene.simulation().unwrap();
    let rec = Recorder::new()
        .region("container", *r.start(), *r.end())
        .record(&mut sim)
        .unwrap();
    rec.region("container").unwrap().energy.clone()
}

/// Speeds 10 (the scene's), 320 and 10240 (32 and 1024 times): energies 1024 and 1024^2 times
/// those at 10, at every one of 1500 snapshots, to the last bit (the run is chaotic after about
/// snapshot 200, so any rounding difference would grow to order one). A speed that is not a
/// power of 32 away (160) is not an exact copy: the test can fail.
#[test]
fn container_e_scales_exactly_with_the_impact_speed() {
    let n = 1500;
    let base = container_energy(None, n);
    let mut rows = Vec::new();
    let mut ok = true;
    for (k, v) in [(1, 320.0), (2, 10240.0)] {
        let e = container_energy(Some(v), n);
        let f = 1024f64.powi(k);
        let same = e.len() == base.len() && e.iter().zip(&base).all(|(a, b)| *a == f * b);
        ok &= same;
        rows.push(
            Row::new(
                "impact speed: container (e) scales exactly",
                format!("striker {v} vs 10, {n} snapshots, time scaled by 2^-{k}"),
                "Hertz scaling: speed 32^k, time 2^-k, energy 1024^k",
            )
            .expected(format!("E_R x {f} at every snapshot, bit for bit"))
            .measured(if same { "identical" } else { "differs" })
            .tolerance("0 (bit for bit)")
            .pass(same),
        );
    }
    // Not a power of 32: the times are not an exact scaling, so the chaotic run parts.
    let e = container_energy(Some(160.0), n);
    let f = (16.0f64).powf(2.0);
    let parted = e.iter().zip(&base).any(|(a, b)| *a != f * b);
    rows.push(
        Row::new(
            "impact speed: a speed not a power of 32 away is not an exact copy",
            format!("striker 160 vs 10, {n} snapshots"),
            "control",
        )
        .expected("differs")
        .measured(if parted { "differs" } else { "identical" })
        .tolerance("-")
        .pass(parted),
    );
    record(&rows);
    assert!(ok && parted, "see target/validation/REPORT.md");
}
