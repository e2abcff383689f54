//! Published results as validation cases (issue 28, item 3): numbers and claims other people
//! computed or measured, each against grainchain's chain run through the public API. Every
//! expected value below is a formula or a statement of the cited paper, evaluated here; none
//! comes from grainchain's code. Where a paper's text could not be read (only its abstract or
//! first page was at hand), the row says which statement of it is used.
//!
//! The cases:
//! - Nesterenko's solitary wave in a *precompressed* chain (Daraio, Nesterenko, Herbold and
//!   Jin, PRE 73, 026610 (2006), their speed formula; Nesterenko 2001): the speed against
//!   `f_r = F_m / F_0`, and the formula's two limits;
//! - the super-exponential localisation of the discrete solitary wave (Chatterjee, PRE 59, 5912
//!   (1999); English and Pego, Proc. AMS 133, 1763 (2005); Ahnert and Pikovsky, PRE 79, 026209
//!   (2009)): the leading tail's logarithm grows by the factor p per grain;
//! - two balls dropped on a floor (the independent-collision answer of Mellen 1968 and Harter
//!   1971, as Müller and Pöschel, PRE 83, 041304 (2011), and Bartz, arXiv 2007.15005, state it):
//!   the upper ball leaves at (3 - q)/(1 + q) of the impact speed, 3 for a light one; touching
//!   balls with Hertz contacts do not follow it (Müller and Pöschel's point);
//! - two counter-propagating solitary waves (Santibanez, Munoz, Caussarieu, Job and Melo, PRE
//!   84, 026604 (2011), abstract): secondary waves proportional to the incident amplitude and
//!   stronger when the collision is at the middle contact (even chain) than at the middle bead
//!   (odd chain); the phase shift, on which the literature disagrees, is reported;
//! - Newton's cradle with soft contacts (Hutzler, Delaney, Weaire and MacLeod, Am. J. Phys. 72,
//!   1508 (2004), abstract): the first collision breaks the line of balls up;
//! - a heavy striker (Job, Melo, Sokolow and Sen, Granular Matter 10, 13 (2007), abstract): a
//!   train of solitary waves ordered by decreasing amplitude, and a nearly exponential unloading
//!   of the force at the struck end (reported).

use crate::common;

use common::{argmax_abs, bm4, fit_line, g, parabolic_peak, record_one, rel, Row, Stop};
use grainchain_engine::problems::SolitaryWave;
use grainchain_engine::{
    ChainBuilder, ContactLaw, End, Frame, SimulationBuilder, Striker, StrikerEnd,
};

/// Contact time of two grains of reduced mass `mu` approaching at `v` (physics.md 4; Hertz's
/// closed form for any p), for the steps and samplings below (not an expected value).
fn contact_time(p: f64, eta: f64, mu: f64, v: f64) -> f64 {
    let dmax = ((p + 1.0) * mu * v * v / (2.0 * eta)).powf(1.0 / (p + 1.0));
    2.0 * dmax / v * common::beta(1.0 / (p + 1.0), 0.5) / (p + 1.0)
}

// ------------------------------------------------------------------------------------------
// Nesterenko's solitary wave in a precompressed chain (Daraio et al. 2006)
// ------------------------------------------------------------------------------------------

/// Steel, as `materials.rs` writes it (`units::STEEL`'s data-sheet values).
const E: f64 = 200e9;
const NU: f64 = 0.29;
const RHO: f64 = 7800.0;

/// The speed of the solitary wave of a chain of spheres (diameter `a`) under a static force
/// `f0`, with force amplitude `fm` (the static force included), as Daraio, Nesterenko, Herbold
/// and Jin (PRE 73, 026610 (2006)) write Nesterenko's long-wave result:
/// `V_s = 0.9314 (4 E^2 F_0 / (a^2 rho^3 (1 - nu^2)^2))^(1/6) / (f_r^(2/3) - 1)
///        * (4/15 (3 + 2 f_r^(5/3) - 5 f_r^(2/3)))^(1/2)`, `f_r = F_m / F_0`. The paper's text
/// could not be read with the tools at hand: this is the formula as it is quoted from it, and
/// `precompressed_speed_formula_has_its_limits` checks it against both limits its derivation
/// must have, computed here independently.
fn daraio_speed(a: f64, f0: f64, fm: f64) -> f64 {
    let fr = fm / f0;
    let c = (4.0 * E * E * f0 / (a * a * RHO.powi(3) * (1.0 - NU * NU).powi(2))).powf(1.0 / 6.0);
    let f23 = fr.powf(2.0 / 3.0);
    0.9314 * c / (f23 - 1.0) * (4.0 / 15.0 * (3.0 + 2.0 * fr.powf(5.0 / 3.0) - 5.0 * f23)).sqrt()
}

/// Two equal steel spheres of diameter `a`: Hertz's constant `E a^(1/2) / (3 (1 - nu^2))`
/// (Hong Eq. 1 with R1 = R2 = a/2) and the mass.
fn steel_pair(a: f64) -> (f64, f64) {
    let eta = E * a.sqrt() / (3.0 * (1.0 - NU * NU));
    (eta, RHO * std::f64::consts::PI * a.powi(3) / 6.0)
}

/// The formula as transcribed above has the two limits its derivation requires, computed here
/// independently: as `f_r -> 1` the sound speed of the precompressed chain,
/// `c_0 = a sqrt(K / m)` with the contact stiffness `K = dF/d delta = (3/2) eta delta_0^(1/2)`,
/// and as `f_r -> infinity` Nesterenko's speed without precompression,
/// `0.6802 (2 E / (a rho^(3/2) (1 - nu^2)))^(1/3) F_m^(1/6)` (the formula `materials.rs`
/// checks). Tolerance: the constants are printed to four digits: 0.9314 for the exact
/// `sqrt(9 / (pi 3^(2/3))) / 4^(1/6) = 0.931456` (6.0e-5 relative) and 0.6802 for 0.680240
/// (5.9e-5); near f_r = 1 the formula is `c_0 (1 + (f_r - 1)/18 + ...)` (5.6e-7 at f_r - 1 =
/// 1e-5) and loses about 1e-5 to the cancellation in its bracket. 2e-4 holds all of it and fails
/// any other reading of the exponents or of the bracket (a 4/15 read as 4/5 moves it by 73 %).
#[test]
fn precompressed_speed_formula_has_its_limits() {
    let (a, f0): (f64, f64) = (8e-3, 10.0);
    let (eta, m) = steel_pair(a);
    let delta0 = (f0 / eta).powf(2.0 / 3.0);
    let c0 = a * (1.5 * eta * delta0.sqrt() / m).sqrt();
    let near = daraio_speed(a, f0, f0 * (1.0 + 1e-5));
    let fm = 1e9 * f0;
    let far = daraio_speed(a, f0, fm);
    let nesterenko = 0.6802
        * (2.0 * E / (a * RHO.powf(1.5) * (1.0 - NU * NU))).powf(1.0 / 3.0)
        * fm.powf(1.0 / 6.0);
    // At f_r = 1e9 the bracket's neglected terms are f_r^(-1) relative: 1e-9.
    let tol = 2e-4;
    let ok_near = rel(near, c0) < tol;
    let ok_far = rel(far, nesterenko) < tol;
    record_one(
        Row::new(
            "precompressed wave: formula's limits",
            "f_r -> 1 and f_r -> infinity, 8 mm steel, F_0 = 10 N",
            "Daraio et al. PRE 73, 026610 (2006): V_s(f_r); limits: c_0 = a sqrt(K/m), Nesterenko's 0.6802 formula",
        )
        .expected(format!("{} m/s and {} m/s", g(c0), g(nesterenko)))
        .measured(format!(
            "{} m/s ({:.1e} rel.) and {} m/s ({:.1e} rel.)",
            g(near),
            rel(near, c0),
            g(far),
            rel(far, nesterenko)
        ))
        .tolerance(format!("{tol:e} relative"))
        .pass(ok_near && ok_far),
    );
    assert!(ok_near, "f_r -> 1: {near} vs c0 {c0}");
    assert!(ok_far, "f_r -> inf: {far} vs {nesterenko}");
}

/// One wave of a precompressed steel chain: grain 1 (next to the left wall) kicked at `kick`;
/// the speed between beads `j1` and `j2` (the difference of the times of their velocity peaks,
/// each refined by a parabola) and the force amplitude (the static force included) at the
/// contacts into `j1` and `j2`.
struct PreWave {
    speed: f64,
    fm: [f64; 2],
}

fn precompressed_wave(a: f64, f0: f64, kick: f64, j1: usize, j2: usize) -> PreWave {
    let (eta, m) = steel_pair(a);
    let delta0 = (f0 / eta).powf(2.0 / 3.0);
    let law = ContactLaw::hertz(eta).with_precompression(delta0);
    let n = j2 + 40;
    let chain = ChainBuilder::new()
        .grains(n, m, law)
        .left(End::Wall(law))
        .right(End::Wall(law))
        .build()
        .unwrap();
    // Time scales: the linear period of one contact, 2 pi sqrt(m / K), and the contact time of
    // the kick's collision without precompression; steps 1/400 and samples 1/40 of the
    // shorter.
    let k = 1.5 * eta * delta0.sqrt();
    let t_lin = 2.0 * std::f64::consts::PI * (m / k).sqrt();
    let t_c = contact_time(1.5, eta, 0.5 * m, kick);
    let t = t_lin.min(t_c);
    let h = t / 40.0;
    let mut sim = SimulationBuilder::new(chain)
        .velocity(0, kick)
        .params(bm4(t / 400.0))
        .schedule(1.0, h)
        .build()
        .unwrap();
    let (mut vt, mut ft) = ([Vec::new(), Vec::new()], [Vec::new(), Vec::new()]);
    let r = sim.run(|fr: &Frame| -> Result<(), Stop> {
        let (u, v) = (&fr.state.u, &fr.state.v);
        for (s, &j) in [j1, j2].iter().enumerate() {
            vt[s].push(v[j]);
            ft[s].push(eta * (delta0 + u[j - 1] - u[j]).max(0.0).powf(1.5));
        }
        if argmax_abs(v) >= j2 + 10 {
            return Err(Stop::Done);
        }
        Ok(())
    });
    assert!(matches!(r, Err(Stop::Done)), "{r:?}");
    let (t1, _) = parabolic_peak(&vt[0], 0.0, h);
    let (t2, _) = parabolic_peak(&vt[1], 0.0, h);
    PreWave {
        speed: (j2 - j1) as f64 * a / (t2 - t1),
        fm: [
            parabolic_peak(&ft[0], 0.0, h).1,
            parabolic_peak(&ft[1], 0.0, h).1,
        ],
    }
}

/// The speed of the solitary wave of a precompressed steel chain (8 mm beads, static force
/// 10 N) against Daraio et al.'s formula, kicks of 0.1 to 3 m/s (f_r from about 1.2 to about
/// 40). The formula is evaluated at the force amplitude measured at the far bead (j2 = 120).
/// It describes a steady solitary wave: a kick whose wave still changes its amplitude by 1 %
/// or more between beads 60 and 120 (a weak kick: the wave forms over a length that grows as
/// f_r -> 1, and until it has formed the leading pulse is a dispersing linear one) is reported,
/// not compared. Below 1 % the wave's speed (as F_m^(1/6) at most) is steady to 0.2 %, well
/// inside the tolerance.
#[test]
fn precompressed_solitary_wave_speed_against_daraio() {
    let (a, f0) = (8e-3, 10.0);
    let (mut worst, mut compared): (f64, usize) = (0.0, 0);
    for kick in [0.1, 0.3, 1.0, 3.0] {
        let w = precompressed_wave(a, f0, kick, 60, 120);
        let want = daraio_speed(a, f0, w.fm[1]);
        let err = rel(w.speed, want);
        let change = rel(w.fm[1], w.fm[0]);
        let steady = change < 1e-2;
        // Tolerance 2 %: the formula is the long-wave (continuum) theory, which keeps the
        // chain's discreteness to second order in a / L; without precompression (the
        // narrowest wave, L = 5 diameters, the largest truncation) the discrete wave runs
        // 1.25 % faster than it (`materials.rs`), and precompression widens the wave. The
        // integrator (blanes-moan4 at 1/400 of the shortest time scale) and the peak
        // refinement (1/40) are below 1e-5. A modulus 10 % off moves the formula by 3 %.
        let tol = 2e-2;
        let row = Row::new(
            "precompressed wave: speed",
            format!("8 mm steel, F_0 = {f0} N, kick {kick} m/s"),
            "Daraio et al. PRE 73, 026610 (2006): Nesterenko's V_s(f_r)",
        )
        .expected(format!("{} m/s at f_r = {}", g(want), g(w.fm[1] / f0)))
        .measured(format!(
            "{} m/s ({:+.2}%; F_m {} N at bead 60, {} N at 120)",
            g(w.speed),
            100.0 * (w.speed / want - 1.0),
            g(w.fm[0]),
            g(w.fm[1])
        ));
        if steady {
            worst = worst.max(err);
            compared += 1;
            record_one(
                row.tolerance(format!("{:.0}% relative", tol * 100.0))
                    .pass(err < tol),
            );
        } else {
            record_one(
                row.tolerance(format!(
                    "not compared: F_m changes {:.1}% from bead 60 to 120 (not yet a steady wave)",
                    100.0 * change
                ))
                .info(),
            );
        }
    }
    assert!(compared >= 2, "only {compared} kicks made a steady wave");
    assert!(worst < 2e-2, "speed off Daraio's formula by {worst}");
}

// ------------------------------------------------------------------------------------------
// Super-exponential localisation of the discrete solitary wave
// ------------------------------------------------------------------------------------------

/// The overlaps ahead of the peak of a solitary wave of the unit chain (eta = m = 1, striker
/// of the grains' mass at speed 1) when its peak reaches grain 100, down to `floor`.
fn leading_tail(p: f64, floor: f64) -> Vec<f64> {
    let n = 160;
    let tc = contact_time(p, 1.0, 0.5, 1.0);
    let chain = SolitaryWave::unit(p, n, 1.0).chain().unwrap();
    let mut sim = SimulationBuilder::new(chain)
        .params(bm4(tc / 400.0))
        .schedule(1e4, tc / 400.0)
        .build()
        .unwrap();
    let mut tail = Vec::new();
    let r = sim.run(|fr: &Frame| -> Result<(), Stop> {
        let (u, v) = (&fr.state.u, &fr.state.v);
        let k = argmax_abs(v);
        if k >= 100 {
            // Contact i joins grains i - 1 and i; the first ahead of the peak is k + 1.
            for i in k + 1..u.len() {
                let d = u[i - 1] - u[i];
                if d <= floor {
                    break;
                }
                tail.push(d);
            }
            return Err(Stop::Done);
        }
        Ok(())
    });
    assert!(matches!(r, Err(Stop::Done)), "{r:?}");
    tail
}

/// Ahead of the wave a grain at rest is pushed by the one behind alone: `u''_{k+1} = u_k^p`
/// (eta = m = 1), so the logarithm of the overlap grows by the factor p from one contact to
/// the next: the doubly exponential (super-exponential) decay of Chatterjee (PRE 59, 5912
/// (1999)), English and Pego (Proc. AMS 133, 1763 (2005)) and Ahnert and Pikovsky (PRE 79,
/// 026209 (2009)), whose base p is this recursion's (Chatterjee's asymptotic argument; the
/// papers' own constants could not be read here). With `L_k = ln delta_k`, the ratio of successive differences
/// `(L_{k+2} - L_{k+1}) / (L_{k+1} - L_k)` tends to p. Measured at the deepest pair above
/// 1e-80 (the force floor, 1e-200, closes contacts below 1e-133 at p = 3/2 and 1e-100 at p = 2).
#[test]
fn solitary_wave_tail_is_doubly_exponential() {
    for p in [1.5, 2.0] {
        let tail = leading_tail(p, 1e-80);
        let l: Vec<f64> = tail.iter().map(|d| d.ln()).collect();
        assert!(
            l.len() >= 5,
            "p = {p}: only {} contacts in the tail",
            l.len()
        );
        let d: Vec<f64> = l.windows(2).map(|w| w[1] - w[0]).collect();
        let ratios: Vec<f64> = d.windows(2).map(|w| w[1] / w[0]).collect();
        let last = *ratios.last().unwrap();
        let d_last = d[d.len() - 2];
        // Tolerance: the recursion is asymptotic. Writing delta_k = e^(L_k), u'' = (L'' +
        // L'^2) e^L turns u''_{k+1} = u_k^p into L_{k+1} = p L_k - 2 ln|L'_{k+1}| + ...,
        // and since |L'| grows like |L|, the differences obey D_{k+1} = p D_k - 2 ln p + ...:
        // the ratio is p + 2 ln p / |D_k|, 1-2 % above p at the depths reached. Twice that
        // correction is the tolerance; a law of exponent p +- 0.1 misses it.
        let tol = 2.0 * 2.0 * p.ln() / d_last.abs();
        let ok = (last - p).abs() < tol;
        record_one(
            Row::new(
                "solitary wave tail: doubly exponential",
                format!("p={p}, unit chain, peak at grain 100, overlaps down to 1e-80"),
                "Chatterjee PRE 59, 5912 (1999); English & Pego Proc. AMS 133, 1763 (2005): doubly exponential tail; base p from u''_(k+1) = u_k^p ahead of the wave",
            )
            .expected(format!("{p}"))
            .measured(format!(
                "{last:.4} (excess {:.4}, the recursion's 2 ln p / |D| {:.4}; ratios {}; deepest overlap {:.1e})",
                last - p,
                2.0 * p.ln() / d_last.abs(),
                ratios
                    .iter()
                    .map(|r| format!("{r:.3}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                tail.last().unwrap()
            ))
            .tolerance(format!("{tol:.3} absolute (2 x the recursion's 2 ln p / |D|)"))
            .pass(ok),
        );
        assert!(ok, "p = {p}: ratio {last} (all {ratios:?})");
    }
}

// ------------------------------------------------------------------------------------------
// Two balls dropped on a floor: the independent-collision answer
// ------------------------------------------------------------------------------------------

/// Two balls falling at speed 1 onto a floor (a wall on the right, Hertz with eta = 1): the
/// lower ball (mass 1) touches the floor at t = 0, the upper one (mass `q`) is `gap` behind
/// it. Returns the upper ball's velocity at the end (negative: away from the floor).
fn two_ball_drop(q: f64, gap: f64) -> f64 {
    let law = ContactLaw::hertz(1.0);
    let chain = ChainBuilder::new()
        .grains(1, q, law)
        .grains(1, 1.0, law)
        .right(End::Wall(law))
        .build()
        .unwrap();
    // The shortest contact: the lighter ball against the other at their relative speed 2.
    let tc = contact_time(1.5, 1.0, q / (1.0 + q), 2.0).min(contact_time(1.5, 1.0, 1.0, 1.0));
    let t_end = 20.0 * contact_time(1.5, 1.0, 1.0, 1.0) + 2.0 * gap;
    let mut sim = SimulationBuilder::new(chain)
        .displacement(0, -gap)
        .velocity(0, 1.0)
        .velocity(1, 1.0)
        .params(bm4(tc / 2000.0))
        .schedule(t_end, t_end / 100.0)
        .build()
        .unwrap();
    sim.run(|_: &Frame| Ok::<(), Stop>(())).unwrap();
    let (u, v) = (&sim.state().u, &sim.state().v);
    assert!(
        u[0] - u[1] < 0.0 && u[1] < 0.0,
        "still in contact: u = {u:?}"
    );
    v[0]
}

/// The textbook answer (Mellen 1968; Harter 1971; reviewed by Müller and Pöschel, PRE 83,
/// 041304 (2011), and Bartz, arXiv 2007.15005, whose introduction states the light-ball limit,
/// three times the impact speed): the lower ball rebounds from the floor, then meets the
/// upper one in a separate elastic collision, which sends the upper ball (mass ratio q) off at
/// `(3 - q) / (1 + q)` of the impact speed. With the balls apart by more than the floor
/// collision's travel the collisions are independent, and grainchain must give it to the
/// integrator's precision. Touching balls (gap 0) with Hertz contacts are not independent
/// collisions: Müller and Pöschel's point is that the answer then differs, which is measured
/// and reported (their figures' numbers could not be read, so no value of theirs is compared).
#[test]
fn two_ball_drop_against_the_independent_collision_answer() {
    let t_floor = contact_time(1.5, 1.0, 1.0, 1.0);
    let mut all = true;
    for q in [0.01, 0.1, 0.25] {
        let want = (3.0 - q) / (1.0 + q);
        // Gap: twice the distance the upper ball falls during the floor contact, so the
        // floor collision is over before the balls meet.
        let got = -two_ball_drop(q, 2.0 * t_floor);
        // Tolerance 1e-8: both collisions are elastic and the outgoing velocities of a Hertz
        // collision are exactly the point masses' (physics.md 4); blanes-moan4 at 1/2000 of
        // the shorter contact time leaves below 1e-10. Any inelasticity or a wrong mass moves
        // the answer by its own size (1e-3 for a restitution of 0.999).
        let ok = rel(got, want) < 1e-8;
        all &= ok;
        record_one(
            Row::new(
                "two-ball drop: independent collisions",
                format!("mass ratio q={q}, balls apart (gap 2 t_c v)"),
                "Harter 1971 / Müller & Pöschel PRE 83, 041304 (2011): v' = (3-q)/(1+q) v (3 v as q -> 0, Bartz 2020)",
            )
            .expected(format!("{want:.9}"))
            .measured(format!("{got:.9} ({:.1e} rel.)", rel(got, want)))
            .tolerance("1e-8 relative")
            .pass(ok),
        );
        let touching = -two_ball_drop(q, 0.0);
        record_one(
            Row::new(
                "two-ball drop: touching balls (Hertz)",
                format!("mass ratio q={q}, balls touching, eta = 1 for both contacts"),
                "Müller & Pöschel PRE 83, 041304 (2011): differs from the independent-collision answer",
            )
            .expected(format!("differs from {want:.4}"))
            .measured(format!(
                "{touching:.4} ({:+.1}%)",
                100.0 * (touching / want - 1.0)
            ))
            .info(),
        );
    }
    assert!(all, "the separated drop misses (3 - q)/(1 + q)");
}

// ------------------------------------------------------------------------------------------
// Two counter-propagating solitary waves (Santibanez et al. 2011)
// ------------------------------------------------------------------------------------------

/// What the collision of two equal solitary waves leaves.
struct Crossing {
    /// Largest |v| of a grain between the two primary waves (the secondary waves), over the
    /// incident wave's peak velocity.
    secondary: f64,
    /// Position of the right-going primary wave (its |v|-weighted centroid) at the end.
    primary_at: f64,
}

/// A unit Hertz chain of `n` grains, free ends; grain 1 kicked to `speed` and (if `both`)
/// grain n to `-speed`: each kicked end grain launches a solitary wave (it is a striker of
/// the grains' mass). Run to `t_end` (in the unit-speed chain's time; scaled by the amplitude
/// symmetry, so equal-shape runs at any speed), outputs every 1/40 of the contact time.
fn crossing(n: usize, speed: f64, both: bool, t_end: f64) -> Crossing {
    let law = ContactLaw::hertz(1.0);
    let chain = ChainBuilder::new().grains(n, 1.0, law).build().unwrap();
    let tc = contact_time(1.5, 1.0, 0.5, speed);
    // The amplitude symmetry (physics.md 3): times scale as speed^(-1/5).
    let scale = speed.powf(-0.2);
    let mut b = SimulationBuilder::new(chain).velocity(0, speed);
    if both {
        b = b.velocity(n - 1, -speed);
    }
    let mut sim = b
        .params(bm4(tc / 400.0))
        .schedule(t_end * scale, tc / 40.0)
        .build()
        .unwrap();
    // The incident wave's peak velocity: the largest |v| of grain 40 before the collision.
    let mut v_in: f64 = 0.0;
    sim.run(|fr: &Frame| -> Result<(), Stop> {
        v_in = v_in.max(fr.state.v[40].abs());
        Ok(())
    })
    .unwrap();
    let v = &sim.state().v;
    let mid = n / 2;
    // The right-going primary: the fastest grain of the right half, and its centroid over
    // +-8 grains (the wave's tails there are below 1e-10 of its peak).
    let k = mid + argmax_abs(&v[mid..]);
    let (sw, sx) = (k - 8..=k + 8).fold((0.0, 0.0), |(a, b), i| {
        (a + v[i].abs(), b + i as f64 * v[i].abs())
    });
    let left = argmax_abs(&v[..mid]);
    let secondary = v[left + 9..k - 8]
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    Crossing {
        secondary: secondary / v_in,
        primary_at: sx / sw,
    }
}

/// The time at which the peak of a lone wave (unit chain of `n` grains, grain 1 kicked to 1)
/// reaches grain `target` (the first output at or past it).
fn arrival(n: usize, target: usize) -> f64 {
    let chain = ChainBuilder::new()
        .grains(n, 1.0, ContactLaw::hertz(1.0))
        .build()
        .unwrap();
    let tc = contact_time(1.5, 1.0, 0.5, 1.0);
    let mut sim = SimulationBuilder::new(chain)
        .velocity(0, 1.0)
        .params(bm4(tc / 400.0))
        .schedule(1e5, tc / 40.0)
        .build()
        .unwrap();
    let mut t = 0.0;
    let r = sim.run(|fr: &Frame| -> Result<(), Stop> {
        t = fr.state.t;
        if argmax_abs(&fr.state.v) >= target {
            return Err(Stop::Done);
        }
        Ok(())
    });
    assert!(matches!(r, Err(Stop::Done)), "{r:?}");
    t
}

/// Santibanez et al. (PRE 84, 026604 (2011)), abstract: two equal counter-propagating solitary
/// waves cross; secondary solitary waves emerge from the collision with an amplitude
/// proportional to the incident one, stronger when the collision is at the middle contact of a
/// chain with an even number of beads than at the middle bead of an odd one. Their phase shift
/// is reported: Santibanez et al. see one, Wang et al. (Chin. Phys. B 27, 044501 (2018)) see
/// none, Zhang et al. (arXiv 2310.19356) a leading one (an advance).
#[test]
fn counter_propagating_solitary_waves() {
    // 200 and 201 grains, followed until a lone wave's peak would reach grain 170 (the
    // primaries are then 30 grains from the far ends, the secondaries well behind them).
    let t_end = arrival(200, 170);
    let even = crossing(200, 1.0, true, t_end);
    let even_small = crossing(200, 0.01, true, t_end);
    let odd = crossing(201, 1.0, true, t_end);
    let single = crossing(200, 1.0, false, t_end);
    // Proportionality: the amplitude symmetry of the Hertz chain (physics.md 3) makes the
    // ratio exactly the same at every amplitude for the discrete chain; the runs at speed 1
    // and 0.01 take the same steps in scaled time, so the ratios agree to round-off. 1e-6 is
    // far above that; a law that is not a pure power (a precompression, a damping) breaks it
    // by far more.
    let prop = rel(even_small.secondary, even.secondary);
    let ok_prop = prop < 1e-6;
    record_one(
        Row::new(
            "colliding waves: secondary amplitude proportional",
            "unit Hertz chain, 200 grains, speeds 1 and 0.01",
            "Santibanez et al. PRE 84, 026604 (2011), abstract: secondary amplitude proportional to the incident",
        )
        .expected(format!("equal ratios ({})", g(even.secondary)))
        .measured(format!(
            "{} and {} ({:.1e} rel.)",
            g(even.secondary),
            g(even_small.secondary),
            prop
        ))
        .tolerance("1e-6 relative")
        .pass(ok_prop),
    );
    // Even against odd: a claim of order, no tolerance beyond the measurement's (the largest
    // |v| between the primaries, a few per cent phase-dependent, far below a factor 1.1).
    let ok_order = even.secondary > 1.1 * odd.secondary;
    record_one(
        Row::new(
            "colliding waves: middle contact against middle bead",
            "unit Hertz chain, 200 (even) and 201 (odd) grains, speed 1",
            "Santibanez et al. PRE 84, 026604 (2011), abstract: stronger secondaries at the middle contact (even chain)",
        )
        .expected("even > odd")
        .measured(format!(
            "even {} of the incident, odd {}",
            g(even.secondary),
            g(odd.secondary)
        ))
        .tolerance("even > 1.1 x odd")
        .pass(ok_order),
    );
    let shift = even.primary_at - single.primary_at;
    record_one(
        Row::new(
            "colliding waves: phase shift",
            format!("unit Hertz chain, 200 grains, speed 1, at t = {}", g(t_end)),
            "Santibanez et al. 2011: a shift; Wang et al. CPB 27, 044501 (2018): none; Zhang et al. arXiv 2310.19356: leading",
        )
        .expected("disputed (see source)")
        .measured(format!(
            "{shift:+.4} grains (positive: ahead of the lone wave)"
        ))
        .info(),
    );
    assert!(
        ok_prop,
        "secondary ratio {} vs {}",
        even.secondary, even_small.secondary
    );
    assert!(ok_order, "even {} odd {}", even.secondary, odd.secondary);
}

// ------------------------------------------------------------------------------------------
// A heavy striker: a train of solitary waves (Job et al. 2007)
// ------------------------------------------------------------------------------------------

/// Job, Melo, Sokolow and Sen (Granular Matter 10, 13 (2007); arXiv 0712.0006), abstract: the
/// impact of a large striker generates a train of solitary waves ordered by decreasing
/// amplitudes, and the compression force at the struck end unloads nearly exponentially with
/// a characteristic time set by the masses. Unit Hertz chain, striker of mass 10 at speed 1:
/// the velocity peaks of grain 150 as the train passes must decrease one after the other (the
/// first five), and the force of the striker's contact is fitted by an exponential over its
/// unloading from 1/2 to 1/100 of its peak (the fit's time constant and its worst deviation
/// are reported: the abstract gives no number).
#[test]
fn heavy_striker_train_is_ordered() {
    let (mass, n, j) = (10.0, 400, 150);
    let (mut sim, h) = heavy_striker(mass, n);
    let (mut vj, mut force) = (Vec::new(), Vec::new());
    let r = sim.run(|fr: &Frame| -> Result<(), Stop> {
        let (u, v) = (&fr.state.u, &fr.state.v);
        vj.push(v[j]);
        // Internal 0 is the striker: its contact with grain 1 is u[0] - u[1].
        force.push((u[0] - u[1]).max(0.0).powf(1.5));
        if argmax_abs(v) >= n - 30 {
            return Err(Stop::Done);
        }
        Ok(())
    });
    assert!(matches!(r, Err(Stop::Done)), "{r:?}");
    // Local maxima of v_j(t), each refined by its parabola.
    let peaks: Vec<f64> = (1..vj.len() - 1)
        .filter(|&i| vj[i] > vj[i - 1] && vj[i] >= vj[i + 1] && vj[i] > 1e-3)
        .map(|i| parabolic_peak(&vj[i - 1..=i + 1], 0.0, h).1)
        .collect();
    assert!(peaks.len() >= 5, "{} peaks at grain {j}", peaks.len());
    let first: Vec<f64> = peaks[..5].to_vec();
    let ordered = first.windows(2).all(|w| w[1] < w[0]);
    record_one(
        Row::new(
            "heavy striker: train ordered by amplitude",
            format!("unit Hertz chain, striker mass {mass} at speed 1, grain {j}"),
            "Job, Melo, Sokolow & Sen, Granular Matter 10, 13 (2007), abstract: waves ordered by decreasing amplitudes",
        )
        .expected("each of the first 5 below the one before")
        .measured(
            first
                .iter()
                .map(|p| g(*p))
                .collect::<Vec<_>>()
                .join(" > "),
        )
        .tolerance("strict order")
        .pass(ordered),
    );
    // The unloading, at this striker and at two heavier ones (their own runs, to the end of
    // the unloading only): the time constant against the striker's mass is reported.
    let mut rows = vec![(mass, unloading(&force, h))];
    for heavier in [20.0, 40.0] {
        let (f, hh) = striker_force(heavier);
        rows.push((heavier, unloading(&f, hh)));
    }
    for (mass, (tau, dev)) in rows {
        record_one(
            Row::new(
                "heavy striker: exponential unloading",
                format!("unit Hertz chain, striker mass {mass} at speed 1, striker's contact"),
                "Job et al., Granular Matter 10, 13 (2007), abstract: nearly exponential unloading, time set by the masses",
            )
            .expected("nearly exponential (no number given)")
            .measured(format!(
                "time constant {} (unit time; {} per unit of striker mass), worst |ln F - fit| {:.3} over F/F_peak 0.5..0.01",
                g(tau),
                g(tau / mass),
                dev
            ))
            .info(),
        );
    }
    assert!(ordered, "peaks {first:?}");
}

/// The force of the contact between a striker of `mass` (speed 1) and a unit Hertz chain,
/// sampled every 1/40 of a contact time, until it has fallen below 1/100 of its peak.
/// A striker of `mass` at speed 1 into `n` unit Hertz grains (eta = 1), Blanes-Moan at a
/// 400th of the contact time, outputs every 40th of it (ended by the caller's callback): the
/// simulation and the output interval.
fn heavy_striker(mass: f64, n: usize) -> (grainchain_engine::Simulation, f64) {
    let chain = ChainBuilder::new()
        .grains(n, 1.0, ContactLaw::hertz(1.0))
        .striker(Striker {
            end: StrikerEnd::Left,
            mass,
            speed: 1.0,
            law: None,
        })
        .build()
        .unwrap();
    let tc = contact_time(1.5, 1.0, 0.5, 2.0);
    let h = tc / 40.0;
    let sim = SimulationBuilder::new(chain)
        .params(bm4(tc / 400.0))
        .schedule(1e5, h)
        .build()
        .unwrap();
    (sim, h)
}

fn striker_force(mass: f64) -> (Vec<f64>, f64) {
    let n = 600;
    let (mut sim, h) = heavy_striker(mass, n);
    let (mut force, mut peak) = (Vec::new(), 0.0f64);
    let r = sim.run(|fr: &Frame| -> Result<(), Stop> {
        let u = &fr.state.u;
        let f = (u[0] - u[1]).max(0.0).powf(1.5);
        force.push(f);
        peak = peak.max(f);
        if f < 0.01 * peak || argmax_abs(&fr.state.v) >= n - 30 {
            return Err(Stop::Done);
        }
        Ok(())
    });
    assert!(matches!(r, Err(Stop::Done)), "{r:?}");
    assert!(
        *force.last().unwrap() < 0.01 * peak,
        "mass {mass}: unloading not over"
    );
    (force, h)
}

/// An exponential fitted to a force's unloading, from its peak on while it is between 1/2 and
/// 1/100 of the peak (samples `h` apart): the time constant and the largest deviation of
/// `ln F` from the fit.
fn unloading(force: &[f64], h: f64) -> (f64, f64) {
    let (kp, fp) = force
        .iter()
        .enumerate()
        .fold((0, 0.0), |b, (i, &f)| if f > b.1 { (i, f) } else { b });
    let (mut ts, mut ls) = (Vec::new(), Vec::new());
    for (i, &f) in force.iter().enumerate().skip(kp) {
        if f < 0.01 * fp {
            break;
        }
        if f <= 0.5 * fp {
            ts.push(i as f64 * h);
            ls.push(f.ln());
        }
    }
    let (slope, icpt, _) = fit_line(&ts, &ls);
    let dev = ts
        .iter()
        .zip(&ls)
        .map(|(t, l)| (l - (icpt + slope * t)).abs())
        .fold(0.0f64, f64::max);
    (-1.0 / slope, dev)
}

// ------------------------------------------------------------------------------------------
// Newton's cradle with soft contacts (three balls)
// ------------------------------------------------------------------------------------------

/// A ball striking two touching balls at rest (equal masses, compression-only contacts of
/// exponent `p`, eta = 1, speed 1): the three velocities once every contact is open and the
/// balls separate (the run is long enough: 40 contact times).
fn cradle(p: f64) -> [f64; 3] {
    let chain = ChainBuilder::new()
        .grains(3, 1.0, ContactLaw::new(p, 1.0))
        .build()
        .unwrap();
    let tc = contact_time(p, 1.0, 0.5, 1.0);
    let t_end = 40.0 * tc;
    let mut sim = SimulationBuilder::new(chain)
        .velocity(0, 1.0)
        .params(bm4(tc / 2000.0))
        .schedule(t_end, t_end / 40.0)
        .build()
        .unwrap();
    sim.run(|_: &Frame| Ok::<(), Stop>(())).unwrap();
    let (u, v) = (&sim.state().u, &sim.state().v);
    assert!(u[0] < u[1] && u[1] < u[2], "still in contact: {u:?}");
    assert!(
        v[0] <= v[1] && v[1] <= v[2],
        "balls still approaching: {v:?}"
    );
    [v[0], v[1], v[2]]
}

/// Newton's cradle (Hutzler, Delaney, Weaire and MacLeod, "Rocking Newton's cradle", Am. J.
/// Phys. 72, 1508 (2004), doi 10.1119/1.1783898; its abstract, after Herrmann and Schmälzle
/// and Hinch and Saint-Jean): the textbook's independent collisions send the row's last ball
/// off at the striker's speed and leave the others at rest, (0, 0, 1); the finite elastic
/// response of the balls instead breaks the line up at the first collision, every ball moving.
/// Asserted: the three balls leave with distinct velocities, each at least 1e-3 from the next
/// (the independent-collision answer has two equal at 0; the run resolves velocities to
/// 1e-9), and momentum and energy are the striker's. Momentum to round-off, 1e-12: every
/// method here conserves it exactly. Energy to 1e-6: a compression-only law is not smooth
/// where a contact opens or closes (at p = 1 the force's derivative jumps), which costs
/// blanes-moan4 its order there, a local error of order (dt / t_c)^2 = 2.5e-7 at dt = t_c /
/// 2000 per opening or closing (2.9e-9 is measured at p = 1). The velocities themselves are
/// reported: no number of theirs for these laws could be read.
#[test]
fn newtons_cradle_with_soft_contacts() {
    for p in [1.5, 1.0] {
        let v = cradle(p);
        let momentum = v.iter().sum::<f64>();
        let energy = v.iter().map(|x| 0.5 * x * x).sum::<f64>();
        let conserved = (momentum - 1.0).abs() < 1e-12 && (energy - 0.5).abs() < 1e-6;
        let broken_up = v[1] - v[0] > 1e-3 && v[2] - v[1] > 1e-3;
        record_one(
            Row::new(
                "Newton's cradle: the line breaks up",
                format!("p={p}, three balls, eta = 1, equal masses, striker speed 1"),
                "Hutzler et al. Am. J. Phys. 72, 1508 (2004), abstract: the first collision breaks up the line (textbook: (0, 0, 1))",
            )
            .expected("three distinct velocities")
            .measured(format!(
                "({:.4}, {:.4}, {:.4}); momentum {:.1e} and energy {:.1e} off",
                v[0],
                v[1],
                v[2],
                momentum - 1.0,
                energy - 0.5
            ))
            .tolerance("each 1e-3 from the next")
            .pass(broken_up && conserved),
        );
        assert!(conserved, "p = {p}: momentum {momentum}, energy {energy}");
        assert!(broken_up, "p = {p}: {v:?}");
    }
}
