//! Velocity Verlet: second order, symplectic, time-reversible.
//!
//! Written as kick-drift-kick with the closing half kick of one step fused with the opening half
//! kick of the next (`v += dt a`), so a step is one fused sweep over the window
//! ([`Chain::drift_forces_kick`]): drift, force, acceleration and kick grain by grain. Velocities are synchronized (the closing half kick) at the
//! end of every `advance_to`, i.e. at every output time.

use super::fixed::{event_loop, step_loop, Pieces};
use super::{FixedStep, LoadWatch, PeakSpeeds, ReflectionWatch, SplitWorkspace, Stats, StepError};
use crate::chain::{Chain, Window};
use crate::state::State;

/// Velocity Verlet (kick-drift-kick) with fused sweeps: second order, symplectic,
/// time-reversible, one force evaluation per step ([`super::Method::Verlet`]).
pub struct Verlet {
    w: SplitWorkspace,
}

impl Verlet {
    /// For a chain of `n` grains (a striker included) with fixed step `dt` (in the scene's time
    /// units; the run has already fitted it to the output interval).
    pub fn new(dt: f64, n: usize) -> Self {
        Verlet {
            w: SplitWorkspace::new(dt, n),
        }
    }

    /// Cut steps at contact events (`integrator.events`, [`super::IntegrationParams::events`]).
    pub fn with_events(mut self, on: bool) -> Self {
        self.w.events_on = on;
        self
    }
}

impl FixedStep for Verlet {
    fn dt(&self) -> f64 {
        self.w.dt
    }

    fn prepare(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        self.w.prepare(chain, state, win, stats);
    }

    /// The opening half kick.
    #[inline(always)]
    fn open(&mut self, chain: &Chain, state: &mut State, win: &mut Window) {
        let h = 0.5 * self.w.dt;
        self.w.forget_drift();
        super::kick(&mut state.v, &self.w.a, h, win);
        super::gravity_kick(chain, &mut state.v, h, win);
    }

    /// The sweep, then the watchers (inside an advance they see half-step velocities, on its
    /// last step synchronized ones; with damped contacts synchronized ones, the next step's
    /// opening half kick after them).
    #[inline(always)]
    fn step(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        last: bool,
        stats: &mut Stats,
    ) {
        self.sweep(chain, state, win, last, stats);
        self.w.watch(chain, state, win);
        self.w.reopen(chain, state, last, 0.5 * self.w.dt, win);
        stats.steps += 1;
    }

    /// The fused loop, or with `integrator.events` the loop that cuts steps at contact events.
    fn steps(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        n: u64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        if self.w.events_on {
            event_loop(self, chain, state, win, n, stats)
        } else {
            step_loop(self, chain, state, win, n, stats)
        }
    }

    fn peaks(&mut self) -> Option<&mut PeakSpeeds> {
        Some(&mut self.w.peaks)
    }

    fn load(&mut self) -> Option<&mut LoadWatch> {
        Some(&mut self.w.load)
    }

    fn reflections(&mut self) -> Option<&mut ReflectionWatch> {
        Some(&mut self.w.reflections)
    }
}

impl Pieces for Verlet {
    fn work(&mut self) -> &mut SplitWorkspace {
        &mut self.w
    }

    /// Drift, force and kick in one sweep; the kick is the closing half kick of this step fused
    /// with the opening one of the next (`v += dt a`), a half kick on the last step.
    #[inline(always)]
    fn sweep(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        last: bool,
        stats: &mut Stats,
    ) {
        let w = &mut self.w;
        let (dt, h) = (w.dt, 0.5 * w.dt);
        // With damped contacts the drift is the damped drift (`chain::damping`), and each step
        // closes with its half kick so that the watchers see synchronized velocities; the next
        // step opens in `step`.
        let last = last || w.contact.is_some();
        let c = if last { h } else { dt };
        let drift = w.drift(chain, state, dt, win, stats);
        chain.drift_forces_kick(&mut state.u, &mut state.v, &mut w.a, drift, c, last, win);
        super::gravity_kick(chain, &mut state.v, c, win);
        super::count_eval(win, stats);
        // Damping (absorbing layers) as one more flow of the splitting, exact
        // (`v *= exp(-rate dt)`), once per step.
        super::damp(chain, &mut state.v, &w.damp, win, stats);
    }
}
