//! Interfaces between sections of different grain mass (physics.md 6; Hong 2005 Fig. 1):
//! heavy to light (total transmission, a train of solitary waves) and light to heavy
//! (reflection, transmission falling with the mass ratio).

use crate::common;

use common::{bm4, g, record, unit_wave, Row, HALF};
use grainchain_engine::problems::MassInterface;
use grainchain_engine::State;
use grainchain_engine::{detect_pulses, PulseRule};
use grainchain_engine::{Frame, RunError, SimulationBuilder};

const P: f64 = 1.5;
/// Grains next to the interface that still push the second section after the wave has
/// crossed (heavy to light), excluded from the reflected energy.
const NEAR: usize = 5;

/// Energy of a state of a chain with masses `m` and Hertz contacts (eta = 1), free ends,
/// computed here.
fn energy(m: &[f64], u: &[f64], v: &[f64]) -> f64 {
    let ke: f64 = m.iter().zip(v).map(|(m, v)| 0.5 * m * v * v).sum();
    let pe: f64 = u
        .windows(2)
        .map(|w| (w[0] - w[1]).max(0.0).powf(P + 1.0) / (P + 1.0))
        .sum();
    ke + pe
}

/// Result of a wave crossing an interface.
struct Crossing {
    /// Energy of the incident wave.
    e_in: f64,
    /// Energy left in the first section at the end.
    e_first: f64,
    /// Energy at the end in the first section's grains at least NEAR grains from the interface.
    e_far: f64,
    /// Most negative velocity of a first-section grain at any output time (relative to the
    /// incident wave's peak velocity).
    min_v_first: f64,
    /// Final state of the second section (u, v, masses) for pulse counting.
    second: State,
    m2: f64,
    /// The hits counted at the first section's edges (`Simulation::watch_reflections` over the
    /// first section: its right edge is the interface), read-only: the run is the same with or
    /// without them.
    hits: Vec<grainchain_engine::Reflection>,
}

/// A wave of the chain of mass `m1` (peak `lead` grains before the interface) meets a section
/// of mass `m2`; run for `duration` (in units of the unit-mass chain's time) with `n2` grains.
fn cross(m1: f64, m2: f64, lead: usize, n2: usize, duration: f64) -> Crossing {
    let (u0, v0) = unit_wave();
    let n1 = lead + HALF + 1;
    // Sections `first` and `second`, no striker: the cut wave is the initial condition.
    let chain = MassInterface {
        p: P,
        eta: 1.0,
        first_grains: n1,
        first_mass: m1,
        second_grains: n2,
        second_mass: m2,
        striker_speed: None,
    }
    .chain()
    .unwrap();
    let s1 = 1.0 / m1.sqrt();
    let mut b = SimulationBuilder::new(chain);
    let start = n1 - 1 - lead - HALF; // index of the cut's first grain
    for i in 0..start {
        b = b.displacement(i, u0[0]);
    }
    let mut masses = vec![m1; n1];
    masses.extend(vec![m2; n2]);
    let mut u = vec![0.0; n1 + n2];
    let mut v = vec![0.0; n1 + n2];
    for j in 0..u0.len() {
        let i = start + j;
        if i < n1 + n2 {
            b = b.displacement(i, u0[j]).velocity(i, v0[j] * s1);
            u[i] = u0[j];
            v[i] = v0[j] * s1;
        }
    }
    for x in u.iter_mut().take(start) {
        *x = u0[0];
    }
    let e_in = energy(&masses, &u, &v);
    let lightest = m1.min(m2);
    // Step: 1/200 of the contact time of the lightest grains at the fastest speed they reach
    // (at most twice the incident peak velocity when light grains are hit by heavy ones).
    let vmax = v0[HALF].abs() * s1 * if m2 < m1 { 2.0 } else { 1.0 };
    let mu = lightest / 2.0;
    let dmax = ((P + 1.0) * mu * vmax * vmax / 2.0).powf(1.0 / (P + 1.0));
    let tc = 2.94 * dmax / vmax;
    let t_end = duration * m1.sqrt();
    let mut sim = b
        .params(bm4(tc / 200.0))
        .schedule(t_end, t_end / 200.0)
        .build()
        .unwrap();
    sim.watch_reflections(0, n1 - 1, grainchain_engine::ReflectionRule::default())
        .unwrap();
    let mut min_v: f64 = 0.0;
    sim.run(|fr: &Frame| {
        for i in 0..n1 {
            min_v = min_v.min(fr.state.v[i]);
        }
        Ok::<(), RunError>(())
    })
    .unwrap();
    let hits = sim.take_reflections();
    let st = sim.state();
    // Half of the interface contact's potential belongs to the first section (the paper's
    // grain-energy convention).
    let e_first = energy(&masses[..n1], &st.u[..n1], &st.v[..n1])
        + (st.u[n1 - 1] - st.u[n1]).max(0.0).powf(P + 1.0) / (P + 1.0) / 2.0;
    // Grains at least NEAR grains from the interface (contact between them and the rest halved).
    let far = n1 - NEAR;
    let e_far = energy(&masses[..far], &st.u[..far], &st.v[..far])
        + (st.u[far - 1] - st.u[far]).max(0.0).powf(P + 1.0) / (P + 1.0) / 2.0;
    Crossing {
        e_in,
        e_first,
        e_far,
        min_v_first: min_v / (v0[HALF].abs() * s1),
        second: State {
            t: st.t,
            u: st.u[n1..].to_vec(),
            v: st.v[n1..].to_vec(),
            dissipated: Vec::new(),
        },
        m2,
        hits,
    }
}

/// Per-grain energies of a section of equal masses `m` (half of each contact's potential to each
/// of its grains), computed here.
fn grain_energies(m: f64, st: &State) -> Vec<f64> {
    let n = st.v.len();
    let half = |k: usize| (st.u[k - 1] - st.u[k]).max(0.0).powf(P + 1.0) / (P + 1.0) / 2.0;
    (0..n)
        .map(|i| {
            let l = if i > 0 { half(i) } else { 0.0 };
            let r = if i + 1 < n { half(i + 1) } else { 0.0 };
            0.5 * m * st.v[i] * st.v[i] + l + r
        })
        .collect()
}

/// Run time for the transmitted train to form and separate, in units of the unit-mass chain's
/// time (multiplied by sqrt(m1) in `cross`): the counts at every threshold below are the same at
/// 200 and 300 for ratios 2..20 (measured while writing this check); for ratio 50 the last heavy
/// grain starts to recoil after about 250.
const DURATION: f64 = 200.0;

/// Counting thresholds: a transmitted pulse counts when its energy is at least this fraction
/// of the leading pulse's energy (pulses split by grainchain's valley rule, valley = 0.25).
const THRESHOLDS: [f64; 5] = [1e-1, 3e-2, 1e-2, 3e-3, 1e-3];
/// The threshold at which the count is asserted against "about the mass ratio".
const COUNT_AT: f64 = 1e-2;

cases! {
/// Check 7: heavy to light, same Hertz law (physics.md 6, Hong 2005 Fig. 1). A clean solitary
/// wave of the heavy chain (peak 20 grains before the interface) meets grains of mass 1.
fn heavy_to_light(ratio: f64) {
    let c = cross(ratio, 1.0, 20, 1200, DURATION);
    let refl = c.e_far / c.e_in;
    let e = grain_energies(c.m2, &c.second);
    let pulses = detect_pulses(
        &e,
        &c.second.v,
        &PulseRule {
            threshold: 1e-6,
            valley: 0.25,
        },
    );
    let lead = pulses.iter().map(|p| p.energy).fold(0.0, f64::max);
    let counts: Vec<usize> = THRESHOLDS
        .iter()
        .map(|th| pulses.iter().filter(|p| p.energy >= th * lead).count())
        .collect();
    let count = pulses
        .iter()
        .filter(|p| p.energy >= COUNT_AT * lead)
        .count();
    let params = format!("m_heavy/m_light={ratio}");
    // Reflected energy: the energy at the end in heavy grains at least 5 grains from the
    // interface. A reflected wave would have run 100+ grains back by then (to the free end); the
    // 5 grains at the interface keep pushing forward and hold the untransmitted rest. Bound
    // 1e-4 of the incident energy: the criterion for total transmission.
    let ok_r = refl < 1e-4;
    // Backward motion: the cut wave's tails carry velocities of relative size 1e-13, the
    // smallest number this measurement can resolve; 1e-9 of the peak velocity is far above that
    // and far below any reflected wave.
    let ok_b = c.min_v_first > -1e-9;
    // Count: the paper's "about the mass ratio" (physics.md 6); asserted within 25% at the
    // stated threshold, for every ratio of the grid.
    let ok_c = (count as f64 / ratio - 1.0).abs() <= 0.25;
    record(&[
        Row::new(
            "heavy to light: reflected energy",
            params.clone(),
            "physics.md 6: total transmission",
        )
        .expected("< 1e-4 of incident")
        .measured(format!(
            "{refl:.1e} (all heavy grains: {:.1e}, forward-moving at the interface)",
            c.e_first / c.e_in
        ))
        .tolerance("bound 1e-4")
        .pass(ok_r),
        Row::new(
            "heavy to light: heavy grains moving backwards",
            params.clone(),
            "physics.md 6: no reflected wave",
        )
        .expected("none (min v >= 0)")
        .measured(format!("min v / v_peak = {:.1e}", c.min_v_first))
        .tolerance("-1e-9 of v_peak (tails of the cut wave)")
        .pass(ok_b),
        Row::new(
            "heavy to light: transmitted waves",
            params,
            "physics.md 6, Hong 2005: about the mass ratio",
        )
        .expected(format!("about {ratio}"))
        .measured(format!(
            "{count} at 1% of the lead's energy; at 10%, 3%, 1%, 0.3%, 0.1%: {counts:?}"
        ))
        .tolerance("25% of the ratio at 1%")
        .pass(ok_c),
    ]);
    assert!(ok_r, "ratio {ratio}: reflected {refl:e}");
    assert!(ok_b, "ratio {ratio}: backward velocity {}", c.min_v_first);
    assert!(ok_c, "ratio {ratio}: {count} waves");
}
case_1(2.0),
case_2(5.0),
case_3(10.0),
case_4(20.0),
case_5(50.0),
}

/// Check 8: light to heavy (physics.md 6): part of the wave is reflected, and the transmitted
/// fraction falls monotonically as the mass ratio grows. The two-point-mass elastic value
/// 4q/(1+q)^2 is reported beside it for comparison (not asserted: a chain is not two masses).
#[test]
fn light_to_heavy() {
    let ratios = [2.0, 5.0, 10.0, 20.0, 50.0];
    let mut rows = Vec::new();
    let mut trans = Vec::new();
    for &q in &ratios {
        let c = cross(1.0, q, 20, 400, DURATION);
        let t = 1.0 - c.e_first / c.e_in;
        let r = c.e_first / c.e_in;
        // Reflection present: more than 1% of the incident energy stays on the light side (the
        // point-mass value is 11% already at q = 2).
        let ok = r > 1e-2;
        rows.push(
            Row::new(
                "light to heavy: reflection and transmission",
                format!("m_heavy/m_light={q}"),
                "physics.md 6 (reflection present; cf. 4q/(1+q)^2)",
            )
            .expected(format!(
                "reflected > 1e-2; point masses: transmitted {}",
                g(4.0 * q / (1.0 + q).powi(2))
            ))
            .measured(format!("transmitted {}, reflected {}", g(t), g(r)))
            .tolerance("reflected > 1e-2")
            .pass(ok),
        );
        trans.push(t);
    }
    let mono = trans.windows(2).all(|w| w[1] < w[0]);
    rows.push(
        Row::new(
            "light to heavy: transmission falls with ratio",
            "ratios 2, 5, 10, 20, 50",
            "physics.md 6",
        )
        .expected("strictly decreasing")
        .measured(trans.iter().map(|t| g(*t)).collect::<Vec<_>>().join(" > "))
        .tolerance("exact order")
        .pass(mono),
    );
    let all_ok = rows.iter().all(|r| r.status != common::Status::Fail);
    record(&rows);
    assert!(all_ok && mono, "transmitted fractions {trans:?}");
}

/// The paper's mechanism counted at an interface (`validation/mechanism.rs` has the rule's other
/// known answers): the hits on the light section's right edge (the interface) transmit, summed,
/// the share of the incident energy that the energy left in the light section at the end gives
/// (check 8's transmitted fraction, from the final state), and the first hit's incident energy
/// is the wave's.
#[test]
fn reflections_count_the_light_to_heavy_share() {
    let mut rows = Vec::new();
    let mut ok_all = true;
    for q in [2.0, 5.0, 10.0] {
        let c = cross(1.0, q, 20, 400, DURATION);
        let right: Vec<_> = c
            .hits
            .iter()
            .filter(|h| h.edge == grainchain_engine::Edge::Right)
            .collect();
        let sent: f64 = right.iter().map(|h| h.transmitted).sum();
        let share = sent / c.e_in;
        let expected = 1.0 - c.e_first / c.e_in;
        let first = right.first().map_or(0.0, |h| h.incident / c.e_in);
        // The work is summed with the trapezoid rule over steps of 1/200 of a contact time
        // (second order: about 3e-5 of the energy), the final state's energy is exact to the
        // integrator's error (fourth order, smaller): 1e-3 of the incident energy covers both
        // with room. The incident energy at the peak carries the velocities' opening-kick shift
        // (0.08 of a step of a pulse lasting 200 steps) and the wave's tails beyond the 10-grain
        // zone (below 1e-6 of its energy): 1 %.
        let ok = (share - expected).abs() <= 1e-3 && (first - 1.0).abs() <= 1e-2;
        ok_all &= ok;
        rows.push(
            Row::new(
                "reflections: light-to-heavy share",
                format!("m_heavy/m_light={q}, {} hits", right.len()),
                "check 8's final-state share; the incident wave's energy",
            )
            .expected(format!("share {}, first incident 1", g(expected)))
            .measured(format!("share {}, first incident {}", g(share), g(first)))
            .tolerance("share 1e-3 absolute, incident 1 %")
            .pass(ok),
        );
    }
    record(&rows);
    assert!(
        ok_all,
        "{:?}",
        rows.iter().map(|r| &r.measured).collect::<Vec<_>>()
    );
}
