//! Gear's fifth-order predictor-corrector for `u'' = a(u)` (six Nordsieck values), the classic
//! of granular molecular dynamics (Allen & Tildesley, Computer Simulation of Liquids, app. E).
//!
//! Scaled derivatives `r_k = dt^k / k! * d^k u / dt^k`, k = 0..5. Predict with the Pascal
//! triangle, evaluate the acceleration at the predicted positions, correct every `r_k` by
//! `c_k * (dt^2/2 a - r_2)` with the coefficients for second-order equations whose force does not
//! depend on velocity. One force evaluation per step. Not symplectic: energy drifts.

use super::fixed::step_loop;
use super::simd::dispatch_simd;
use super::{eval, FixedStep, Integrator, Stats, StepError};
use crate::chain::{Chain, Window};
use crate::state::State;

/// Scaled higher derivatives below this are set to zero (see the corrector).
const FLUSH: f64 = 1e-250;

const C: [f64; 6] = [
    3.0 / 16.0,
    251.0 / 360.0,
    1.0,
    11.0 / 18.0,
    1.0 / 6.0,
    1.0 / 60.0,
];

/// Gear's fifth-order Nordsieck predictor-corrector for `u'' = a(u)`, one force evaluation per
/// step, started from a Blanes-Moan probe ([`super::Method::Gear5`]).
pub struct Gear5 {
    dt: f64,
    /// r1..r5 (r0 is `state.u`).
    r: [Vec<f64>; 5],
    a: Vec<f64>,
    f: Vec<f64>,
}

impl Gear5 {
    /// For a chain of `n` grains (a striker included) with fixed step `dt` (in the scene's time
    /// units).
    pub fn new(dt: f64, n: usize) -> Self {
        Gear5 {
            dt,
            r: std::array::from_fn(|_| vec![0.0; n]),
            a: vec![0.0; n],
            f: vec![0.0; n + 1],
        }
    }

    /// Predict, evaluate, correct.
    #[inline(always)]
    fn predict_correct(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        stats: &mut Stats,
    ) {
        let rg = win.range();
        {
            let u = &mut state.u[rg.clone()];
            let [r1, r2, r3, r4, r5] = &mut self.r;
            let (r1, r2, r3, r4, r5) = (
                &mut r1[rg.clone()],
                &mut r2[rg.clone()],
                &mut r3[rg.clone()],
                &mut r4[rg.clone()],
                &r5[rg.clone()],
            );
            for i in 0..u.len() {
                u[i] += r1[i] + r2[i] + r3[i] + r4[i] + r5[i];
                r1[i] += 2.0 * r2[i] + 3.0 * r3[i] + 4.0 * r4[i] + 5.0 * r5[i];
                r2[i] += 3.0 * r3[i] + 6.0 * r4[i] + 10.0 * r5[i];
                r3[i] += 4.0 * r4[i] + 10.0 * r5[i];
                r4[i] += 5.0 * r5[i];
            }
        }
        eval(chain, &state.u, &mut self.f, &mut self.a, win, stats);
        let rg = win.range();
        let h2 = 0.5 * self.dt * self.dt;
        let u = &mut state.u[rg.clone()];
        let a = &self.a[rg.clone()];
        let [r1, r2, r3, r4, r5] = &mut self.r;
        let (r1, r2, r3, r4, r5) = (
            &mut r1[rg.clone()],
            &mut r2[rg.clone()],
            &mut r3[rg.clone()],
            &mut r4[rg.clone()],
            &mut r5[rg],
        );
        for i in 0..u.len() {
            let corr = h2 * a[i] - r2[i];
            u[i] += C[0] * corr;
            r1[i] += C[1] * corr;
            r2[i] += corr;
            // Where the force has vanished (a grain in free flight) the corrector damps r3..r5
            // geometrically, into subnormal numbers within a few thousand steps, and subnormal
            // arithmetic made Gear5 many times slower on long runs (BENCHMARKS.md, "Throughput").
            // Values below FLUSH are 1e-50 below any displacement a scene can
            // hold, so they are set to zero (a select, the same in every path).
            let flush = |x: f64| if x.abs() < FLUSH { 0.0 } else { x };
            r3[i] = flush(r3[i] + C[3] * corr);
            r4[i] = flush(r4[i] + C[4] * corr);
            r5[i] = flush(r5[i] + C[5] * corr);
        }
    }

    fn sync_velocity(&self, state: &mut State, win: &Window) {
        let inv = 1.0 / self.dt;
        for i in win.range() {
            state.v[i] = self.r[0][i] * inv;
        }
    }
}

impl Gear5 {
    /// The shared loop ([`step_loop`]), compiled here so that [`dispatch_simd`] can build it
    /// for AVX2 too.
    #[inline(always)]
    fn steps_impl(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        n: u64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        step_loop(self, chain, state, win, n, stats)
    }
}

dispatch_simd!(Gear5, steps_dispatched, steps_impl, (chain: &Chain, state: &mut State, win: &mut Window, n: u64, stats: &mut Stats) -> Result<(), StepError>);

impl FixedStep for Gear5 {
    fn dt(&self) -> f64 {
        self.dt
    }

    /// Start-up. Starting with zero higher derivatives (the common shortcut) leaves an O(dt^3)
    /// error in r3 that acts as an O(dt^2) velocity error and makes the method second order
    /// globally. Instead the accelerations at t0 + j dt, j = 0..3, are taken from a probe run of
    /// [`BlanesMoan4`](super::BlanesMoan4) at dt/8 (position error O(dt^4)), and a', a'', a''' at
    /// t0 come from the cubic through them (Newton forward differences), accurate to O(dt^3),
    /// O(dt^2), O(dt): enough for r3, r4, r5 to be right to O(dt^6).
    fn prepare(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        for r in &mut self.r {
            r.iter_mut().for_each(|x| *x = 0.0);
        }
        let n = state.len();
        let mut acc: [Vec<f64>; 4] = std::array::from_fn(|_| vec![0.0; n]);
        eval(chain, &state.u, &mut self.f, &mut acc[0], win, stats);
        let mut probe_state = state.clone();
        let mut probe = super::BlanesMoan4::new(self.dt / 8.0, n);
        probe.init(chain, &probe_state, win, stats);
        for a in acc.iter_mut().skip(1) {
            let t_next = probe_state.t + self.dt;
            // A finite blow-up here shows up again in the first real steps; ignore it.
            let _ = probe.advance_to(chain, &mut probe_state, win, t_next, stats);
            eval(chain, &probe_state.u, &mut self.f, a, win, stats);
        }
        let h2 = 0.5 * self.dt * self.dt;
        #[allow(clippy::needless_range_loop)] // nine arrays indexed alike: an index reads best
        for i in 0..n {
            let (a0, a1, a2, a3) = (acc[0][i], acc[1][i], acc[2][i], acc[3][i]);
            let d1 = a1 - a0;
            let d2 = a2 - 2.0 * a1 + a0;
            let d3 = a3 - 3.0 * a2 + 3.0 * a1 - a0;
            let dt2 = self.dt * self.dt;
            self.r[0][i] = self.dt * state.v[i];
            self.r[1][i] = h2 * a0;
            self.r[2][i] = dt2 / 6.0 * (d1 - 0.5 * d2 + d3 / 3.0);
            self.r[3][i] = dt2 / 24.0 * (d2 - d3);
            self.r[4][i] = dt2 / 120.0 * d3;
        }
        self.a.copy_from_slice(&acc[0]);
    }

    #[inline(always)]
    fn step(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        _last: bool,
        stats: &mut Stats,
    ) {
        self.predict_correct(chain, state, win, stats);
        stats.steps += 1;
    }

    /// Velocities from the Nordsieck vector (`v = r1 / dt`).
    #[inline(always)]
    fn synchronize(&mut self, state: &mut State, win: &Window) {
        self.sync_velocity(state, win);
    }

    /// The loop compiled for the baseline instruction set and for AVX2.
    fn steps(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        n: u64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        self.steps_dispatched(chain, state, win, n, stats)
    }
}
