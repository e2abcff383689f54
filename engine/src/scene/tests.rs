use super::*;

const GOOD: &str = r#"
name = "t"
[chain]
[[chain.sections]]
count = 10
mass = 1.0
p = 1.5
eta = 5657.0
[striker]
end = "left"
mass = 1.0
speed = 1.0
[run]
duration = 1.0
output_interval = 0.5
"#;

fn err(text: &str) -> String {
    Scene::parse(text, Path::new("s.toml"))
        .unwrap_err()
        .to_string()
}

#[test]
fn good_scene_builds() {
    let s = Scene::parse(GOOD, Path::new("s.toml")).unwrap();
    assert_eq!(s.grains(), 11);
    let sim = s.simulation().unwrap();
    assert_eq!(sim.chain().len(), 11);
    assert_eq!(sim.outputs(), 2);
}

#[test]
fn into_simulation_hands_over_the_checked_chain() {
    let s = Scene::parse(GOOD, Path::new("s.toml")).unwrap();
    let len = s.chain().len();
    let mut a = s.simulation().unwrap();
    let mut b = s.into_simulation().unwrap();
    assert_eq!(b.chain().len(), len);
    a.run(|_| Ok::<(), RunError>(())).unwrap();
    b.run(|_| Ok::<(), RunError>(())).unwrap();
    for (x, y) in a.state().u.iter().zip(&b.state().u) {
        assert_eq!(x.to_bits(), y.to_bits());
    }
    assert_eq!(a.stats(), b.stats());
}

#[test]
fn unknown_key_is_named() {
    let e = err(&GOOD.replace("mass = 1.0\np", "mass = 1.0\nmas = 2.0\np"));
    assert!(
        e.contains("s.toml") && e.contains("chain.sections[0].mas"),
        "{e}"
    );
}

#[test]
fn bad_values_name_their_key() {
    let e = err(&GOOD.replace("mass = 1.0\np", "mass = -1.0\np"));
    assert_eq!(
        e,
        "s.toml: key `chain.sections[0].mass`: must be a finite number > 0, got -1"
    );
    let e = err(&GOOD.replace("p = 1.5", "p = 0.5"));
    assert!(e.contains("chain.sections[0].p"), "{e}");
    let e = err(&GOOD.replace("duration = 1.0", "duration = inf"));
    assert!(e.contains("run.duration"), "{e}");
    let e = err(&GOOD.replace("mass = 1.0\np", "mass = \"heavy\"\np"));
    assert!(e.contains("chain.sections[0].mass"), "{e}");
}

#[test]
fn regions_by_name_in_the_library_numbering() {
    // A left striker is printed grain 0 = internal index 0; without one, printed grain 1 is
    // internal index 0.
    let text = format!("{GOOD}\n[[regions]]\nname = \"front\"\nfirst = 1\nlast = 4\n");
    let s = Scene::parse(&text, Path::new("s.toml")).unwrap();
    assert_eq!(s.region_grains("front").unwrap(), 1..=4);
    let chain = s.simulation().unwrap().chain().clone();
    assert_eq!(chain.grain_number(1), 1);
    let free = text.replace("[striker]\nend = \"left\"\nmass = 1.0\nspeed = 1.0\n", "");
    let s = Scene::parse(&free, Path::new("s.toml")).unwrap();
    assert_eq!(s.region_grains("front").unwrap(), 0..=3);
    let e = s.region_grains("back").unwrap_err().to_string();
    assert!(e.contains("no region named `back` (regions: front)"), "{e}");
}

/// An SI scene: two materials, a striker and a wall, every constant by hand.
const SI: &str = r#"
[chain]
right = { kind = "wall", material = "steel" }
[[chain.sections]]
name = "steel"
count = 3
material = "steel"
diameter = 0.01
[[chain.sections]]
name = "soft"
count = 2
material = { E = 1.46e9, nu = 0.46, rho = 2200 }
diameter = 0.01
[striker]
end = "left"
material = "steel"
diameter = 0.01
speed = 1.0
[integrator]
dt = 1e-8
[run]
duration = 1e-4
output_interval = 1e-5
"#;

/// Masses and laws of an SI scene by hand (the numbers of `units`' own hand calculation: a
/// 10 mm steel sphere weighs 4.08407e-3 kg; steel on PTFE, both 10 mm, 1.224185e8 N/m^1.5; a
/// 10 mm steel sphere on a steel flat 1.029380e10), the joint between the materials the pair's
/// constant, the striker the steel pair's.
#[test]
fn si_scene_takes_masses_and_laws_from_materials() {
    let s = Scene::parse(SI, Path::new("s.toml")).unwrap();
    assert!(s.si);
    let c = s.chain();
    assert_eq!(c.len(), 6);
    let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-5;
    assert!(close(c.mass()[0], 4.08407e-3), "{}", c.mass()[0]);
    assert!(close(
        c.mass()[5],
        2200.0 * std::f64::consts::PI * 1e-6 / 6.0
    ));
    // Contact 4 joins steel grain 3 (internal 3) and the first soft grain (internal 4).
    let joint = c.contact_law(4).unwrap();
    assert_eq!(joint.p, 1.5);
    assert!(close(joint.eta, 1.224185e8), "{}", joint.eta);
    // Steel on steel, 10 mm: E* = 1 / (2 * 4.5795e-12) = 1.091822e11 Pa, sqrt(R*) =
    // sqrt(2.5e-3) = 0.05: 4/3 * 1.091822e11 * 0.05 = 7.278813e9. Contact 1 is the striker's
    // (internal 0, a steel sphere) with the first bead, contact 2 inside the steel section.
    assert!(close(c.contact_law(1).unwrap().eta, 7.278813e9));
    assert!(close(c.contact_law(2).unwrap().eta, 7.278813e9));
    // The wall touches the last (soft) grain: PTFE sphere on a steel flat.
    let flat = crate::chain::material::hertz_eta_flat(
        &crate::chain::material::PTFE,
        0.01,
        &crate::chain::material::STEEL,
    );
    assert!(close(c.contact_law(6).unwrap().eta, flat));
    assert_eq!(s.protected_contact(), Some(6));
}

#[test]
fn a_target_is_a_section_at_the_right_end() {
    let text = SI.replace("right = { kind = \"wall\", material = \"steel\" }", "")
        + "[target]\nmaterial = \"steel\"\ndiameter = 0.02\nspring = 1e6\n";
    let s = Scene::parse(&text, Path::new("s.toml")).unwrap();
    let c = s.chain();
    assert_eq!(c.len(), 7);
    let t = c.section("target").unwrap();
    assert_eq!((t.first, t.last), (6, 6));
    assert_eq!(s.protected_contact(), Some(6));
    // The spring to the ground: a two-sided linear law at the right end.
    let spring = c.contact_law(7).unwrap();
    assert!(spring.tension && spring.p == 1.0 && spring.eta == 1e6);
    // Its contact with the last bead: PTFE 10 mm on steel 20 mm.
    let want = crate::chain::material::hertz_eta(
        &crate::chain::material::PTFE,
        0.01,
        &crate::chain::material::STEEL,
        0.02,
    );
    assert_eq!(c.contact_law(6).unwrap().eta, want);
    // A free target: the chain ends free, and the protected contact is still the target's.
    let free = text.replace("spring = 1e6\n", "");
    let s = Scene::parse(&free, Path::new("s.toml")).unwrap();
    assert_eq!(s.chain().contact_law(7), None);
    assert_eq!(s.protected_contact(), Some(6));
    // A program-unit scene: no wall, no target: nothing protected.
    assert_eq!(
        Scene::parse(GOOD, Path::new("s.toml"))
            .unwrap()
            .protected_contact(),
        None
    );
    // With a target and a left striker the target is after the striker.
    let prog = GOOD.to_string() + "[target]\nmass = 2.0\n";
    let s = Scene::parse(&prog, Path::new("s.toml")).unwrap();
    assert_eq!(s.chain().len(), 12);
    assert_eq!(s.protected_contact(), Some(11));
    assert_eq!(s.chain().mass()[11], 2.0);
}

#[test]
fn si_and_program_units_do_not_mix() {
    let mixed = SI.replace(
        "material = { E = 1.46e9, nu = 0.46, rho = 2200 }\ndiameter = 0.01",
        "mass = 1.0\np = 1.5\neta = 5657.0",
    );
    assert_eq!(
        err(&mixed),
        "s.toml: key `chain.sections[1].material`: missing: this is an SI scene \
         (`chain.sections[0].material`), where every section gives `material` and `diameter`; \
         program units (`mass`, `p`, `eta`) and SI cannot be mixed"
    );
    let e = err(&SI.replace(
        "\"steel\"\ndiameter = 0.01\n[[",
        "\"unobtainium\"\ndiameter = 0.01\n[[",
    ));
    assert!(e.contains("key `chain.sections[0].material`: unknown material `unobtainium` (known: steel, stainless-steel, brass, aluminium, ptfe, glass, tungsten-carbide"), "{e}");
    let e = err(&SI.replace("dt = 1e-8\n", ""));
    assert!(e.contains("key `integrator.dt`: missing"), "{e}");
    let e = err(&SI.replace("nu = 0.46", "nu = 0.7"));
    assert!(
        e.contains("key `chain.sections[1].material`: Poisson's ratio"),
        "{e}"
    );
    let e = err(&GOOD
        .replace("[striker]", "[target]\nmass = 1.0\n[striker]")
        .replace("end = \"left\"", "end = \"right\""));
    assert!(
        e.contains("key `striker.end`: the right end holds the `[target]`"),
        "{e}"
    );
}

/// A checked scene stays valid: every edit is checked as the file's keys are, names the key,
/// and leaves the scene unchanged when refused (issue 39).
#[test]
fn edits_are_checked_and_a_refused_edit_changes_nothing() {
    let horizon = GOOD.replace(
        "output_interval = 0.5",
        "output_interval = 0.5\n[run.horizon]",
    );
    let mut s = Scene::parse(&horizon, Path::new("s.toml")).unwrap();
    let before = (
        *s.params(),
        s.duration(),
        s.output_interval(),
        s.horizon().copied(),
    );
    let gear5 = IntegrationParams {
        method: crate::Method::Gear5,
        ..*s.params()
    };
    // gear5 cannot run under a horizon: the edit is refused under the horizon's key.
    let e = s.set_params(gear5).unwrap_err().to_string();
    assert!(e.contains("run.horizon") && e.contains("gear5"), "{e}");
    // An interval longer than the run, a step that does not fit.
    let e = s.set_schedule(1.0, 2.0).unwrap_err().to_string();
    assert!(e.contains("run.output_interval"), "{e}");
    let e = s
        .set_params(IntegrationParams {
            dt: -1.0,
            ..*s.params()
        })
        .unwrap_err()
        .to_string();
    assert!(e.contains("integrator.dt"), "{e}");
    assert_eq!(
        before,
        (
            *s.params(),
            s.duration(),
            s.output_interval(),
            s.horizon().copied()
        )
    );
    // Without the horizon, gear5 is taken, and its step is fitted to the interval.
    s.set_horizon(None).unwrap();
    s.set_params(gear5).unwrap();
    assert_eq!(s.params().method, crate::Method::Gear5);
    assert_eq!(s.step(), gear5.fitted_step(s.output_interval()));
    s.set_schedule(2.0, 0.25).unwrap();
    assert_eq!(s.outputs(), 8);
    assert!(s.simulation().is_ok());
}
