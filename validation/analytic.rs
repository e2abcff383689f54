//! Analytic checks of the model against exact or asymptotic results (physics.md sections 2-5):
//! the solitary wave's width, speed and energy split, the exact scaling symmetries, two-grain
//! collisions and the linear spring chain.

use crate::common;

use common::{argmax_abs, bm4, g, record, record_one, rel, Row};
use grainchain_engine::problems::{LinearSpringChain, SolitaryWave, TwoGrainCollision};
use grainchain_engine::State;
use grainchain_engine::{Frame, RunError, SimulationBuilder};

use crate::common::Stop;

/// Continuum width L(p) = (pi/(p-1)) sqrt(p(p+1)/6) in grain diameters (physics.md 2).
fn continuum_width(p: f64) -> f64 {
    std::f64::consts::PI / (p - 1.0) * (p * (p + 1.0) / 6.0).sqrt()
}

/// Contact time of two grains of reduced mass `mu` approaching at `v` (physics.md 4), with
/// I_p = B(1/(p+1), 1/2)/(p+1) from ln-gamma (no grainchain code involved).
fn contact_time(p: f64, eta: f64, mu: f64, v: f64) -> f64 {
    let dmax = ((p + 1.0) * mu * v * v / (2.0 * eta)).powf(1.0 / (p + 1.0));
    let ip = common::beta(1.0 / (p + 1.0), 0.5) / (p + 1.0);
    2.0 * dmax / v * ip
}

/// Potential energy of contact between grains i-1 and i, computed here (eta = 1).
fn contact_pe(p: f64, u: &[f64], k: usize) -> f64 {
    let x = (u[k - 1] - u[k]).max(0.0);
    x.powf(p + 1.0) / (p + 1.0)
}

/// Measurements of one travelling solitary wave (equal-mass striker, eta = m = 1).
struct WaveStats {
    /// Overlap-weighted r.m.s. extent of the contact-overlap (discrete strain) profile, averaged
    /// over phases (grains).
    strain_rms: f64,
    /// |v|-weighted r.m.s. extent of the grain-velocity profile, averaged over phases.
    velocity_rms: f64,
    /// Time-averaged kinetic energy / energy of the grains around the wave.
    ke_fraction: f64,
    /// Phases sampled.
    frames: usize,
}

/// Weighted r.m.s. extent of non-negative weights `w` placed at 0, 1, 2, ...
pub(crate) fn rms_extent(w: &[f64]) -> f64 {
    let sw: f64 = w.iter().sum();
    let c = w.iter().enumerate().map(|(j, x)| j as f64 * x).sum::<f64>() / sw;
    let var = w
        .iter()
        .enumerate()
        .map(|(j, x)| (j as f64 - c).powi(2) * x)
        .sum::<f64>()
        / sw;
    var.sqrt()
}

/// Follow the wave while its peak is between grains `from` and `to` and average the profiles'
/// r.m.s. extents and the kinetic-energy fraction over every output time (40 per contact time,
/// so many phases of the wave relative to the lattice are sampled).
fn measure_wave(p: f64, from: usize, to: usize) -> WaveStats {
    let n = to + 40;
    let tc = contact_time(p, 1.0, 0.5, 1.0);
    let half = (3.0 * continuum_width(p)).ceil() as usize + 2;
    let mut sim = SimulationBuilder::new(SolitaryWave::unit(p, n, 1.0).chain().unwrap())
        // t_c/400 with the 4th-order method: relative error of the profile far below 1e-6.
        .params(bm4(tc / 400.0))
        .schedule(1e4, tc / 40.0)
        .build()
        .unwrap();
    let (mut srms, mut vrms, mut ke_sum, mut e_sum, mut frames) = (0.0, 0.0, 0.0, 0.0, 0usize);
    let r = sim.run(|fr: &Frame| -> Result<(), Stop> {
        let (u, v) = (&fr.state.u, &fr.state.v);
        let k = argmax_abs(v);
        if k >= to {
            return Err(Stop::Done);
        }
        if k < from {
            return Ok(());
        }
        // Grains a..=b; contacts a..=b+1 (contact i joins grains i-1 and i).
        let (a, b) = (k - half, k + half);
        let w: Vec<f64> = (a..=b).map(|i| v[i].abs()).collect();
        vrms += rms_extent(&w);
        let d: Vec<f64> = (a..=b + 1).map(|i| (u[i - 1] - u[i]).max(0.0)).collect();
        srms += rms_extent(&d);
        let ke: f64 = (a..=b).map(|i| 0.5 * v[i] * v[i]).sum();
        let pe: f64 = (a..=b + 1).map(|i| contact_pe(p, u, i)).sum();
        ke_sum += ke;
        e_sum += ke + pe;
        frames += 1;
        Ok(())
    });
    assert!(
        matches!(r, Err(Stop::Done)),
        "the wave never reached grain {to}"
    );
    WaveStats {
        strain_rms: srms / frames as f64,
        velocity_rms: vrms / frames as f64,
        ke_fraction: ke_sum / e_sum,
        frames,
    }
}

/// The r.m.s. extent, as a fraction of L, of the continuum profile cos^(2/(p-1))(pi s / L) on
/// |s| <= L/2 (the velocity follows the strain in a travelling wave), by Simpson quadrature.
pub(crate) fn continuum_rms_ratio(p: f64) -> f64 {
    let n = 2.0 / (p - 1.0);
    let w = |y: f64| (std::f64::consts::PI * y).cos().max(0.0).powf(n);
    let m0 = common::simpson(w, -0.5, 0.5, 20_000);
    let m2 = common::simpson(|y| y * y * w(y), -0.5, 0.5, 20_000);
    (m2 / m0).sqrt()
}

cases! {
/// Check 1: solitary-wave width against L(p).
///
/// Definition: L(p) is the width of the continuum strain profile xi ~ cos^(2/(p-1)). Its
/// discrete counterpart is the contact overlap delta_k = u_{k-1} - u_k. The measured width is the
/// overlap-weighted r.m.s. extent of the overlap profile (in grains, averaged over the phases
/// sampled while the wave travels from grain 60 to grain 140) divided by the r.m.s.-to-width
/// ratio of the continuum profile (Simpson quadrature here). The striker has the grain mass; 60
/// grains are enough for its small trailing residue to fall far behind. The velocity profile's
/// width (same definition, |v| weights) is reported beside it.
fn solitary_wave_width(p: f64) {
    let s = measure_wave(p, 60, 140);
    let ratio = continuum_rms_ratio(p);
    let width = s.strain_rms / ratio;
    let vwidth = s.velocity_rms / ratio;
    let want = continuum_width(p);
    // Tolerance: the continuum theory gives one strain field; the discrete chain has its strain
    // on contacts and its velocity on grains, and the two discrete profiles differ exactly by a
    // unit-box average (variance + 1/12 grain^2; measured here to hold). Which one the theory
    // describes is beyond its resolution, an ambiguity of (1/12)/2 in the variance, i.e.
    // 1/(24 sigma^2) in relative width, sigma = the continuum r.m.s. extent: 8.4% at p = 1.5,
    // 17.8% at p = 3. A wrong exponent by 0.1 moves L by 13-20% and still fails.
    let sigma = ratio * want;
    let tol = 1.0 / (24.0 * sigma * sigma);
    let ok = rel(width, want) < tol;
    record_one(
        Row::new(
            "solitary wave width",
            format!("p={p}"),
            "physics.md 2: L(p)",
        )
        .expected(format!("{} grains", g(want)))
        .measured(format!(
            "{} grains ({:+.1}%; velocity profile {}, {} phases)",
            g(width),
            100.0 * (width / want - 1.0),
            g(vwidth),
            s.frames
        ))
        .tolerance(format!("{:.1}% relative", tol * 100.0))
        .pass(ok),
    );
    assert!(ok, "p={p}: width {width} vs {want}");
}
case_1(1.5),
case_2(2.0),
case_3(2.5),
case_4(3.0),
}

cases! {
/// Check 3: time-averaged kinetic-energy fraction of a travelling solitary wave, (p+1)/(p+3)
/// (virial identity, physics.md 2). Same runs as the width; the average is over 1600 output
/// times spread uniformly over 80 grain passages; the energy is that of the grains within three
/// widths of the peak, computed here from u and v.
fn solitary_wave_kinetic_fraction(p: f64) {
    let s = measure_wave(p, 60, 140);
    let want = (p + 1.0) / (p + 3.0);
    // Tolerance 1e-3 absolute: the identity is exact for a travelling wave of the discrete chain;
    // the average covers about 80 passages of the wave over one grain but not a whole number of
    // them, so the kinetic fraction's oscillation at the lattice period (a few per cent) is left
    // with a weight of at most 1/80 * its amplitude.
    let tol = 1e-3;
    let ok = (s.ke_fraction - want).abs() < tol;
    record_one(
        Row::new(
            "solitary wave kinetic-energy fraction",
            format!("p={p}"),
            "physics.md 2: virial (p+1)/(p+3)",
        )
        .expected(format!("{want:.6}"))
        .measured(format!("{:.6} ({} samples)", s.ke_fraction, s.frames))
        .tolerance(format!("{tol:e} absolute"))
        .pass(ok),
    );
    assert!(ok, "p={p}: kinetic fraction {} vs {want}", s.ke_fraction);
}
case_1(1.5),
case_2(2.0),
case_3(3.0),
}

/// Time-weighted mean passage time of the velocity pulse at grain `j` and its peak velocity
/// (parabolic refinement), from a run of the struck chain.
struct Passage {
    t_mean: [f64; 2],
    v_peak: f64,
}

/// Run an equal-mass striker at `speed` into the chain and time the pulse at grains j1 < j2.
fn passage(p: f64, speed: f64, dt: f64, j1: usize, j2: usize) -> Passage {
    let n = j2 + 30;
    // Sampling proportional to this amplitude's contact time (measurement only).
    let h = contact_time(p, 1.0, 0.5, speed) / 40.0;
    let mut sim = SimulationBuilder::new(SolitaryWave::unit(p, n, speed).chain().unwrap())
        .params(bm4(dt))
        .schedule(1e9 * h, h)
        .build()
        .unwrap();
    let (mut s, mut st) = ([0.0; 2], [0.0; 2]);
    let mut trace = Vec::new();
    let r = sim.run(|fr: &Frame| -> Result<(), Stop> {
        let v = &fr.state.v;
        for (k, &j) in [j1, j2].iter().enumerate() {
            s[k] += v[j];
            st[k] += v[j] * fr.state.t;
        }
        trace.push(v[j2]);
        if argmax_abs(v) >= j2 + 10 {
            return Err(Stop::Done);
        }
        Ok(())
    });
    assert!(matches!(r, Err(Stop::Done)));
    Passage {
        t_mean: [st[0] / s[0], st[1] / s[1]],
        v_peak: common::parabolic_peak(&trace, 0.0, h).1,
    }
}

cases! {
/// Check 2: speed of the solitary wave against its peak grain velocity, V ~ v_max^((p-1)/(p+1))
/// (physics.md 2), fitted over two decades of striker speed (1e-2 .. 1). V is measured as
/// 60 grains over the difference of the velocity-weighted mean passage times at grains 60 and
/// 120 (for a travelling wave this difference is exactly 60/V), v_max as the peak velocity of
/// grain 120. One step size for all amplitudes (t_c/400 at the largest), so the integrator
/// error differs between them.
fn solitary_wave_speed_exponent(p: f64) {
    let dt = contact_time(p, 1.0, 0.5, 1.0) / 400.0;
    let (mut lx, mut ly) = (Vec::new(), Vec::new());
    for k in 0..=4 {
        let speed = 10f64.powf(-2.0 + 0.5 * k as f64);
        let ps = passage(p, speed, dt, 60, 120);
        let vel = 60.0 / (ps.t_mean[1] - ps.t_mean[0]);
        lx.push(ps.v_peak.ln());
        ly.push(vel.ln());
    }
    let (slope, _, se) = common::fit_line(&lx, &ly);
    let want = (p - 1.0) / (p + 1.0);
    // Tolerance 1e-5: the amplitude symmetry (physics.md 3) makes the exponent exact for the
    // discrete chain. What remains: the integrator error (BM4 at t_c/400 or finer: relative
    // error below 1e-7 in times and velocities, spread over ln(100) = 4.6 in the fit) and the
    // peak interpolation, which is the same relative error at every amplitude because the
    // sampling is proportional to the contact time. 1e-5 is 100x above that; a law with a
    // wrong exponent p +- 0.01 moves the slope by 4e-3 or more.
    let tol = 1e-5;
    let ok = (slope - want).abs() < tol;
    record_one(
        Row::new(
            "solitary wave speed exponent",
            format!("p={p}, striker 1e-2..1"),
            "physics.md 2-3: V ~ v_max^((p-1)/(p+1))",
        )
        .expected(format!("{want:.6}"))
        .measured(format!("{slope:.6} (fit s.e. {se:.1e}, 5 speeds)"))
        .tolerance(format!("{tol:e} absolute"))
        .pass(ok),
    );
    assert!(ok, "p={p}: exponent {slope} vs {want}");
}
case_1(1.5),
case_2(2.0),
case_3(3.0),
}

/// Final state of a struck chain (`n` grains of mass `mass`, striker of the same mass at
/// `speed`) after `duration`, with BM4 at step `dt`.
fn final_state(p: f64, n: usize, mass: f64, speed: f64, duration: f64, dt: f64) -> State {
    let chain = SolitaryWave {
        p,
        eta: 1.0,
        mass,
        grains: n,
        speed,
    }
    .chain()
    .unwrap();
    let mut sim = SimulationBuilder::new(chain)
        .params(bm4(dt))
        .schedule(duration, duration)
        .build()
        .unwrap();
    sim.run(|_| Ok::<(), RunError>(())).unwrap();
    sim.state().clone()
}

/// max_i |a_i * sa - b_i| / max_i |b_i|
fn scaled_diff(a: &[f64], sa: f64, b: &[f64]) -> f64 {
    let m = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |d, (x, y)| d.max((x * sa - y).abs()))
        / m
}

/// Relative change of a state when the step is halved: (u, v) max-norm differences.
fn halving_change(a: &State, b: &State) -> (f64, f64) {
    (scaled_diff(&a.u, 1.0, &b.u), scaled_diff(&a.v, 1.0, &b.v))
}

cases! {
/// Check 4 (amplitude): a striker speed scaled by kappa gives u_B(t) = lambda u_A(kappa^((p-1)/
/// (p+1)) t), lambda = kappa^(2/(p+1)) (physics.md 3). Both runs use the same absolute step, so
/// their integrator errors differ; the tolerance is built from each run's own error estimate.
fn amplitude_symmetry(p: f64, kappa: f64) {
    let n = 40;
    let tc = contact_time(p, 1.0, 0.5, 1.0);
    let ta = 15.0 * tc;
    let tb = ta * kappa.powf(-(p - 1.0) / (p + 1.0));
    let lambda = kappa.powf(2.0 / (p + 1.0));
    // One absolute step for both: t_c/400 of the faster of the two runs.
    let dt = tc.min(tc * kappa.powf(-(p - 1.0) / (p + 1.0))) / 400.0;
    let a1 = final_state(p, n, 1.0, 1.0, ta, dt);
    let a2 = final_state(p, n, 1.0, 1.0, ta, dt / 2.0);
    let b1 = final_state(p, n, 1.0, kappa, tb, dt);
    let b2 = final_state(p, n, 1.0, kappa, tb, dt / 2.0);
    let du = scaled_diff(&a1.u, lambda, &b1.u);
    let dv = scaled_diff(&a1.v, kappa, &b1.v);
    let (eau, eav) = halving_change(&a1, &a2);
    let (ebu, ebv) = halving_change(&b1, &b2);
    // Tolerance: for a method of order >= 1 the error at dt is at most twice the change when dt
    // is halved; the two runs' errors add; a factor 2 of margin; plus 1e-12 for round-off of
    // ~1e5 steps (the scaled quantities are compared relative to their maximum).
    let tol_u = 4.0 * (eau + ebu) + 1e-12;
    let tol_v = 4.0 * (eav + ebv) + 1e-12;
    let ok = du <= tol_u && dv <= tol_v;
    record_one(
        Row::new(
            "amplitude symmetry",
            format!("p={p}, kappa={kappa:e}"),
            "physics.md 3: u -> lambda u(lambda^((p-1)/2) t)",
        )
        .expected("u_B = lambda u_A, v_B = kappa v_A")
        .measured(format!("rel. diff u {du:.1e}, v {dv:.1e}"))
        .tolerance(format!(
            "u {tol_u:.1e}, v {tol_v:.1e} (4x step-halving change)"
        ))
        .pass(ok),
    );
    assert!(
        ok,
        "p={p} kappa={kappa}: du {du:e} (tol {tol_u:e}), dv {dv:e} (tol {tol_v:e})"
    );
}
case_1(1.5, 1e-2),
case_2(1.5, 1e2),
case_3(2.0, 1e-2),
case_4(2.0, 1e2),
case_5(3.0, 1e-2),
case_6(3.0, 1e2),
}

cases! {
/// Check 4 (mass): every mass times mu is time slowed by sqrt(mu): with the striker speed divided
/// by sqrt(mu), u_B(sqrt(mu) t) = u_A(t) and v_B = v_A / sqrt(mu) (physics.md 3).
fn mass_symmetry(p: f64, mu: f64) {
    let n = 40;
    let tc = contact_time(p, 1.0, 0.5, 1.0);
    let ta = 15.0 * tc;
    let tb = ta * mu.sqrt();
    let dt = tc.min(tc * mu.sqrt()) / 400.0;
    let a1 = final_state(p, n, 1.0, 1.0, ta, dt);
    let a2 = final_state(p, n, 1.0, 1.0, ta, dt / 2.0);
    let b1 = final_state(p, n, mu, 1.0 / mu.sqrt(), tb, dt);
    let b2 = final_state(p, n, mu, 1.0 / mu.sqrt(), tb, dt / 2.0);
    let du = scaled_diff(&a1.u, 1.0, &b1.u);
    let dv = scaled_diff(&a1.v, 1.0 / mu.sqrt(), &b1.v);
    let (eau, eav) = halving_change(&a1, &a2);
    let (ebu, ebv) = halving_change(&b1, &b2);
    // Same construction as the amplitude symmetry: 4x the step-halving changes plus round-off.
    let tol_u = 4.0 * (eau + ebu) + 1e-12;
    let tol_v = 4.0 * (eav + ebv) + 1e-12;
    let ok = du <= tol_u && dv <= tol_v;
    record_one(
        Row::new(
            "mass symmetry",
            format!("p={p}, mu={mu:e}"),
            "physics.md 3: masses x mu = time x sqrt(mu)",
        )
        .expected("u_B(sqrt(mu) t) = u_A(t)")
        .measured(format!("rel. diff u {du:.1e}, v {dv:.1e}"))
        .tolerance(format!(
            "u {tol_u:.1e}, v {tol_v:.1e} (4x step-halving change)"
        ))
        .pass(ok),
    );
    assert!(
        ok,
        "p={p} mu={mu}: du {du:e} (tol {tol_u:e}), dv {dv:e} (tol {tol_v:e})"
    );
}
case_1(1.5, 1e-2),
case_2(1.5, 1e2),
case_3(3.0, 1e-2),
case_4(3.0, 1e2),
}

cases! {
/// Check 5: two-grain collision. A striker of mass `ratio` hits a resting grain of mass 1 at
/// speed 1 (eta = 1). Contact duration against 2 (delta_max / v) B(1/(p+1), 1/2)/(p+1), and the
/// outgoing velocities against the elastic point-mass result (physics.md 4).
fn two_grain_collision(p: f64, ratio: f64) {
    let (m1, m2, v) = (ratio, 1.0, 1.0);
    let mu = m1 * m2 / (m1 + m2);
    let tc = contact_time(p, 1.0, mu, v);
    let chain = TwoGrainCollision {
        p,
        eta: 1.0,
        striker_mass: m1,
        grain_mass: m2,
        speed: v,
    }
    .chain()
    .unwrap();
    let h = tc / 500.0;
    let mut sim = SimulationBuilder::new(chain)
        .params(bm4(tc / 2000.0))
        .schedule(1.5 * tc, h)
        .build()
        .unwrap();
    let mut overlap = Vec::new();
    sim.run(|fr: &Frame| {
        overlap.push(fr.state.u[0] - fr.state.u[1]);
        Ok::<(), RunError>(())
    })
    .unwrap();
    let k = (1..overlap.len()).find(|&k| overlap[k] <= 0.0).unwrap();
    let t_end = h * ((k - 1) as f64 + overlap[k - 1] / (overlap[k - 1] - overlap[k]));
    let st = sim.state();
    let want1 = (m1 - m2) / (m1 + m2) * v;
    let want2 = 2.0 * m1 / (m1 + m2) * v;
    let dvel = ((st.v[0] - want1).abs()).max((st.v[1] - want2).abs()) / v;
    // Tolerance 1e-6 relative on the duration: the end is found by linear interpolation between
    // outputs h = t_c/500 apart. Near separation the overlap is x = w s + O(s^(p+2)) in the time
    // s to separation (its curvature is the force, ~ x^p), so the interpolation error is of
    // order (h/t_c)^(p+2) <= 8e-9; BM4 at t_c/2000 has a relative error near (2 pi/2000)^4 = 1e-10
    // on the smooth part of the contact.
    let tol_t = 1e-6;
    // Tolerance 1e-9 of the approach speed on the velocities: momentum is conserved to round-off,
    // and after separation the speeds carry the energy error BM4 had when the contact opened, of
    // relative order (2 pi/2000)^4 = 1e-10.
    let tol_v = 1e-9;
    let ok_t = rel(t_end, tc) < tol_t;
    let ok_v = dvel < tol_v;
    let params = format!("p={p}, m1/m2={ratio}");
    record(&[
        Row::new(
            "two-grain contact duration",
            params.clone(),
            "physics.md 4: Beta-function formula",
        )
        .expected(g(tc))
        .measured(format!("{} (rel. diff {:.1e})", g(t_end), rel(t_end, tc)))
        .tolerance(format!("{tol_t:e} relative"))
        .pass(ok_t),
        Row::new(
            "two-grain outgoing velocities",
            params,
            "physics.md 4: elastic point masses",
        )
        .expected(format!("{}, {}", g(want1), g(want2)))
        .measured(format!(
            "{}, {} (max diff {dvel:.1e})",
            g(st.v[0]),
            g(st.v[1])
        ))
        .tolerance(format!("{tol_v:e} of v"))
        .pass(ok_v),
    ]);
    assert!(ok_t, "p={p} ratio={ratio}: contact time {t_end} vs {tc}");
    assert!(
        ok_v,
        "p={p} ratio={ratio}: velocities {:?} vs {want1}, {want2}",
        st.v
    );
}
case_1(1.0, 0.2),
case_2(1.0, 1.0),
case_3(1.0, 5.0),
case_4(1.5, 0.2),
case_5(1.5, 1.0),
case_6(1.5, 5.0),
case_7(2.0, 0.2),
case_8(2.0, 1.0),
case_9(2.0, 5.0),
case_10(3.0, 0.2),
case_11(3.0, 1.0),
case_12(3.0, 5.0),
}

/// Grain velocities of the two-sided linear spring chain (k = m = 1) after a kick of grain
/// `mid` to 1, sampled every `h` to `t_end`, with BM4 at step `dt`.
fn spring_chain_run(n: usize, mid: usize, dt: f64, h: f64, t_end: f64) -> Vec<Vec<f64>> {
    let mut sim = LinearSpringChain {
        grains: n,
        kicked: mid,
        k: 1.0,
        mass: 1.0,
        v0: 1.0,
    }
    .builder()
    .unwrap()
    .params(bm4(dt))
    .schedule(t_end, h)
    .build()
    .unwrap();
    let mut out = Vec::new();
    sim.run(|fr: &Frame| {
        out.push(fr.state.v.clone());
        Ok::<(), RunError>(())
    })
    .unwrap();
    out
}

/// Check 6: linear chain with two-sided springs: v_n(t) = v0 J_2n(2 omega0 t) (physics.md 5),
/// J computed here from its integral representation. 301 grains, kick in the middle, t <= 60:
/// the front (group velocity <= omega0 = 1 grain per unit time) stays 90 grains from the ends,
/// where J_2n(120) for n >= 150 is below 1e-30, so the finite chain is the infinite one.
#[test]
fn linear_chain_bessel() {
    let (n, mid, h, t_end) = (301, 150, 5.0, 60.0);
    let dt = 0.02;
    let run1 = spring_chain_run(n, mid, dt, h, t_end);
    let run2 = spring_chain_run(n, mid, dt / 2.0, h, t_end);
    let (mut err, mut change) = (0.0f64, 0.0f64);
    for (k, (a, b)) in run1.iter().zip(&run2).enumerate() {
        let t = k as f64 * h;
        for i in 0..n {
            let m = i as i64 - mid as i64;
            let exact = common::bessel_j(2 * m, 2.0 * t);
            err = err.max((a[i] - exact).abs());
            change = change.max((a[i] - b[i]).abs());
        }
    }
    // Tolerance: twice the step-halving change (an upper bound of the error of a method of order
    // >= 1 at dt), plus 1e-12 for round-off and the Bessel quadrature (accurate to ~1e-15).
    let tol = 2.0 * change + 1e-12;
    let ok = err <= tol && err < 1e-6;
    record_one(
        Row::new(
            "linear spring chain: v_n = J_2n(2 t)",
            format!("301 grains, t<=60, BM4 dt={dt}"),
            "physics.md 5: Bessel J_2n",
        )
        .expected("v0 J_2n(2 omega0 t)")
        .measured(format!("max abs error {err:.2e}"))
        .tolerance(format!("{tol:.1e} (2x step-halving change)"))
        .pass(ok),
    );
    assert!(ok, "max error {err:e}, tolerance {tol:e}");
}
