//! The optimized fourth-order symmetric symplectic Runge-Kutta-Nystrom method of Blanes & Moan,
//! J. Comput. Appl. Math. 142, 313 (2002), "SRKN_6^b": six force evaluations per step (the last
//! kick of one step and the first of the next are fused into one), error constants far smaller
//! than those of the Forest-Ruth / Yoshida triple jump.

use super::fixed::{event_loop, step_loop, Pieces};
use super::{FixedStep, LoadWatch, PeakSpeeds, ReflectionWatch, SplitWorkspace, Stats, StepError};
use crate::chain::{Chain, Window};
use crate::state::State;

const A1: f64 = 0.245298957184271;
const A2: f64 = 0.604872665711080;
const A3: f64 = 0.5 - (A1 + A2);
const B1: f64 = 0.0829844064174052;
const B2: f64 = 0.396309801498368;
const B3: f64 = -0.0390563049223486;
const B4: f64 = 1.0 - 2.0 * (B1 + B2 + B3);

/// Kick weights and drift weights, in order: kick B[0], drift A[0], kick B[1], ... kick B[6].
pub(crate) const KICKS: [f64; 7] = [B1, B2, B3, B4, B3, B2, B1];
pub(crate) const DRIFTS: [f64; 6] = [A1, A2, A3, A3, A2, A1];

/// Blanes & Moan (2002) SRKN_6^b: fourth order, symplectic, time-reversible, six force
/// evaluations per step ([`super::Method::BlanesMoan4`]).
pub struct BlanesMoan4 {
    w: SplitWorkspace,
}

impl BlanesMoan4 {
    /// For a chain of `n` grains (a striker included) with fixed step `dt` (in the scene's time
    /// units).
    pub fn new(dt: f64, n: usize) -> Self {
        BlanesMoan4 {
            w: SplitWorkspace::new(dt, n),
        }
    }

    /// Cut steps at contact events (`integrator.events`, [`super::IntegrationParams::events`]).
    pub fn with_events(mut self, on: bool) -> Self {
        self.w.events_on = on;
        self
    }
}

impl FixedStep for BlanesMoan4 {
    fn dt(&self) -> f64 {
        self.w.dt
    }

    fn prepare(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        self.w.prepare(chain, state, win, stats);
    }

    /// The opening kick.
    #[inline(always)]
    fn open(&mut self, chain: &Chain, state: &mut State, win: &mut Window) {
        self.w.forget_drift();
        super::kick(&mut state.v, &self.w.a, KICKS[0] * self.w.dt, win);
        super::gravity_kick(chain, &mut state.v, KICKS[0] * self.w.dt, win);
    }

    /// The sweep, then the watchers (inside an advance they see half-step velocities, on its
    /// last step synchronized ones; with damped contacts synchronized ones, the next step's
    /// opening kick after them).
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
        self.w.reopen(chain, state, last, KICKS[0] * self.w.dt, win);
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

impl Pieces for BlanesMoan4 {
    fn work(&mut self) -> &mut SplitWorkspace {
        &mut self.w
    }

    /// Six fused sweeps; the kick after the last drift closes this step and opens the next one.
    #[inline(always)]
    fn sweep(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        last_step: bool,
        stats: &mut Stats,
    ) {
        let w = &mut self.w;
        let dt = w.dt;
        // With damped contacts the drifts are damped drifts (`chain::damping`), and each step
        // closes (the kick after the last drift only closes it) so that the watchers see
        // synchronized velocities; the next step opens in `step`.
        let damped = w.contact.is_some();
        for s in 0..6 {
            // The kick after the last drift closes this step and opens the next one.
            let last = s == 5 && (last_step || damped);
            let c = if s < 5 {
                KICKS[s + 1] * dt
            } else if last {
                KICKS[6] * dt
            } else {
                (KICKS[6] + KICKS[0]) * dt
            };
            let drift = w.drift(chain, state, DRIFTS[s] * dt, win, stats);
            chain.drift_forces_kick(&mut state.u, &mut state.v, &mut w.a, drift, c, last, win);
            super::gravity_kick(chain, &mut state.v, c, win);
            super::count_eval(win, stats);
            // Damping (absorbing layers) as one more flow of the splitting, exact
            // (`v *= exp(-rate dt)`), after the central kick of the step.
            if s == 2 {
                super::damp(chain, &mut state.v, &w.damp, win, stats);
            }
        }
    }
}
