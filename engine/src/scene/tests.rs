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
    assert_eq!(s.grains, 11);
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
