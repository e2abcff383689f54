//! Contact damping (`ContactLaw::with_damping`): the restitution of a two-grain collision
//! against theory, exactly speed-independent for the scale-respecting form, the energy budget
//! closing with the dissipated energy, and a damped linear chain against its modal solution
//! with the splitting methods' order measured.

use crate::common;

use common::{g, record, Row};
use grainchain_engine::Recorder;
use grainchain_engine::SimulationBuilder;
use grainchain_engine::{ChainBuilder, ContactLaw, DampingModel};
use grainchain_engine::{IntegrationParams, Method};

fn params(method: Method, dt: f64) -> IntegrationParams {
    IntegrationParams {
        method,
        dt,
        ..Default::default()
    }
}

/// Hertz contact time of two unit masses (m_eff = 1/2) with eta = 1 at approach speed `v`:
/// 3.2145 (m_eff/eta)^(2/5) v^(-1/5) (physics.md 4).
fn hertz_contact_time(v: f64) -> f64 {
    3.2145 * 0.5f64.powf(0.4) * v.powf(-0.2)
}

/// What a head-on collision of two unit masses does: grain 0 at speed `v` hits grain 1 at rest
/// through a Hertz contact (eta = 1) damped by `model` with coefficient `c`. Runs three elastic
/// contact times with `steps` steps per contact time (`method`), then returns the restitution
/// `(v1 - v0) / v` after separation, the energy left, the energy dissipated and the largest
/// relative error of `E + dissipated` against `E0` at any output.
fn collide(
    model: DampingModel,
    c: f64,
    v: f64,
    method: Method,
    steps: f64,
) -> (f64, f64, f64, f64) {
    let law = ContactLaw::hertz(1.0).with_damping(model, c);
    let chain = ChainBuilder::new().grains(2, 1.0, law).build().unwrap();
    let tc = hertz_contact_time(v);
    // Powers of two of the contact time, so that the scaling test's runs differ only by
    // exponents: the interval is tc/64 rounded down to a power of two, the step 1/steps of tc
    // likewise.
    let pow2 = |x: f64| 2f64.powi(x.log2().floor() as i32);
    let interval = pow2(tc / 64.0);
    let dt = pow2(tc / steps);
    let mut sim = SimulationBuilder::new(chain)
        .params(params(method, dt))
        .schedule(256.0 * interval, interval)
        .velocity(0, v)
        .build()
        .unwrap();
    let rec = Recorder::new().record(&mut sim).unwrap();
    let st = sim.state();
    assert!(st.u[0] < st.u[1], "the grains must have separated");
    let e0 = rec.totals[0].total;
    let err = rec
        .totals
        .iter()
        .zip(&rec.dissipated)
        .map(|(t, d)| ((t.total + d - e0) / e0).abs())
        .fold(0.0, f64::max);
    let e = (st.v[1] - st.v[0]) / v;
    (
        e,
        rec.totals.last().unwrap().total,
        *rec.dissipated.last().unwrap(),
        err,
    )
}

/// The scale-respecting form `c delta^((p-1)/2) d(delta)/dt` leaves the contact's equation
/// without a scale: speed `v 32^k`, time `t / 2^k`, overlap `delta 16^k` solve it exactly. In
/// floating point every quantity of the run is then scaled by a power of two (sqrt and
/// sqrt(sqrt) of 16^k x are exact), so the restitution must be the same to the last bit at
/// every speed: 7 speeds over 9 decades (2^-17 to 2^13).
#[test]
fn scale_respecting_restitution_is_the_same_at_every_speed() {
    let mut rows = Vec::new();
    let mut es = Vec::new();
    for k in 0..7 {
        let v = 2f64.powi(-17 + 5 * k);
        let (e, left, lost, err) = collide(
            DampingModel::ScaleRespecting,
            0.2,
            v,
            Method::Verlet,
            2000.0,
        );
        // The budget: E + dissipated = E0 to the integrator's error (verlet at tc/2048:
        // relative energy error of order (2 pi dt/tc)^2 / 8 ~ 1e-6 inside the contact).
        assert!(
            err < 1e-5,
            "v = {v:e}: E + dissipated differs from E0 by {err:e}"
        );
        assert!(lost > 0.0 && left > 0.0);
        rows.push(format!("v = 2^{}: e = {e}", -17 + 5 * k));
        es.push(e);
    }
    let same = es.iter().all(|&e| e.to_bits() == es[0].to_bits());
    record(&[Row::new(
        "scale-respecting damping: restitution independent of speed",
        "Hertz, c = 0.2, unit masses, v = 2^-17 ... 2^13 (x32), verlet tc/2048",
        "exact scaling (speed 32^k, time 2^-k, overlap 16^k)",
    )
    .expected("the same e, bit for bit, at every speed")
    .measured(format!("e = {} at all 7 speeds: {same}", g(es[0])))
    .tolerance("0 (bit for bit)")
    .pass(same)]);
    assert!(same, "restitution differs between speeds: {rows:?}");
    // Damping took energy: 0 < e < 1.
    assert!(es[0] > 0.0 && es[0] < 1.0, "e = {}", es[0]);
}

/// Restitution of the viscoelastic Hertz contact (Kuwabara-Kono / Brilliantov form,
/// F = eta delta^(3/2) + c delta^(1/2) d(delta)/dt, total force never tensile) as a function of
/// the single parameter b = c v^(1/5) / (eta^(3/5) m_eff^(2/5)) (so that b = A kappa^(2/5)
/// v^(1/5) in the notation of Schwager & Poschel, Phys. Rev. E 57, 650 (1998), with
/// kappa = (3/2)^(5/2) eta / m_eff and A = 2c/(3 eta)).
///
/// References: (1) the series 1 - e = C1 b - C2 b^2 - h5 b^(5/2) + O(b^3) with C1 = 1.15344
/// (Schwager & Poschel 1998), C2 = 0.79826 (Ramirez, Poschel, Brilliantov & Schwager, Phys.
/// Rev. E 60, 4465 (1999)) and h5 = 0.26667, the term of the clipped (never tensile) force
/// (Schwager & Poschel, Phys. Rev. E 78, 051304 (2008), expanded from the Pade approximant of
/// Muller & Poschel, Phys. Rev. E 84, 021302 (2011)); (2) that Pade approximant in x = sqrt(b)
/// itself, for larger b. The constants could not be read in the papers themselves here: C1 was
/// checked against its closed form Gamma(3/5) sqrt(pi) / (2^(1/5) 5^(2/5) Gamma(21/10)) =
/// 1.1534489 and C2 against (3/5) C1^2 = 0.7982666 (the relation of Ramirez et al.); see the
/// closing note of the issue.
#[test]
fn kuwabara_kono_restitution_follows_the_theory() {
    let c = 0.05;
    let m_eff: f64 = 0.5;
    let pade = |b: f64| {
        let x = b.sqrt();
        let num = 1.0 + 1.07232 * x + 0.574198 * x.powi(2) + 0.141552 * x.powi(3);
        let den = 1.0
            + 1.07232 * x
            + 1.72765 * x.powi(2)
            + 1.37842 * x.powi(3)
            + 1.19449 * x.powi(4)
            + 0.467273 * x.powi(5)
            + 0.235585 * x.powi(6);
        num / den
    };
    let series = |b: f64| 1.0 - 1.15344 * b + 0.79826 * b * b + 0.26667 * b.powf(2.5);
    let mut rows = Vec::new();
    let mut ok = true;
    let mut small_b = Vec::new();
    for k in 0..7 {
        let v = 10f64.powi(k - 4);
        let b = c * v.powf(0.2) / m_eff.powf(0.4);
        let (e, _, _, err) = collide(
            DampingModel::KuwabaraKono,
            c,
            v,
            Method::BlanesMoan4,
            4000.0,
        );
        // The Pade approximant's coefficients are given to 6 digits: 2e-5 on e covers their
        // rounding (the helper's direct integrations matched it to 1e-6 at b = 0.075 and
        // 0.15); the integrator's error at tc/4096 is far below (second order in the damping
        // flow, (1/4096)^2 ~ 6e-8 relative).
        let tol = 2e-5;
        let d = (e - pade(b)).abs();
        ok &= d < tol && err < 1e-6;
        if b < 0.03 {
            // The series to b^(5/2): the rest is h6 b^3 + h7 b^(7/2) with h6 = -0.5229 and
            // h7 = -0.461 (from the Pade approximant), 0.57-0.60 b^3 for these b: b^3 bounds
            // it (the integrator's share is below 1e-7, from the Pade rows).
            small_b.push((b, e, (e - series(b)).abs(), b.powi(3)));
        }
        rows.push(
            Row::new(
                "Kuwabara-Kono restitution",
                format!("Hertz, c = {c}, unit masses, v = {v:e} (b = {b:.4})"),
                "Muller & Poschel 2011 Pade approximant (clipped force)",
            )
            .expected(g(pade(b)))
            .measured(format!("{} (diff {d:.1e}; budget error {err:.1e})", g(e)))
            .tolerance(format!("{tol:e}"))
            .pass(d < tol && err < 1e-6),
        );
    }
    for &(b, e, d, tol) in &small_b {
        rows.push(
            Row::new(
                "Kuwabara-Kono restitution, small b",
                format!("b = {b:.4}"),
                "Schwager & Poschel 1998 series: 1 - 1.15344 b + 0.79826 b^2 + 0.26667 b^2.5",
            )
            .expected(g(series(b)))
            .measured(format!("{} (diff {d:.1e})", g(e)))
            .tolerance(format!("{tol:.1e} (the b^3 term)"))
            .pass(d < tol),
        );
        ok &= d < tol;
    }
    record(&rows);
    assert!(!small_b.is_empty(), "no speed gave b < 0.03");
    assert!(
        ok,
        "restitution off the theory: see target/validation/REPORT.md"
    );
}

/// A chain of 8 unit masses joined by two-sided linear springs (k = 1) with dashpots (viscous,
/// c = 0.2), free ends, grain 0 started at speed 1. Stiffness and damping matrices are both
/// proportional to the path graph's Laplacian, whose modes are known in closed form
/// (lambda_j = 4 sin^2(j pi / 2N), phi_j(i) = cos(j pi (i + 1/2) / N)), so each mode is a damped
/// oscillator: q_j(t) = q_j'(0) exp(-beta t) sin(omega t) / omega with beta = c lambda / 2,
/// omega = sqrt(k lambda - beta^2) (q_0 = q_0'(0) t). Verlet and blanes-moan4 at three steps:
/// the error falls as dt^2 for both (contact damping is carried by the drifts, `chain::damping`).
#[test]
fn damped_linear_chain_matches_its_modes() {
    damped_linear_chain(DampingModel::Viscous);
}

/// The same two-sided chain with scale-respecting damping: on a linear contact its q =
/// (p - 1)/2 is 0, so its force is `c d(delta)/dt` at every overlap, in tension (the springs
/// stretch: the modal solution's overlaps go below -0.1) as in compression, and the run must
/// match the same modal solution, with the same order. (Issue 24, item 4: the two-sided
/// contact's damping is the model's own form, not viscous by accident; kuwabara-kono, whose
/// delta^(1/2) has no value there, is refused: `kuwabara_kono_on_a_two_sided_contact_is_refused`.)
#[test]
fn scale_respecting_two_sided_chain_matches_its_modes() {
    damped_linear_chain(DampingModel::ScaleRespecting);
}

/// Kuwabara-Kono damping (`c delta^(1/2) d(delta)/dt`) on a two-sided contact, whose overlap
/// goes negative where delta^(1/2) has no value, is refused by the chain builder (section and
/// wall, at any c), naming the model and the tension; eb2d8c3 ran it as viscous.
#[test]
fn kuwabara_kono_on_a_two_sided_contact_is_refused() {
    use grainchain_engine::End;
    for c in [0.2, 0.0] {
        let law = ContactLaw::linear_spring(1.0).with_damping(DampingModel::KuwabaraKono, c);
        let section = ChainBuilder::new().grains(8, 1.0, law).build();
        let wall = ChainBuilder::new()
            .grains(8, 1.0, ContactLaw::linear_spring(1.0))
            .left(End::Wall(law))
            .build();
        for (what, r) in [("section", section), ("wall", wall)] {
            let msg = r.err().map(|e| e.to_string()).unwrap_or_default();
            assert!(
                msg.contains("kuwabara-kono") && msg.contains("two-sided (tension)"),
                "{what}, c = {c}: {msg:?}"
            );
        }
        // The compression-only contact keeps it, and the two-sided one the q = 0 forms.
        let hertz = ContactLaw::hertz(1.0).with_damping(DampingModel::KuwabaraKono, c);
        assert!(ChainBuilder::new().grains(8, 1.0, hertz).build().is_ok());
        for model in [DampingModel::Viscous, DampingModel::ScaleRespecting] {
            let law = ContactLaw::linear_spring(1.0).with_damping(model, c);
            assert!(ChainBuilder::new().grains(8, 1.0, law).build().is_ok());
        }
    }
}

/// [`damped_linear_chain_matches_its_modes`] with damping `model` (whose exponent on the linear
/// contact must be 0).
fn damped_linear_chain(model: DampingModel) {
    const N: usize = 8;
    let (k, c, t_end) = (1.0, 0.2, 10.0);
    let exact = |t: f64| {
        let (mut u, mut v) = ([0.0; N], [0.0; N]);
        for j in 0..N {
            let phi: Vec<f64> = (0..N)
                .map(|i| (j as f64 * std::f64::consts::PI * (i as f64 + 0.5) / N as f64).cos())
                .collect();
            let norm: f64 = phi.iter().map(|x| x * x).sum();
            let q1 = phi[0] / norm; // initial velocity (1, 0, ..., 0) projected
            let lam = 4.0
                * (j as f64 * std::f64::consts::PI / (2.0 * N as f64))
                    .sin()
                    .powi(2);
            let (q, qd) = if j == 0 {
                (q1 * t, q1)
            } else {
                let beta = c * lam / 2.0;
                let om = (k * lam - beta * beta).sqrt();
                let e = (-beta * t).exp();
                (
                    q1 * e * (om * t).sin() / om,
                    q1 * e * (om * (om * t).cos() - beta * (om * t).sin()) / om,
                )
            };
            for i in 0..N {
                u[i] += q * phi[i];
                v[i] += qd * phi[i];
            }
        }
        (u, v)
    };
    let (ue, ve) = exact(t_end);
    // The springs are stretched as well as compressed over the run (overlap u_i - u_{i+1}
    // below -0.1 at some time): the damping is measured in tension too.
    let stretched = (0..=1000)
        .map(|s| exact(t_end * s as f64 / 1000.0).0)
        .flat_map(|u| (0..N - 1).map(move |i| u[i] - u[i + 1]).collect::<Vec<_>>())
        .fold(f64::INFINITY, f64::min);
    assert!(stretched < -0.1, "smallest overlap {stretched}");
    let error = |method: Method, dt: f64| {
        let law = ContactLaw::linear_spring(k).with_damping(model, c);
        let chain = ChainBuilder::new().grains(N, 1.0, law).build().unwrap();
        let mut sim = SimulationBuilder::new(chain)
            .params(params(method, dt))
            .schedule(t_end, t_end / 4.0)
            .velocity(0, 1.0)
            .build()
            .unwrap();
        let rec = Recorder::new().record(&mut sim).unwrap();
        let st = sim.state();
        // The budget closes too (energy error of the method, order dt^2).
        let e0 = rec.totals[0].total;
        let last = rec.totals.last().unwrap().total + rec.dissipated.last().unwrap();
        assert!(
            ((last - e0) / e0).abs() < 1e-2,
            "{method:?} dt {dt}: budget"
        );
        (0..N)
            .map(|i| (st.u[i] - ue[i]).abs().max((st.v[i] - ve[i]).abs()))
            .fold(0.0, f64::max)
    };
    let mut rows = Vec::new();
    let mut ok = true;
    for (method, dt0) in [(Method::Verlet, 0.04), (Method::BlanesMoan4, 0.1)] {
        let errs: Vec<f64> = [dt0, dt0 / 2.0, dt0 / 4.0]
            .iter()
            .map(|&dt| error(method, dt))
            .collect();
        let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        // Second order: each halving of the step divides the error by 4 (order 2 +- 0.2, the
        // band of a clean asymptotic regime at these steps).
        let pass = orders.iter().all(|o| (1.8..=2.2).contains(o)) && errs[2] < 1e-3;
        ok &= pass;
        rows.push(
            Row::new(
                "damped linear chain against its modes",
                format!(
                    "{model:?}, {method:?}, N = 8, two-sided, k = 1, c = 0.2, t = 10, dt = {dt0}, /2, /4"
                ),
                "modal solution (proportional damping)",
            )
            .expected("order 2 (the damped drift)")
            .measured(format!(
                "max error {:.2e}, {:.2e}, {:.2e}; orders {:.2}, {:.2}",
                errs[0], errs[1], errs[2], orders[0], orders[1]
            ))
            .tolerance("order in [1.8, 2.2], finest error < 1e-3")
            .pass(pass),
        );
    }
    record(&rows);
    assert!(ok, "see target/validation/REPORT.md");
}

/// `TwoGrainCollision::damping_for_restitution` (what a study's `dissipation` uses) finds the
/// coefficient that gives the asked restitution, and with the scale-respecting form that
/// coefficient gives it at any speed (a speed 2^-15 times lower: the same bits, by scaling).
#[test]
fn damping_for_a_restitution() {
    use grainchain_engine::problems::TwoGrainCollision;
    for (p, m) in [(1.0, 2.0), (1.5, 1.0), (2.0, 100.0)] {
        let col = TwoGrainCollision {
            p,
            eta: 5657.0,
            striker_mass: m,
            grain_mass: m,
            speed: 1.0,
        };
        let c = col
            .damping_for_restitution(DampingModel::ScaleRespecting, 0.95)
            .unwrap();
        let e = col.restitution(DampingModel::ScaleRespecting, c).unwrap();
        // The bisection stops at 1e-12 of c; e is smooth in c (de/dc of order 1/sqrt(eta m)).
        assert!((e - 0.95).abs() < 1e-9, "p = {p}: e = {e}");
        let slow = TwoGrainCollision {
            speed: 2f64.powi(-15),
            ..col
        };
        let e_slow = slow.restitution(DampingModel::ScaleRespecting, c).unwrap();
        // For p = 1.5 every quantity scales by a power of two, but the contact time that sets
        // the step comes from `powf` and is not exactly 2^3 times longer at the low speed (3
        // ulp off), so the two runs differ by rounding only: 2.2e-15 measured, 1e-13 asked
        // (the Strang-split flow of before happened to give the same bits; the scaling itself
        // is checked bit for bit by `scale_respecting_restitution_is_the_same_at_every_speed`,
        // whose steps scale exactly). For p = 1 and 2 the time and overlap scale by powers of
        // 2^(15 (p-1)/(p+1)) that are not all powers of two, so only to the integrator's error
        // (about 1e-7 at tc/4096).
        let tol = if p == 1.5 { 1e-13 } else { 1e-6 };
        assert!(
            (e_slow - e).abs() <= tol,
            "p = {p}: {e_slow} at low speed, {e} at 1"
        );
    }
}
