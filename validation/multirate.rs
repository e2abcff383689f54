//! Multiple time stepping (`method = "multirate"`, engine/src/integrators/multirate.rs): its order in
//! the slow step, its bounded energy error (symplectic), its agreement with the single-rate run
//! on container (a) before the dynamics turn chaotic, and clear errors for bad settings.
//!
//! Whether it changes the *statistics* of the chaotic container runs is measured by an ensemble
//! study (studies/multirate-check.toml; BENCHMARKS.md, "Multirate"), too long for `cargo test`.

use crate::common;

use common::{fit_line, g, record_one, Row};
use grainchain_engine::Recorder;
use grainchain_engine::Scene;
use grainchain_engine::{Chain, State};
use grainchain_engine::{ChainBuilder, ContactLaw, End};
use grainchain_engine::{IntegrationParams, Method, MultirateParams};
use grainchain_engine::{RunError, SimulationBuilder};

use std::path::Path;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Sixteen Hertz grains (m = 1, eta = 1) squeezed by delta0 = 1 between walls: every contact
/// stays closed at small amplitude, so the force is smooth and the asymptotic order shows.
/// Highest frequency 2 sqrt(1.5) = 2.45.
fn precompressed() -> Chain {
    let law = ContactLaw::hertz(1.0).with_precompression(1.0);
    ChainBuilder::new()
        .grains(16, 1.0, law)
        .left(End::Wall(law))
        .right(End::Wall(law))
        .build()
        .unwrap()
}

/// Fast region: grains 5..=9 (the rest, walls included, is slow).
fn params(dt: f64, ratio: Option<u64>) -> IntegrationParams {
    match ratio {
        None => IntegrationParams {
            method: Method::BlanesMoan4,
            dt,
            ..Default::default()
        },
        Some(r) => IntegrationParams {
            method: Method::Multirate,
            dt,
            multirate: Some(MultirateParams {
                ratio: r,
                first: 5,
                last: 9,
            }),
            ..Default::default()
        },
    }
}

fn run(p: IntegrationParams, t: f64, interval: f64) -> (State, f64) {
    let mut sim = SimulationBuilder::new(precompressed())
        .params(p)
        .schedule(t, interval)
        .velocity(7, 0.01)
        .velocity(2, -0.005)
        .build()
        .unwrap();
    sim.run(|_| Ok::<(), RunError>(())).unwrap();
    (sim.state().clone(), sim.max_energy_error())
}

/// The slow part is velocity Verlet in disguise (r-RESPA): second order in H = ratio dt. The fast
/// step stays 1e-3 (Blanes-Moan 4: its error, ~1e-13 here, is far below the slow part's), and H
/// runs from 4e-3 to 3.2e-2 (omega H <= 0.08: asymptotic regime).
#[test]
fn multirate_is_second_order_in_the_slow_step() {
    let t = 10.0;
    let (reference, _) = run(params(1e-3 / 4.0, None), t, 0.64);
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    let mut errs = Vec::new();
    for r in [4u64, 8, 16, 32] {
        let (s, _) = run(params(1e-3, Some(r)), t, 0.64);
        let e =
            s.u.iter()
                .zip(&reference.u)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
        xs.push((r as f64 * 1e-3).ln());
        ys.push(e.ln());
        errs.push(e);
    }
    let (slope, _, _) = fit_line(&xs, &ys);
    // Order 2 asymptotically; 1.8-2.2 allows the next term of the error expansion at the
    // largest H (omega H = 0.08, a relative correction of order (omega H)^2 ~ 1 %) with room.
    let ok = (1.8..=2.2).contains(&slope);
    record_one(
        Row::new(
            "multirate order in the slow step",
            "precompressed Hertz chain, fast grains 5-9 at dt 1e-3, H = 4e-3 .. 3.2e-2, t = 10",
            "validation/multirate.rs",
        )
        .expected("2 (r-RESPA with velocity Verlet outside)")
        .measured(format!(
            "{} (errors {})",
            g(slope),
            errs.iter().map(|e| g(*e)).collect::<Vec<_>>().join(", ")
        ))
        .tolerance("1.8 to 2.2")
        .pass(ok),
    );
    assert!(ok, "order {slope}, errors {errs:?}");
}

/// Symplectic: the energy error oscillates and does not grow. Sixteen Hertz grains (m = 1,
/// eta = 1) between touching Hertz walls, no precompression; grain 0 starts at speed 1, so a
/// solitary wave runs back and forth through the fast region (grains 5-9) and the slow rest
/// (H = 8 dt = 8e-3) for 102.4 and 10,240 time units (hundreds of crossings). The largest energy
/// error of the long run must stay within 1.5x that of the short one (a method with secular
/// drift would grow ~100x).
#[test]
fn multirate_energy_error_is_bounded() {
    let law = ContactLaw::hertz(1.0);
    let chain = ChainBuilder::new()
        .grains(16, 1.0, law)
        .left(End::Wall(law))
        .right(End::Wall(law))
        .build()
        .unwrap();
    let p = IntegrationParams {
        max_energy_error: 1.0,
        ..params(1e-3, Some(8))
    };
    let err = |t: f64| {
        let mut sim = SimulationBuilder::new(chain.clone())
            .params(p)
            .schedule(t, 0.512)
            .velocity(0, 1.0)
            .build()
            .unwrap();
        sim.run(|_| Ok::<(), RunError>(())).unwrap();
        sim.max_energy_error()
    };
    let (short, long) = (err(102.4), err(10_240.0));
    let ratio = long / short;
    let ok = short > 0.0 && ratio < 1.5;
    record_one(
        Row::new(
            "multirate energy error bounded",
            "16 Hertz grains between walls, fast grains 5-9, dt 1e-3, H = 8e-3, t = 102.4 and 10240",
            "validation/multirate.rs",
        )
        .expected("max |dE/E0| over t = 10240 within 1.5x of that over t = 102.4")
        .measured(format!("{} and {} (ratio {})", g(short), g(long), g(ratio)))
        .tolerance("ratio < 1.5")
        .pass(ok),
    );
    assert!(ok, "{short} -> {long}");
}

/// Container (a) with multirate as `grainchain study` sets it up (ratio 16; fast region from the
/// container to the striker, 20 grains more on each side) against the scene file itself, beside a
/// chaos twin (striker speed x (1 + 1e-12)). Until the dynamics amplify every difference (from
/// ~180 snapshots on the twin itself differs by 5e-3 of E0), the multirate run must stay closer
/// to the single-rate run than the twin does: its error is smaller than a 1e-12 change of the
/// initial condition. Measured (`cargo run --release --example multirate_drift`): over
/// snapshots 0-179, 0 for multirate (bit for bit: the fast region does the single-rate
/// method's arithmetic, fused kicks included, and what the slow step changes in the outer
/// chains has not come back into the container by snapshot 179) against 5.0e-6 for the twin.
/// That the multirate run is not the single-rate run is checked on its work counters.
#[test]
fn multirate_stays_closer_than_a_chaos_twin_before_chaos() {
    use grainchain::batch::scenes::{perturb_striker, set_snapshots, SceneSource};
    use grainchain::batch::Stepping;
    let path = Path::new(ROOT).join("scenes/containers/a-standard.toml");
    let src = SceneSource::load(&path).unwrap();
    let e_r = |multirate: bool, eps: f64| {
        let mut c = src.container();
        set_snapshots(c.file_mut(), 179);
        perturb_striker(c.file_mut(), eps);
        if multirate {
            c.mark_fast_region().unwrap();
            c.integrator(Stepping::decide(Some((16, 20)), false), None);
        }
        let scene = c.build().unwrap();
        let c = scene
            .regions()
            .iter()
            .find(|r| r.name == "container")
            .unwrap()
            .clone();
        let mut sim = scene.simulation().unwrap();
        let (a, b) = (
            sim.chain().index_of(c.first).unwrap(),
            sim.chain().index_of(c.last).unwrap(),
        );
        let rec = Recorder::new().region("c", a, b).record(&mut sim).unwrap();
        (
            rec.region("c").unwrap().energy.clone(),
            sim.initial_energy(),
            sim.stats().grain_evals,
        )
    };
    let (single, e0, single_work) = e_r(false, 0.0);
    let (twin, _, _) = e_r(false, 1e-12);
    let (multi, _, multi_work) = e_r(true, 0.0);
    let dev = |x: &[f64]| {
        single
            .iter()
            .zip(x)
            .map(|(a, b)| (a - b).abs() / e0)
            .fold(0.0, f64::max)
    };
    let (dm, dt) = (dev(&multi), dev(&twin));
    // The multirate run did its own work (its counters differ: the fast region is integrated
    // from the start, the outer chains at 16 dt), so it is not the single-rate run again.
    let ok = multi_work != single_work && dm < dt;
    record_one(
        Row::new(
            "multirate against single rate before chaos",
            "container (a), ratio 16, fast region container..striker + 20 grains, snapshots 0-179",
            "validation/multirate.rs",
        )
        .expected("max |dE_R| / E0 below that of a chaos twin (striker speed x (1 + 1e-12))")
        .measured(format!(
            "{} (twin {}; grain evaluations {} against {})",
            g(dm),
            g(dt),
            multi_work,
            single_work
        ))
        .tolerance("below the twin")
        .pass(ok),
    );
    assert!(
        ok,
        "multirate {dm}, twin {dt}, grain evaluations {multi_work} against {single_work}"
    );
}

/// Container (a)'s scene file with its `[integrator]` table replaced by `integrator`.
fn container_a(integrator: &str) -> Result<Scene, grainchain_engine::InputError> {
    let text =
        std::fs::read_to_string(Path::new(ROOT).join("scenes/containers/a-standard.toml")).unwrap();
    let start = text.find("[integrator]").unwrap();
    let end = start + text[start..].find("\n\n").unwrap();
    let changed = format!(
        "{}[integrator]\n{integrator}{}",
        &text[..start],
        &text[end..]
    );
    let f: grainchain_engine::file::SceneFile = toml::from_str(&changed).unwrap();
    Scene::from_file(f, Path::new("x.toml"))
}

cases! {
/// Bad multirate settings in a scene: exact message, no panic.
fn bad_multirate_settings_fail_clearly(integrator: &str, message: &str) {
    let err = container_a(integrator).unwrap_err().to_string();
    assert_eq!(err, format!("x.toml: {message}"));
}
case_1("method = \"multirate\"\ndt = 7.8125e-4", "key `integrator.multirate`: method multirate needs `multirate = { ratio = .., fast = \"<region>\" }`"),
case_2("method = \"verlet\"\ndt = 7.8125e-4\nmultirate = { ratio = 8, fast = \"container\" }", "key `integrator.multirate`: applies to method multirate only, not verlet"),
case_3("method = \"multirate\"\ndt = 7.8125e-4\nmultirate = { ratio = 7, fast = \"container\" }", "key `integrator.multirate.ratio`: must divide the 160 steps of dt per output interval, got 7"),
case_4("method = \"multirate\"\ndt = 7.8125e-4\nmultirate = { ratio = 8, fast = \"box\" }", "key `integrator.multirate.fast`: `box` is not a region of this scene"),
}
