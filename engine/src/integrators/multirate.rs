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
//! As computed: the fast steps do not read the slow grains, so a slow grain's drift is done
//! after them, in one fused sweep with the slow forces and the kick (`Slow`, velocity
//! Verlet's sweep, `Chain::sweep_range`): step 3's kick and the next step's step-1 kick are one
//! kick of `H` (a half kick on the last step of an advance, whose opening kick is `open`). Each
//! of the fast region's six stages is one fused sweep too (`Chain::drift_forces_kick_free`).
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

use super::blanes_moan::SRKN6B;
use super::splitting::{open, stages, Flows};
use super::verlet::KDK;
use super::{FixedStep, Stats};
use crate::chain::{Chain, Island, Window};
use crate::state::State;
use serde::Serialize;

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
/// `ratio * dt` on the rest, forces split by contact ([`super::Method::Multirate`]).
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
    /// Reflections at a stretch's edges, counted after every fast step (the stretch, its
    /// zones and the grains just outside lie in the fast region: `Simulation` checks it).
    reflections: super::ReflectionWatch,
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
            reflections: super::ReflectionWatch::default(),
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
        for x in &mut self.a[f0..f1] {
            *x = 0.0;
        }
        // The same arithmetic as the fused slow sweep's (`Slow::stage`).
        let im = &chain.inv_mass;
        if f1 == f0 + 1 {
            self.a[f0] = (self.f[f0] - self.f[f1]) * im[f0];
        } else {
            self.a[f0] = (self.f[f0] - 0.0) * im[f0];
            self.a[f1 - 1] = (0.0 - self.f[f1]) * im[f1 - 1];
        }
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

    /// The fast region's `ratio` Blanes-Moan steps under the fast forces alone ([`Fast`]).
    /// As in the single-rate method, the last kick of a step is fused with the first of the
    /// next, the advance's first opening kick being in `open`; the last step of an advance
    /// closes and keeps the accelerations for the next advance's opening kick.
    fn fast_steps(&mut self, chain: &Chain, state: &mut State, last: bool, stats: &mut Stats) {
        let (f0, f1) = (self.f0, self.f1);
        let dt = self.dt;
        let w = (f1 - f0) as u64;
        for r in 0..self.ratio {
            let closing = last && r + 1 == self.ratio;
            let mut fast = Fast {
                chain,
                state: &mut *state,
                af: &mut self.af,
                f0,
                f1,
            };
            stages(&SRKN6B, &mut fast, dt, closing);
            self.reflections.update(chain, state);
            if f1 >= f0 + 2 {
                stats.force_evals += 6;
                stats.grain_evals += 6 * w;
                stats.window_evals += 6 * w;
            }
            stats.steps += 1;
        }
    }
}

/// The fast region under the fast forces alone: each stage one fused sweep over it (drift, its
/// inner contacts' forces, kick: `Chain::drift_forces_kick_free`).
struct Fast<'a> {
    chain: &'a Chain,
    state: &'a mut State,
    af: &'a mut [f64],
    f0: usize,
    f1: usize,
}

impl Flows for Fast<'_> {
    fn kick(&mut self, c: f64, h: f64) {
        let c = c * h;
        let (f0, f1) = (self.f0, self.f1);
        for (v, a) in self.state.v[f0..f1].iter_mut().zip(&self.af[f0..f1]) {
            *v += c * a;
        }
    }

    #[inline(always)]
    fn stage(&mut self, _stage: usize, d: f64, k: f64, h: f64, closing: bool) {
        self.chain.drift_forces_kick_free(
            &mut self.state.u,
            &mut self.state.v,
            self.af,
            d * h,
            k * h,
            closing,
            self.f0,
            self.f1,
        );
    }
}

/// The slow part of a step after the fast steps, as velocity Verlet's step ([`KDK`]): its one
/// stage drifts every slow grain by `H`, takes the slow forces (the contacts with a slow grain,
/// so the fast region's two end contacts too, at its new positions) and kicks: the closing half
/// kick of this step fused with the opening one of the next (`H`), or a half kick on the last
/// step of an advance (which keeps every slow acceleration for the next opening kick). The fast
/// region's two end grains get their slow kick from its end contacts.
struct Slow<'a> {
    a: &'a mut [f64],
    f0: usize,
    f1: usize,
    chain: &'a Chain,
    state: &'a mut State,
    win: &'a mut Window,
    stats: &'a mut Stats,
}

impl Flows for Slow<'_> {
    fn kick(&mut self, c: f64, h: f64) {
        super::kick(&mut self.state.v, self.a, c * h, self.win);
    }

    fn stage(&mut self, _stage: usize, d: f64, k: f64, h: f64, last: bool) {
        let (h, ck) = (d * h, k * h);
        let (f0, f1, chain) = (self.f0, self.f1, self.chain);
        let (u, v, a) = (&mut self.state.u, &mut self.state.v, &mut *self.a);
        let (g0, g1) = chain.eval_range(self.win, self.win.islands()[0]);
        if f0 < f1 {
            if g0 < f0 {
                chain.sweep_range(u, v, a, h, ck, last, g0, f0);
            }
            if f1 < g1 {
                chain.sweep_range(u, v, a, h, ck, last, f1, g1);
            }
            let im = &chain.inv_mass;
            let (fl, fr) = (chain.contact_force_at(u, f0), chain.contact_force_at(u, f1));
            if f1 == f0 + 1 {
                a[f0] = (fl - fr) * im[f0];
            } else {
                a[f0] = (fl - 0.0) * im[f0];
                a[f1 - 1] = (0.0 - fr) * im[f1 - 1];
                v[f1 - 1] += ck * a[f1 - 1];
            }
            v[f0] += ck * a[f0];
        } else {
            chain.sweep_range(u, v, a, h, ck, last, g0, g1);
        }
        let grew = chain.grow(self.win, 0, v, a, g0, g1, true);
        self.win.after_growth(grew);
        super::count_eval(self.win, self.stats);
    }
}

impl Multirate {
    /// The slow carrier of one call ([`Slow`]).
    fn slow_flows<'a>(
        &'a mut self,
        chain: &'a Chain,
        state: &'a mut State,
        win: &'a mut Window,
        stats: &'a mut Stats,
    ) -> Slow<'a> {
        Slow {
            a: &mut self.a,
            f0: self.f0,
            f1: self.f1,
            chain,
            state,
            win,
            stats,
        }
    }
}

impl FixedStep for Multirate {
    fn dt(&self) -> f64 {
        self.dt
    }

    /// The slow step `H = ratio * dt`.
    fn outer_step(&self) -> f64 {
        self.ratio as f64 * self.dt
    }

    /// The opening half kick of an advance with the slow accelerations (zero inside the fast
    /// region but at its two ends), and the fast region's opening kick.
    fn open(&mut self, chain: &Chain, state: &mut State, win: &mut Window) {
        let h = self.outer_step();
        let mut stats = Stats::default();
        open(&KDK, &mut self.slow_flows(chain, state, win, &mut stats), h);
        // And the fast region's first Blanes-Moan kick.
        let (f0, f1) = (self.f0, self.f1);
        let mut fast = Fast {
            chain,
            state,
            af: &mut self.af,
            f0,
            f1,
        };
        open(&SRKN6B, &mut fast, self.dt);
    }

    fn reflections(&mut self) -> Option<&mut super::ReflectionWatch> {
        Some(&mut self.reflections)
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

    /// One slow step `H` (and `ratio` fast steps, each counted as a step). The slow grains
    /// were kicked by `H / 2` (the advance's opening kick or the previous step's fused kick),
    /// so their drift comes after the fast steps, which do not read them.
    #[inline(always)]
    fn step(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        last: bool,
        stats: &mut Stats,
    ) {
        self.fast_steps(chain, state, last, stats);
        let h = self.outer_step();
        stages(
            &KDK,
            &mut self.slow_flows(chain, state, win, stats),
            h,
            last,
        );
    }
}
