//! The one driver of the fixed-step methods: a method says how it starts and how it takes `n`
//! steps ([`FixedStep`]); how many steps reach an output time, the blow-up checks, landing on the
//! output time and the rest of [`Integrator`] are written here once, as `solve` is built on
//! `step` in an ODE solver library.

use super::events::Events;
use super::{
    check_finite, fixed_steps, Integrator, LoadWatch, PeakSpeeds, ReflectionWatch, Stats,
    StepError, CHECK_EVERY,
};
use crate::chain::{Chain, DampWork, Window};
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

/// The workspace of the splitting methods (verlet, blanes-moan4): accelerations, contact forces
/// (for the start only: the sweeps keep forces in registers), damping factors and peak speeds.
pub(crate) struct SplitWorkspace {
    pub dt: f64,
    pub a: Vec<f64>,
    f: Vec<f64>,
    /// `exp(-rate dt)` of each damped stretch (empty without damping).
    pub damp: Vec<f64>,
    /// The damped drift's scratch space (`None`: no damped contacts).
    pub contact: Option<DampWork>,
    pub peaks: PeakSpeeds,
    pub load: LoadWatch,
    pub reflections: ReflectionWatch,
    /// Whether steps are cut at contact events (`integrator.events`), and the events' data
    /// once prepared.
    pub events_on: bool,
    pub events: Option<Events>,
    /// The accelerations the events' prediction reads with damped contacts: the elastic ones
    /// and the dashpots'.
    a_events: Vec<f64>,
}

impl SplitWorkspace {
    /// At the start of an advance or of a piece of a step: the damped drift computes its first
    /// terms afresh (`DampWork::forget`).
    #[inline(always)]
    pub fn forget_drift(&mut self) {
        if let Some(work) = &mut self.contact {
            work.forget();
        }
    }

    /// The drift of a splitting method's sweep: `tau` for the fused sweep to take, or, with
    /// damped contacts, the damped drift over `tau` (`chain::damping`) taken here, its energy
    /// counted in `stats`, and zero for the sweep.
    #[inline(always)]
    pub fn drift(
        &mut self,
        chain: &Chain,
        state: &mut State,
        tau: f64,
        win: &mut Window,
        stats: &mut Stats,
    ) -> f64 {
        let Some(work) = &mut self.contact else {
            return tau;
        };
        let n = state.v.len();
        if state.dissipated.len() != n {
            state.dissipated.resize(n, 0.0);
        }
        stats.dissipated_energy += chain.damped_drift(
            &mut state.u,
            &mut state.v,
            tau,
            win,
            work,
            &mut state.dissipated,
        );
        0.0
    }

    /// What a splitting method with damped contacts does after a step it closed and the
    /// watchers saw (synchronized velocities: the load's dashpot reads them): the next step's
    /// opening kick `open_kick * a` (not after the last step).
    #[inline]
    pub fn reopen(
        &self,
        chain: &Chain,
        state: &mut State,
        last: bool,
        open_kick: f64,
        win: &Window,
    ) {
        if self.contact.is_some() && !last {
            super::kick(&mut state.v, &self.a, open_kick, win);
            super::gravity_kick(chain, &mut state.v, open_kick, win);
        }
    }

    /// For a chain of `n` grains and the step `dt`.
    pub fn new(dt: f64, n: usize) -> Self {
        SplitWorkspace {
            dt,
            a: vec![0.0; n],
            f: vec![0.0; n + 1],
            damp: Vec::new(),
            contact: None,
            peaks: PeakSpeeds::default(),
            load: LoadWatch::default(),
            reflections: ReflectionWatch::default(),
            events_on: false,
            events: None,
            a_events: Vec::new(),
        }
    }

    /// Fold the state after a whole step into the watchers (peak speeds, load, reflections).
    #[inline(always)]
    pub fn watch(&mut self, chain: &Chain, state: &State, win: &Window) {
        self.peaks.update(&state.v, win);
        self.load.update(chain, state);
        self.reflections.update(chain, state);
    }

    /// Make `tau` the step (a piece of a step cut at an event, or the grid's step back): the
    /// step and the damping factors for it, without allocating.
    pub fn set_step(&mut self, chain: &Chain, tau: f64) {
        self.dt = tau;
        chain.damping_factors_into(tau, &mut self.damp);
    }

    /// The first contact event within `left` of `state` ([`Events::first`]; `None` without
    /// events). With damped contacts the prediction reads the dashpots' accelerations too.
    pub fn next_event(
        &mut self,
        chain: &Chain,
        state: &State,
        win: &Window,
        left: f64,
    ) -> Option<f64> {
        let e = self.events.as_mut()?;
        match &mut self.contact {
            None => e.first(state, &self.a, win, left),
            Some(work) => {
                self.a_events.clear();
                self.a_events.extend_from_slice(&self.a);
                chain.add_damping_accelerations(&state.u, &state.v, &mut self.a_events, win, work);
                e.first(state, &self.a_events, win, left)
            }
        }
    }

    /// The start of a splitting method: damping factors for the step, accelerations at `state`.
    pub fn prepare(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        self.damp = chain.damping_factors(self.dt);
        self.contact = chain.has_contact_damping().then(DampWork::default);
        self.a.iter_mut().for_each(|x| *x = 0.0);
        super::eval(chain, &state.u, &mut self.f, &mut self.a, win, stats);
        self.events = self.events_on.then(|| Events::new(chain));
    }
}

/// At most this many pieces per step: a step with more events takes its last piece to the end
/// (a contact whose state changes there is treated as without events, unlocated).
const MAX_PIECES: u32 = 16;

/// A splitting method whose step can be cut at events: its workspace and its step without
/// the watchers.
pub(crate) trait Pieces: FixedStep {
    /// The method's workspace.
    fn work(&mut self) -> &mut SplitWorkspace;

    /// The step of [`SplitWorkspace::dt`] after [`FixedStep::open`], its closing kick included
    /// when `last`, without the watchers or the step count.
    fn sweep(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        last: bool,
        stats: &mut Stats,
    );
}

/// The loop of [`FixedStep::steps`] with events: `n` steps of the grid, each cut into pieces
/// at the predicted events, each piece a whole step (open, sweep, close); the watchers after
/// each step of the grid; a blow-up check every [`CHECK_EVERY`] steps.
pub(crate) fn event_loop<M: Pieces>(
    m: &mut M,
    chain: &Chain,
    state: &mut State,
    win: &mut Window,
    n: u64,
    stats: &mut Stats,
) -> Result<(), StepError> {
    let h = m.outer_step();
    let t0 = state.t;
    for k in 0..n {
        let mut left = h;
        let mut pieces = 1;
        loop {
            let tau = if pieces < MAX_PIECES {
                m.work().next_event(chain, state, win, left)
            } else {
                None
            };
            let Some(tau) = tau else {
                piece(m, chain, state, win, left, h, stats);
                break;
            };
            piece(m, chain, state, win, tau, h, stats);
            left -= tau;
            pieces += 1;
        }
        m.work().watch(chain, state, win);
        stats.steps += 1;
        if (k + 1) % CHECK_EVERY == 0 {
            state.t = t0 + (k + 1) as f64 * h;
            check_finite(chain, state, win, stats.steps)?;
        }
    }
    Ok(())
}

/// One whole step of `tau` (the grid's step is `h`).
#[inline(always)]
fn piece<M: Pieces>(
    m: &mut M,
    chain: &Chain,
    state: &mut State,
    win: &mut Window,
    tau: f64,
    h: f64,
    stats: &mut Stats,
) {
    if tau != h {
        m.work().set_step(chain, tau);
    }
    m.open(chain, state, win);
    m.sweep(chain, state, win, true, stats);
    if tau != h {
        m.work().set_step(chain, h);
    }
}
