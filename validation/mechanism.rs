//! The paper's mechanism counted: reflections at a stretch's edges
//! (`Simulation::watch_reflections`, the rule in `engine/src/integrators/reflections.rs`)
//! where the answer is known. One solitary wave between two rigid walls hits each wall once per
//! crossing (`c / (2 L)` per unit time, nothing transmitted); the energy the hits send out of
//! container (a) is what its region loses. The light-to-heavy share is in `interfaces.rs`.

use crate::common;

use common::{bm4, g, grainchain, parabolic_peak, record, unit_wave, Row, HALF};
use grainchain_engine::{
    ChainBuilder, ContactLaw, Edge, End, Frame, Recorder, ReflectionRule, RunError, Scene,
    SimulationBuilder,
};
use std::path::Path;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// What one wave between walls gave: its speed from two interior grains, the hits, its energy.
struct Walls {
    speed: f64,
    hits: Vec<grainchain_engine::Reflection>,
    energy: f64,
}

/// The unit Hertz wave (eta = m = 1) placed with its peak at grain 25 of `n` grains between two
/// Hertz walls, moving right, run for `duration`. Its speed is measured from the passage of its
/// peak over grains 30 and 40 on the way out (the times of largest velocity, parabola through
/// the outputs): kinematics the counting rule never reads.
fn walls(n: usize, duration: f64) -> Walls {
    let law = ContactLaw::hertz(1.0);
    let chain = ChainBuilder::new()
        .grains(n, 1.0, law)
        .left(End::Wall(law))
        .right(End::Wall(law))
        .build()
        .unwrap();
    let (u0, v0) = unit_wave();
    let start = 25 - HALF;
    let mut b = SimulationBuilder::new(chain);
    let mut energy = 0.0;
    for i in 0..start {
        b = b.displacement(i, u0[0]);
    }
    for j in 0..u0.len() {
        b = b.displacement(start + j, u0[j]).velocity(start + j, v0[j]);
        energy += 0.5 * v0[j] * v0[j];
        if j + 1 < u0.len() {
            energy += (u0[j] - u0[j + 1]).max(0.0).powf(2.5) / 2.5;
        }
    }
    let h = 0.01;
    let mut sim = b.params(bm4(2e-3)).schedule(duration, h).build().unwrap();
    sim.watch_reflections(0, n - 1, ReflectionRule::default())
        .unwrap();
    let (mut v30, mut v40) = (Vec::new(), Vec::new());
    sim.run(|fr: &Frame| {
        if fr.state.t < 25.0 {
            v30.push(fr.state.v[30]);
            v40.push(fr.state.v[40]);
        }
        Ok::<(), RunError>(())
    })
    .unwrap();
    let t30 = parabolic_peak(&v30, 0.0, h).0;
    let t40 = parabolic_peak(&v40, 0.0, h).0;
    Walls {
        speed: 10.0 / (t40 - t30),
        hits: sim.take_reflections(),
        energy,
    }
}

/// The hits that carry at least half of the wave's energy (the wave itself; a wall also leaves
/// a little of it behind, rattling, which the rule counts as small hits of their own), in time
/// order.
fn main_hits(w: &Walls) -> Vec<&grainchain_engine::Reflection> {
    let mut all: Vec<_> = w
        .hits
        .iter()
        .filter(|h| h.incident > 0.5 * w.energy)
        .collect();
    all.sort_by(|a, b| a.time.total_cmp(&b.time));
    all
}

/// One wave between two walls: the wave hits the walls in turn, once per crossing; a wall takes
/// nothing (transmitted exactly 0); no hit counts more than the wave's energy and the first
/// counts all of it. Its round trip in a chain of `n` grains is `2 n / c` plus the time it
/// spends turning at the two walls: the difference between two lengths (60 and 120 grains)
/// cancels the turning, so hits come at `c / (2 L)` per wall per unit time exactly where that
/// can be checked: `T(120) - T(60) = 120 / c`.
#[test]
fn one_wave_between_walls_hits_each_wall_once_per_crossing() {
    let short = walls(60, 350.0);
    let long = walls(120, 800.0);
    let mut rows = Vec::new();
    let mut ok_all = true;
    let mut trips = Vec::new();
    for (n, w) in [(60, &short), (120, &long)] {
        let main = main_hits(w);
        let edges: Vec<Edge> = main.iter().map(|h| h.edge).collect();
        let alternate =
            edges.len() >= 5 && edges.windows(2).all(|p| p[0] != p[1]) && edges[0] == Edge::Right;
        let sent = w
            .hits
            .iter()
            .map(|h| h.transmitted.abs())
            .fold(0.0, f64::max);
        let most = w.hits.iter().map(|h| h.incident).fold(0.0, f64::max) / w.energy;
        let first = main.first().map_or(0.0, |h| h.incident / w.energy);
        // The first round trip, between the first two hits on the right wall.
        let trip = main
            .get(2)
            .zip(main.first())
            .map_or(f64::NAN, |(b, a)| b.time - a.time);
        trips.push(trip);
        // The first hit holds the whole wave: the opening-kick shift of the velocities and the
        // tails beyond the 10-grain zone (interfaces.rs measures both) are below 1e-3. No hit
        // may count more than the wave (1e-3 above it for the same reasons). A wall does no
        // work: exactly 0.
        let ok = alternate && sent == 0.0 && (first - 1.0).abs() < 1e-3 && most < 1.0 + 1e-3;
        ok_all &= ok;
        rows.push(
            Row::new(
                "reflections: one wave between walls",
                format!(
                    "{n} grains, {} hits, {} of the wave",
                    w.hits.len(),
                    main.len()
                ),
                "the walls in turn, nothing transmitted",
            )
            .expected("right, left, right, ...; transmitted 0; first incident 1, none above")
            .measured(format!(
                "{edges:?}; transmitted {}; first incident {}, largest {}; rate per wall \
                 {} (c/(2L) = {}: the turning time adds to the trip)",
                g(sent),
                g(first),
                g(most),
                g(1.0 / trip),
                g(w.speed / (2.0 * n as f64)),
            ))
            .tolerance("order exact, transmitted exactly 0, incident 1e-3")
            .pass(ok),
        );
    }
    // The turning time cancels in the difference of the two round trips. Each wall leaves a
    // little of the wave behind (measured here as the incident energies of the main hits:
    // the left wall about 3 %), and a lighter wave is slower: c goes as E^(1/10) (physics.md 2,
    // V ~ v_max^(1/5) at a fixed width, E ~ v_max^2). The extra 60 grains are crossed once
    // leftwards with the energy of the second main hit and once rightwards with that of the
    // third.
    let speed = (short.speed + long.speed) / 2.0;
    let energy = |k: usize| main_hits(&short)[k].incident / short.energy;
    let expected = 60.0 / (speed * energy(1).powf(0.1)) + 60.0 / (speed * energy(2).powf(0.1));
    let measured = trips[1] - trips[0];
    // The speed is the outgoing wave's, read every 0.01 time units with a parabola through the
    // peak (about 1e-4 of the 12-unit passage between grains 30 and 40); a wave just after a
    // wall is still reshaping, which the steady scaling leaves out: 1e-3.
    let ok = (measured / expected - 1.0).abs() < 1e-3;
    rows.push(
        Row::new(
            "reflections: round trip against length",
            "120 and 60 grains",
            "T(120) - T(60) = 2 (120 - 60) / c, c from the wave's passage",
        )
        .expected(g(expected))
        .measured(g(measured))
        .tolerance("1e-3 relative")
        .pass(ok),
    );
    ok_all &= ok;
    record(&rows);
    assert!(
        ok_all,
        "{:?}",
        rows.iter().map(|r| &r.measured).collect::<Vec<_>>()
    );
}

/// Container (a) as shipped (multirate), the first 100 time units: the work its two edges did
/// on the grains beyond them is the energy its region lost, and the hits account for all of it.
#[test]
fn the_hits_carry_every_joule_that_leaves_container_a() {
    let mut scene = Scene::load(Path::new(ROOT).join("scenes/containers/a-standard.toml")).unwrap();
    scene.set_schedule(100.0, scene.output_interval()).unwrap();
    let c = scene.region_grains("container").unwrap();
    let (a, b) = (*c.start(), *c.end());
    let mut sim = scene.simulation().unwrap();
    sim.watch_reflections(a, b, ReflectionRule::default())
        .unwrap();
    let rec = Recorder::new()
        .region("container", a, b)
        .record(&mut sim)
        .unwrap();
    let e = &rec.region("container").unwrap().energy;
    let work = sim.edge_work().unwrap();
    let hits = sim.take_reflections();
    let sent = work.sent[0] + work.sent[1];
    let in_hits: f64 =
        hits.iter().map(|h| h.transmitted).sum::<f64>() + work.open[0] + work.open[1];
    let lost = e[0] - e[e.len() - 1];
    let e_max = e.iter().cloned().fold(0.0, f64::max);
    // The region's energy counts half of each edge contact's potential, the work counts it when
    // it reaches the grain beyond: they differ by the edge contacts' potential at the end, and
    // by the trapezoid rule's error over steps of 7.8e-4 (second order): 1e-3 of the largest
    // energy the container held.
    let ok_lost = (sent - lost).abs() <= 1e-3 * e_max;
    // The hits partition the steps in which an edge contact is closed, and an open contact does
    // no work: the same sum in another order, to rounding.
    let ok_hits = (in_hits - sent).abs() <= 1e-12 * e_max * hits.len() as f64;
    let rows = [
        Row::new(
            "reflections: container (a) energy sent out",
            format!("t = 0..100, {} hits", hits.len()),
            "the container's energy lost",
        )
        .expected(g(lost))
        .measured(g(sent))
        .tolerance("1e-3 of the container's largest energy")
        .pass(ok_lost),
        Row::new(
            "reflections: container (a) hits account for the work",
            "t = 0..100",
            "the work through the edges",
        )
        .expected(g(sent))
        .measured(g(in_hits))
        .tolerance("rounding")
        .pass(ok_hits),
    ];
    record(&rows);
    assert!(
        ok_lost && ok_hits,
        "sent {sent}, lost {lost}, in hits {in_hits}"
    );
}

/// A study with `mechanism = true`: the same outputs at 1 and 2 threads, and each member's
/// binned reflections (through its JSON file) account for the change of its container's energy
/// (from its CSV file), the engine's balance carried through the study's files.
#[test]
fn a_study_counts_reflections_the_same_on_every_thread_count() {
    let dir = tempfile::Builder::new()
        .prefix("grainchain-mechanism-study-")
        .tempdir()
        .unwrap();
    let sweep = dir.path().join("sweep.toml");
    std::fs::write(
        &sweep,
        format!(
            "name = \"mechanism-check\"\nsnapshots = 600\nmembers = 2\nperturbation = {{ kind = \
             \"striker-speed\", epsilon = 1e-12 }}\nouter_chains = 600\nmechanism = true\n\n\
             [[containers]]\nkey = \"a\"\nscene = \"{ROOT}/scenes/containers/a-standard.toml\"\n"
        ),
    )
    .unwrap();
    let mut outputs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("out-{threads}"));
        let (code, _, err) = grainchain(&[
            "study",
            common::s(&sweep),
            "--out",
            common::s(&out),
            "--threads",
            threads,
        ]);
        assert_eq!(code, Some(0), "{err}");
        let read = |f: &str| std::fs::read(out.join(f)).unwrap();
        outputs.push((read("mechanism.csv"), read("leak.csv"), out));
    }
    let same = outputs[0].0 == outputs[1].0 && outputs[0].1 == outputs[1].1;
    // The balance of member 0 from its files.
    let members = outputs[0].2.join("members");
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(members.join("a-m0.json")).unwrap()).unwrap();
    let e0 = meta["initial_energy"].as_f64().unwrap();
    let bins = meta["mechanism"]["time"].as_array().unwrap();
    let net: f64 = bins
        .iter()
        .map(|b| b["inflow"].as_f64().unwrap() - b["transmitted"].as_f64().unwrap())
        .sum();
    let hits: u64 = bins.iter().map(|b| b["hits"].as_u64().unwrap()).sum();
    let csv = std::fs::read_to_string(members.join("a-m0.csv")).unwrap();
    let column = csv
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "container")
        .unwrap();
    let energy: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(column).unwrap().parse().unwrap())
        .collect();
    let change = energy[energy.len() - 1] - energy[0];
    // The region's energy holds half of each edge contact's potential and the work counts it
    // when it reaches the grain beyond: at the end (t = 75, the impulse still inside) they
    // differ by half of the edge contacts' potential then; and the trapezoid rule's error of
    // the work (the engine's check: under 1e-3 of the largest energy over 100 time units):
    // 2e-3 of the initial energy.
    let ok = same && hits > 100 && (net - change).abs() <= 2e-3 * e0;
    record(&[Row::new(
        "reflections: a study's files",
        "container (a), 2 members, 600 snapshots, 1 and 2 threads",
        "the container's energy change; the same bytes at every thread count",
    )
    .expected(format!("identical outputs; {} of E0", g(change / e0)))
    .measured(format!(
        "identical {same}; {} of E0 from {hits} reflections and the inflow",
        g(net / e0)
    ))
    .tolerance("bytes; 2e-3 of E0")
    .pass(ok)]);
    assert!(
        ok,
        "same {same}, net {net}, change {change}, e0 {e0}, hits {hits}"
    );
}
