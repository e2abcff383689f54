//! The one driver of the fixed-step methods: a method says how it starts and how it takes `n`
//! steps ([`FixedStep`]); how many steps reach an output time, the blow-up checks, landing on the
//! output time and the rest of [`Integrator`] are written here once, as `solve` is built on
//! `step` in an ODE solver library.

use super::{
    check_finite, fixed_steps, Integrator, LoadWatch, PeakSpeeds, ReflectionWatch, Stats,
    StepError, CHECK_EVERY,
};
use crate::chain::{Chain, Window};
use crate::state::State;

/// A fixed-step method: what differs from one to the next. Every `FixedStep` is an
/// [`Integrator`] (blanket implementation): `advance_to` takes the whole number of steps
/// ([`FixedStep::outer_step`]) that reaches the output time, checks for blow-ups every 256 steps
/// and at the end, and sets `state.t` to the output time exactly.
///
/// A new fixed-step method is a file implementing this trait plus its row in
/// [`super::Method::information`] and [`super::make`] (CONTRIBUTING.md, "Adding an integrator").
// Reachable from outside only through the blanket `Integrator` impl: a method outside the crate
// could not join `Method`'s table, so the trait is the engine's own, not the façade's.
#[allow(unnameable_types)]
pub trait FixedStep {
    /// The step (in the scene's time units; the run has already fitted it to the output
    /// interval). [`Integrator::step_size`] reports it.
    fn dt(&self) -> f64;

    /// The step of the driver's loop: [`FixedStep::dt`], or a multiple of it for a method whose
    /// [`FixedStep::step`] takes several (multirate's slow step).
    fn outer_step(&self) -> f64 {
        self.dt()
    }

    /// Prepare for `state` ([`Integrator::init`]): accelerations, history, the window's shape.
    fn prepare(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats);

    /// Before the first step of an advance (the splitting methods' opening half kick).
    #[inline(always)]
    fn open(&mut self, _chain: &Chain, _state: &mut State, _win: &mut Window) {}

    /// One step of [`FixedStep::outer_step`]; `last` is the last step of this advance (the
    /// splitting methods close their fused kick there). Counts its steps in `stats`.
    fn step(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        last: bool,
        stats: &mut Stats,
    );

    /// Make `state.v` current where the method keeps velocities elsewhere (gear5), before a
    /// blow-up check and at the end of an advance.
    #[inline(always)]
    fn synchronize(&mut self, _state: &mut State, _win: &Window) {}

    /// The running maxima of |v| per grain, for a method that keeps them after every step.
    fn peaks(&mut self) -> Option<&mut PeakSpeeds> {
        None
    }

    /// The watch on one contact's force after every whole step, for a method that keeps it.
    fn load(&mut self) -> Option<&mut LoadWatch> {
        None
    }

    /// The reflections counted at a stretch's edges after every step, for a method that keeps
    /// them.
    fn reflections(&mut self) -> Option<&mut ReflectionWatch> {
        None
    }

    /// `n` steps from `state`, checking for blow-ups every 256 steps; allocation-free. A method
    /// may override it only to compile the same loop (`step_loop`) for another instruction
    /// set.
    fn steps(
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

/// The loop of [`FixedStep::steps`]: open, `n` steps, a blow-up check every [`CHECK_EVERY`]
/// steps (at the time reached, velocities synchronized).
#[inline(always)]
pub(crate) fn step_loop<M: FixedStep + ?Sized>(
    m: &mut M,
    chain: &Chain,
    state: &mut State,
    win: &mut Window,
    n: u64,
    stats: &mut Stats,
) -> Result<(), StepError> {
    let h = m.outer_step();
    let t0 = state.t;
    m.open(chain, state, win);
    for k in 0..n {
        m.step(chain, state, win, k + 1 == n, stats);
        if (k + 1) % CHECK_EVERY == 0 {
            state.t = t0 + (k + 1) as f64 * h;
            m.synchronize(state, win);
            check_finite(chain, state, win, stats.steps)?;
        }
    }
    Ok(())
}

impl<M: FixedStep> Integrator for M {
    fn init(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        self.prepare(chain, state, win, stats);
    }

    fn advance_to(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        t_end: f64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        let n = fixed_steps(state.t, t_end, self.outer_step());
        self.steps(chain, state, win, n, stats)?;
        state.t = t_end;
        self.synchronize(state, win);
        check_finite(chain, state, win, stats.steps)
    }

    fn step_size(&self) -> f64 {
        self.dt()
    }

    fn peak_speeds(&mut self) -> Option<&mut PeakSpeeds> {
        self.peaks()
    }

    fn load_watch(&mut self) -> Option<&mut LoadWatch> {
        self.load()
    }

    fn reflection_watch(&mut self) -> Option<&mut ReflectionWatch> {
        self.reflections()
    }
}
