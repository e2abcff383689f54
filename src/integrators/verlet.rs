//! Velocity Verlet (kick-drift-kick): second order, symplectic, time-reversible.

use super::{check_finite, eval, fixed_steps, Integrator, Method, Stats, StepError, CHECK_EVERY};
use crate::chain::{Chain, Window};
use crate::state::State;

pub struct Verlet {
    dt: f64,
    a: Vec<f64>,
    f: Vec<f64>,
}

impl Verlet {
    pub fn new(dt: f64, n: usize) -> Self {
        Verlet {
            dt,
            a: vec![0.0; n],
            f: vec![0.0; n + 1],
        }
    }

    /// One step: half kick, drift, force, half kick. Allocation-free.
    #[inline]
    fn step(&mut self, chain: &Chain, state: &mut State, win: &mut Window, stats: &mut Stats) {
        let (dt, h) = (self.dt, 0.5 * self.dt);
        let r = win.range();
        {
            let (u, v, a) = (
                &mut state.u[r.clone()],
                &mut state.v[r.clone()],
                &self.a[r.clone()],
            );
            for i in 0..u.len() {
                v[i] += h * a[i];
                u[i] += dt * v[i];
            }
        }
        eval(chain, &state.u, &mut self.f, &mut self.a, win, stats);
        let r = win.range();
        let (v, a) = (&mut state.v[r.clone()], &self.a[r]);
        for i in 0..v.len() {
            v[i] += h * a[i];
        }
    }
}

impl Integrator for Verlet {
    fn method(&self) -> Method {
        Method::Verlet
    }

    fn init(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        self.a.iter_mut().for_each(|x| *x = 0.0);
        eval(chain, &state.u, &mut self.f, &mut self.a, win, stats);
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
        let t0 = state.t;
        for k in 0..n {
            self.step(chain, state, win, stats);
            stats.steps += 1;
            if (k + 1) % CHECK_EVERY == 0 {
                state.t = t0 + (k + 1) as f64 * self.dt;
                check_finite(chain, state, win, stats.steps)?;
            }
        }
        state.t = t_end;
        check_finite(chain, state, win, stats.steps)
    }

    fn step_size(&self) -> f64 {
        self.dt
    }
}
