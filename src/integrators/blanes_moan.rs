//! The optimized fourth-order symmetric symplectic Runge-Kutta-Nystrom method of Blanes & Moan,
//! J. Comput. Appl. Math. 142, 313 (2002), "SRKN_6^b": six force evaluations per step (the last
//! kick of one step and the first of the next are fused into one), error constants far smaller
//! than those of the Forest-Ruth / Yoshida triple jump.

use super::{
    check_finite, fixed_steps, Integrator, Method, PeakSpeeds, Stats, StepError, CHECK_EVERY,
};
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
/// evaluations per step ([`Method::BlanesMoan4`]).
pub struct BlanesMoan4 {
    dt: f64,
    a: Vec<f64>,
    f: Vec<f64>,
    /// `exp(-rate dt)` of each damped stretch (empty without damping).
    damp: Vec<f64>,
    peaks: PeakSpeeds,
}

impl BlanesMoan4 {
    /// For a chain of `n` grains (a striker included) with fixed step `dt` (in the scene's time
    /// units).
    pub fn new(dt: f64, n: usize) -> Self {
        BlanesMoan4 {
            dt,
            a: vec![0.0; n],
            f: vec![0.0; n + 1],
            damp: Vec::new(),
            peaks: PeakSpeeds::default(),
        }
    }

    fn steps(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        n: u64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        let dt = self.dt;
        let t0 = state.t;
        super::kick(&mut state.v, &self.a, KICKS[0] * dt, win);
        for k in 0..n {
            for s in 0..6 {
                // The kick after the last drift closes this step and opens the next one.
                let last = s == 5 && k + 1 == n;
                let c = if s < 5 {
                    KICKS[s + 1] * dt
                } else if last {
                    KICKS[6] * dt
                } else {
                    (KICKS[6] + KICKS[0]) * dt
                };
                chain.drift_forces_kick(
                    &mut state.u,
                    &mut state.v,
                    &mut self.a,
                    DRIFTS[s] * dt,
                    c,
                    last,
                    win,
                );
                super::count_eval(win, stats);
                // Damping (absorbing layers) as one more flow of the splitting, exact
                // (`v *= exp(-rate dt)`), after the central kick of the step.
                if s == 2 {
                    super::damp(chain, &mut state.v, &self.damp, win, stats);
                }
            }
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

impl Integrator for BlanesMoan4 {
    fn method(&self) -> Method {
        Method::BlanesMoan4
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
