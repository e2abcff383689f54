//! Multiple time stepping (r-RESPA, Tuckerman, Berne & Martyna, J. Chem. Phys. 97, 1990 (1992)):
//! a fast region of the chain (a container and a few grains of its outer chains) is integrated
//! with Blanes-Moan 4 at the step `dt`, the rest of the window (the long outer chains of heavy
//! grains that carry the leaked waves away) with velocity Verlet at `H = ratio * dt`.
//!
//! The forces are split by contact: a contact between two grains of the fast region is *fast*,
//! every other contact is *slow* (among them the two contacts that join the fast region to the
//! rest). One step of length `H` is
//!
//! 1. kick every grain with the slow forces for `H / 2`;
//! 2. the fast region: `ratio` Blanes-Moan steps of `dt` under the fast forces alone; every other
//!    grain feels no fast force, so it drifts freely for `H`;
//! 3. slow forces at the new positions (the window grows at its margins as usual); kick for
//!    `H / 2`.
//!
//! Each stage is the exact flow or a symplectic map of a part of the Hamiltonian, and the
//! composition is symmetric, so the method is symplectic and time-reversible; it is second order
//! in `H` for the slow part and fourth order in `dt` for the fast part. Its error enters where the
//! slow and fast parts meet, so the fast region should reach a few grains into the outer chains
//! (scene key `integrator.multirate.margin`). Nothing here is exact against the single-rate run:
//! the validation suite and BENCHMARKS.md measure what it changes (an ensemble statistic, since
//! the container dynamics are chaotic) and what it saves.
//!
//! The window is one interval (no islands, no sleep rule, no damping) and always holds the fast
//! region.

use super::{FixedStep, Method, Stats};
use crate::chain::{Chain, Island, Window};
use crate::state::State;
use serde::Serialize;

// The fast region's Blanes-Moan 4 coefficients, shared with the single-rate method.
use super::blanes_moan::{DRIFTS, KICKS};

/// Settings of the multirate method: internal grain indices of the fast region (inclusive) and
/// the ratio of the slow step to the fast one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct MultirateParams {
    /// Slow step over fast step: the outer chains step at `ratio * dt`.
    pub ratio: u64,
    /// First grain of the fast region (internal index).
    pub first: usize,
    /// Last grain of the fast region (internal index, inclusive).
    pub last: usize,
}

/// r-RESPA multiple time stepping: Blanes-Moan 4 at `dt` on the fast region, velocity Verlet at
/// `ratio * dt` on the rest, forces split by contact ([`Method::Multirate`]).
pub struct Multirate {
    dt: f64,
    ratio: u64,
    /// Fast region `[f0, f1)`.
    f0: usize,
    f1: usize,
    /// Slow accelerations over the window (zero inside the fast region but at its two ends).
    a: Vec<f64>,
    f: Vec<f64>,
    /// Fast accelerations over the fast region, and the fast contact forces (`g[f0]` and `g[f1]`
    /// stay 0: the fast region's end contacts are slow).
    af: Vec<f64>,
    g: Vec<f64>,
}

impl Multirate {
    /// `p`: the fast region and ratio; without it (a chain built in code without settings) the
    /// whole chain is fast, which is Blanes-Moan 4 with extra bookkeeping.
    pub fn new(dt: f64, p: Option<MultirateParams>, n: usize) -> Self {
        let p = p.unwrap_or(MultirateParams {
            ratio: 1,
            first: 0,
            last: n.saturating_sub(1),
        });
        let f1 = (p.last + 1).min(n);
        Multirate {
            dt,
            ratio: p.ratio.max(1),
            f0: p.first.min(f1),
            f1,
            a: vec![0.0; n],
            f: vec![0.0; n + 1],
            af: vec![0.0; n],
            g: vec![0.0; n + 1],
        }
    }

    /// Slow accelerations: every contact of the window (growing it at its margins), then the
    /// fast contacts taken out again inside the fast region.
    fn slow(&mut self, chain: &Chain, u: &[f64], win: &mut Window, stats: &mut Stats) {
        chain.accelerations(u, &mut self.f, &mut self.a, win);
        super::count_eval(win, stats);
        let (f0, f1) = (self.f0, self.f1);
        if f0 >= f1 {
            return;
        }
        let m = chain.mass();
        for x in &mut self.a[f0..f1] {
            *x = 0.0;
        }
        self.a[f0] = self.f[f0] / m[f0];
        self.a[f1 - 1] += -self.f[f1] / m[f1 - 1];
    }

    /// Fast accelerations over the fast region (its internal contacts only).
    fn fast(&mut self, chain: &Chain, u: &[f64], stats: &mut Stats) {
        let (f0, f1) = (self.f0, self.f1);
        if f1 < f0 + 2 {
            return;
        }
        // g[f0] and g[f1] are never written: they stay 0, the fast region's ends are free.
        chain.contact_forces(u, &mut self.g, f0 + 1, f1 - 1);
        let (ga, gb) = (&self.g[f0..f1], &self.g[f0 + 1..f1 + 1]);
        for (((a, l), r), im) in self.af[f0..f1]
            .iter_mut()
            .zip(ga)
            .zip(gb)
            .zip(&chain.inv_mass[f0..f1])
        {
            *a = (l - r) * im;
        }
        stats.force_evals += 1;
        stats.grain_evals += (f1 - f0) as u64;
        stats.window_evals += (f1 - f0) as u64;
    }

    fn big_step(&mut self, chain: &Chain, state: &mut State, win: &mut Window, stats: &mut Stats) {
        let h = self.outer_step();
        let (f0, f1) = (self.f0, self.f1);
        super::kick(&mut state.v, &self.a, 0.5 * h, win);
        // Free drift of every slow grain (the islands' grains outside the fast region).
        for isl in win.islands() {
            for r in [isl.lo..isl.hi.min(f0), isl.lo.max(f1)..isl.hi] {
                if r.start < r.end {
                    let (u, v) = (&mut state.u[r.clone()], &state.v[r]);
                    for (u, v) in u.iter_mut().zip(v) {
                        *u += h * v;
                    }
                }
            }
        }
        let dt = self.dt;
        let axpy = |y: &mut [f64], x: &[f64], c: f64| {
            for (y, x) in y.iter_mut().zip(x) {
                *y += c * x;
            }
        };
        // Each stage is one fused sweep over the fast region (drift, its inner contacts' forces,
        // kick), the arithmetic per grain of drift all, fast forces, kick all; the last stage
        // keeps the accelerations for the next step's opening kick.
        let w = (f1 - f0) as u64;
        for _ in 0..self.ratio {
            axpy(&mut state.v[f0..f1], &self.af[f0..f1], KICKS[0] * dt);
            for s in 0..6 {
                chain.drift_forces_kick_free(
                    &mut state.u,
                    &mut state.v,
                    &mut self.af,
                    DRIFTS[s] * dt,
                    KICKS[s + 1] * dt,
                    s == 5,
                    f0,
                    f1,
                );
            }
            if f1 >= f0 + 2 {
                stats.force_evals += 6;
                stats.grain_evals += 6 * w;
                stats.window_evals += 6 * w;
            }
            stats.steps += 1;
        }
        self.slow(chain, &state.u, win, stats);
        super::kick(&mut state.v, &self.a, 0.5 * h, win);
    }
}

impl FixedStep for Multirate {
    const METHOD: Method = Method::Multirate;

    fn dt(&self) -> f64 {
        self.dt
    }

    /// The slow step `H = ratio * dt`.
    fn outer_step(&self) -> f64 {
        self.ratio as f64 * self.dt
    }

    fn prepare(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        // The fast region is always integrated: one interval from the first moving grain to the
        // last, stretched over the fast region.
        if win.skip && self.f0 < self.f1 {
            let isl = match (win.islands().first(), win.islands().last()) {
                (Some(a), Some(b)) => Island {
                    lo: a.lo.min(self.f0),
                    hi: b.hi.max(self.f1),
                },
                _ => Island {
                    lo: self.f0,
                    hi: self.f1,
                },
            };
            win.reset_to(isl);
        }
        self.a.iter_mut().for_each(|x| *x = 0.0);
        self.af.iter_mut().for_each(|x| *x = 0.0);
        self.slow(chain, &state.u, win, stats);
        self.fast(chain, &state.u, stats);
    }

    /// One slow step `H` (and `ratio` fast steps, each counted as a step).
    #[inline(always)]
    fn step(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        _last: bool,
        stats: &mut Stats,
    ) {
        self.big_step(chain, state, win, stats);
    }
}
