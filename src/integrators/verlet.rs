//! Velocity Verlet: second order, symplectic, time-reversible.
//!
//! Written as kick-drift-kick with the closing half kick of one step fused with the opening half
//! kick of the next (`v += dt a`), so a step is one fused sweep over the window
//! ([`Chain::drift_forces_kick`]): drift, force, acceleration and kick grain by grain. Velocities are synchronized (the closing half kick) at the
//! end of every `advance_to`, i.e. at every output time.

use super::{
    check_finite, fixed_steps, Integrator, Method, PeakSpeeds, Stats, StepError, CHECK_EVERY,
};
use crate::chain::{Chain, Window};
use crate::state::State;

/// Velocity Verlet (kick-drift-kick) with fused sweeps: second order, symplectic,
/// time-reversible, one force evaluation per step ([`Method::Verlet`]).
pub struct Verlet {
    dt: f64,
    a: Vec<f64>,
    /// Contact forces (only `init` uses them; the sweep keeps forces in registers).
    f: Vec<f64>,
    /// `exp(-rate dt)` of each damped stretch (empty without damping).
    damp: Vec<f64>,
    peaks: PeakSpeeds,
}

impl Verlet {
    /// For a chain of `n` grains (a striker included) with fixed step `dt` (in the scene's time
    /// units; the run has already fitted it to the output interval).
    pub fn new(dt: f64, n: usize) -> Self {
        Verlet {
            dt,
            a: vec![0.0; n],
            f: vec![0.0; n + 1],
            damp: Vec::new(),
            peaks: PeakSpeeds::default(),
        }
    }

    /// `n` steps from `state`; allocation-free.
    fn steps(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        n: u64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        let (dt, h) = (self.dt, 0.5 * self.dt);
        let t0 = state.t;
        super::kick(&mut state.v, &self.a, h, win);
        for k in 0..n {
            let last = k + 1 == n;
            let c = if last { h } else { dt };
            chain.drift_forces_kick(&mut state.u, &mut state.v, &mut self.a, dt, c, last, win);
            super::count_eval(win, stats);
            // Damping (absorbing layers) as one more flow of the splitting, exact
            // (`v *= exp(-rate dt)`), once per step.
            super::damp(chain, &mut state.v, &self.damp, win, stats);
            // Half-step velocities inside the advance, synchronized ones on its last step.
            self.peaks.update(&state.v, win);
            stats.steps += 1;
            if (k + 1) % CHECK_EVERY == 0 {
                state.t = t0 + (k + 1) as f64 * dt;
                check_finite(chain, state, win, stats.steps)?;
            }
        }
        Ok(())
    }
}

impl Integrator for Verlet {
    fn method(&self) -> Method {
        Method::Verlet
    }

    fn init(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        self.damp = chain.damping_factors(self.dt);
        self.a.iter_mut().for_each(|x| *x = 0.0);
        super::eval(chain, &state.u, &mut self.f, &mut self.a, win, stats);
    }

    fn advance_to(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        t_end: f64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        let n = fixed_steps(state.t, t_end, self.dt);
        self.steps(chain, state, win, n, stats)?;
        state.t = t_end;
        check_finite(chain, state, win, stats.steps)
    }

    fn step_size(&self) -> f64 {
        self.dt
    }

    fn peak_speeds(&mut self) -> Option<&mut PeakSpeeds> {
        Some(&mut self.peaks)
    }
}
