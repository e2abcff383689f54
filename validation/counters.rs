//! Work counters pinned: steps, rejected steps, force evaluations, grain evaluations and the
//! largest window of fixed scenes, as insta snapshots in `golden/snapshots/` (diffsol style), so
//! a change of the step controller, the skipping window or the islands shows up as a reviewable
//! diff (`cargo insta review`). These counts are exact and machine-independent: the kernels give
//! the same bits on every CPU (ARCHITECTURE.md), and the counters follow from the state.

use grainchain_engine::RunError;
use grainchain_engine::Scene;
use grainchain_engine::{IntegrationParams, Method, Sleep};
use serde::Serialize;
use std::path::Path;

/// The counters of one run.
#[derive(Serialize)]
struct Counters {
    scene: String,
    method: &'static str,
    steps: u64,
    rejected_steps: u64,
    force_evaluations: u64,
    grain_evaluations: u64,
    max_window: usize,
    grains_taken_out_of_islands: u64,
    islands_at_the_end: usize,
}

fn counters(path: &str, edit: impl FnOnce(&mut Scene)) -> Counters {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sc = Scene::load(root.join(path)).unwrap();
    edit(&mut sc);
    let mut sim = sc.simulation().unwrap();
    sim.run(|_| Ok::<(), RunError>(())).unwrap();
    let st = sim.stats();
    Counters {
        scene: path.to_string(),
        method: sim.params().method.name(),
        steps: st.steps,
        rejected_steps: st.rejected,
        force_evaluations: st.force_evals,
        grain_evaluations: st.grain_evals,
        max_window: st.max_window,
        grains_taken_out_of_islands: st.slept_grains,
        islands_at_the_end: sim.window().islands().len(),
    }
}

#[test]
fn work_counters_of_fixed_scenes() {
    let runs = vec![
        // verlet, one wave: the skipping window.
        counters("scenes/single-solitary-wave.toml", |_| {}),
        // The same wave on the adaptive method: accepted and rejected steps of the controller.
        counters("scenes/single-solitary-wave.toml", |s| {
            s.set_params(IntegrationParams {
                method: Method::Dopri5,
                rtol: 1e-8,
                atol: 1e-10,
                ..*s.params()
            })
            .unwrap();
        }),
        // gear5 on the same wave (its start-up probe included).
        counters("scenes/single-solitary-wave.toml", |s| {
            s.set_params(IntegrationParams {
                method: Method::Gear5,
                ..*s.params()
            })
            .unwrap();
        }),
        // dopri5 on a precompressed chain (every grain moving, walls).
        counters("scenes/precompressed-chain.toml", |_| {}),
        // blanes-moan4 on the Fig. 3 container: the window of a container run.
        counters("scenes/fig3-standard-container.toml", |_| {}),
        // The same with the sleep rule: islands split and wake.
        counters("scenes/fig3-standard-container.toml", |s| {
            s.set_params(IntegrationParams {
                sleep: Some(Sleep {
                    velocity: 1e-10,
                    force: 1e-10,
                }),
                ..*s.params()
            })
            .unwrap();
        }),
    ];
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path(Path::new(env!("CARGO_MANIFEST_DIR")).join("golden/snapshots"));
    settings.set_prepend_module_to_snapshot(false);
    settings.bind(|| insta::assert_yaml_snapshot!("work_counters", runs));
}
