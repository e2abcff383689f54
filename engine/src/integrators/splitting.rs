//! The splitting methods (velocity Verlet, Blanes-Moan 4): one step, written once, for every
//! carrier of a state.
//!
//! A splitting method is a table of weights ([`Splitting`]): kick `b0`, then for each stage
//! `s` drift `a_s`, new forces, kick `b_(s+1)`. [`stages`] is the one implementation of that
//! sequence. What it moves is a [`Flows`]: the fused f64 sweeps of a scene's run
//! ([`Split`]: the same struct for both methods, [`super::Verlet`] and
//! [`super::BlanesMoan4`] are its two instances), the fast and slow parts of multirate's step,
//! and the runs of a protector's derivatives (`protector::gradient`: the reverse run's forward
//! pass, which keeps its record, and forward mode, which carries each number's tangent beside
//! it). [`cut_at_events`] is the one loop that cuts a step at
//! contact events, for the same carriers. A new splitting method is a table; a new carrier is
//! an implementation of [`Flows`] (and of [`Cuts`] to take events).

use std::marker::PhantomData;

use super::events::Events;
use super::fixed::step_loop;
use super::{
    check_finite, FixedStep, LoadWatch, PeakSpeeds, ReflectionWatch, Stats, StepError, CHECK_EVERY,
};
use crate::chain::{Chain, DampWork, Window};
use crate::state::State;

/// A splitting method's weights: kick `kicks[0]`, then for each stage `s`: drift `drifts[s]`,
/// forces, kick `kicks[s + 1]` (so `kicks` has one more entry than `drifts`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Splitting {
    pub kicks: &'static [f64],
    pub drifts: &'static [f64],
    /// The stage after whose kick a damped stretch's exact flow runs ([`Flows::central`]):
    /// the step's middle, which keeps the composition symmetric.
    pub central: usize,
}

/// A splitting method known at compile time: [`Split`]'s parameter, so each method's loop is
/// compiled with its weights as constants.
pub(crate) trait Scheme: Send + 'static {
    const SPLITTING: Splitting;
}

/// What a splitting step moves: a state and its forces, with whatever it carries beside them.
/// The weights come with the step `h` they multiply (a carrier of derivatives needs both).
pub(crate) trait Flows {
    /// Velocities `+= c h` times the current accelerations.
    fn kick(&mut self, c: f64, h: f64);

    /// Stage `stage`: positions `+= d h` times the velocities, the forces and accelerations
    /// there, velocities `+= k h` times them; `closing` when this kick closes the step (it is
    /// not fused with the next step's opening kick, and the accelerations are kept for it).
    fn stage(&mut self, stage: usize, d: f64, k: f64, h: f64, closing: bool);

    /// After the kick of [`Splitting::central`]: a damped stretch's exact flow over `h`, where
    /// the carrier has one.
    #[inline(always)]
    fn central(&mut self) {}
}

/// The opening kick of a step of `h`.
#[inline(always)]
pub(crate) fn open<F: Flows>(sp: &Splitting, f: &mut F, h: f64) {
    f.kick(sp.kicks[0], h);
}

/// A step of `h` after its opening kick: each stage's drift, forces and kick. The last kick
/// closes the step when `closing`; otherwise it is fused with the next step's opening kick
/// (`kicks[last] + kicks[0]`), and the next step starts without [`open`].
#[inline(always)]
pub(crate) fn stages<F: Flows>(sp: &Splitting, f: &mut F, h: f64, closing: bool) {
    let n = sp.drifts.len();
    for s in 0..n {
        let last = s + 1 == n;
        let k = if !last {
            sp.kicks[s + 1]
        } else if closing {
            sp.kicks[n]
        } else {
            sp.kicks[n] + sp.kicks[0]
        };
        f.stage(s, sp.drifts[s], k, h, last && closing);
        if s == sp.central {
            f.central();
        }
    }
}

/// A whole step of `h`: opened and closed.
#[inline(always)]
pub(crate) fn whole<F: Flows>(sp: &Splitting, f: &mut F, h: f64) {
    open(sp, f, h);
    stages(sp, f, h, true);
}

/// At most this many pieces per step: a step with more events takes its last piece to the end
/// (a contact whose state changes there is treated as without events, unlocated).
pub(crate) const MAX_PIECES: u32 = 16;

/// A carrier whose steps can be cut at contact events.
pub(crate) trait Cuts {
    /// The first event within `left` of the current state, and its contact ([`Events::first`]).
    fn next_cut(&mut self, left: f64) -> Option<(f64, usize)>;

    /// A whole step of `tau`; `event`: the contact whose event ends it (`None`: the step's
    /// rest, up to the grid).
    fn piece(&mut self, tau: f64, event: Option<usize>);
}

/// One step of the grid, `h`, cut into pieces at the predicted events ([`MAX_PIECES`] at most).
#[inline(always)]
pub(crate) fn cut_at_events<C: Cuts>(c: &mut C, h: f64) {
    let mut left = h;
    let mut pieces = 1;
    loop {
        let cut = if pieces < MAX_PIECES {
            c.next_cut(left)
        } else {
            None
        };
        let Some((tau, k)) = cut else {
            c.piece(left, None);
            return;
        };
        c.piece(tau, Some(k));
        left -= tau;
        pieces += 1;
    }
}

/// A splitting method as a scene's integrator: fused f64 sweeps over the window
/// ([`Chain::drift_forces_kick`]: drift, force, acceleration and kick grain by grain), the
/// closing kick of one step fused with the opening one of the next, velocities synchronized at
/// the end of every advance (and, with damped contacts, after every step).
pub struct Split<S: Scheme> {
    w: SplitWorkspace,
    scheme: PhantomData<S>,
}

impl<S: Scheme> Split<S> {
    /// For a chain of `n` grains (a striker included) with fixed step `dt` (in the scene's time
    /// units; the run has already fitted it to the output interval).
    pub fn new(dt: f64, n: usize) -> Self {
        Split {
            w: SplitWorkspace::new(dt, n),
            scheme: PhantomData,
        }
    }

    /// Cut steps at contact events (`integrator.events`, [`super::IntegrationParams::events`]).
    pub fn with_events(mut self, on: bool) -> Self {
        self.w.events_on = on;
        self
    }

    /// The f64 carrier of one call.
    #[inline(always)]
    fn sweeps<'a>(
        &'a mut self,
        chain: &'a Chain,
        state: &'a mut State,
        win: &'a mut Window,
        stats: &'a mut Stats,
    ) -> Sweeps<'a> {
        Sweeps {
            w: &mut self.w,
            chain,
            state,
            win,
            stats,
        }
    }

    /// The step of [`SplitWorkspace::dt`] after the opening kick, closing it when `last`.
    /// With damped contacts the drifts are damped drifts (`chain::damping`), and each step
    /// closes so that the watchers see synchronized velocities; the next step opens in
    /// [`FixedStep::step`].
    #[inline(always)]
    fn sweep(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        last: bool,
        stats: &mut Stats,
    ) {
        let dt = self.w.dt;
        let closing = last || self.w.contact.is_some();
        stages(
            &S::SPLITTING,
            &mut self.sweeps(chain, state, win, stats),
            dt,
            closing,
        );
    }

    /// The loop of [`FixedStep::steps`] with events: `n` steps of the grid, each cut into
    /// pieces at the predicted events ([`cut_at_events`]), each piece a whole step; the
    /// watchers after each step of the grid; a blow-up check every [`CHECK_EVERY`] steps.
    fn event_loop(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        n: u64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        let h = self.w.dt;
        let t0 = state.t;
        for k in 0..n {
            cut_at_events(
                &mut Pieces {
                    s: self.sweeps(chain, state, win, stats),
                    h,
                    sp: &S::SPLITTING,
                },
                h,
            );
            self.w.watch(chain, state, win);
            stats.steps += 1;
            if (k + 1) % CHECK_EVERY == 0 {
                state.t = t0 + (k + 1) as f64 * h;
                check_finite(chain, state, win, stats.steps)?;
            }
        }
        Ok(())
    }
}

impl<S: Scheme> FixedStep for Split<S> {
    fn dt(&self) -> f64 {
        self.w.dt
    }

    fn prepare(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        self.w.prepare(chain, state, win, stats);
    }

    /// The opening kick.
    #[inline(always)]
    fn open(&mut self, chain: &Chain, state: &mut State, win: &mut Window) {
        let dt = self.w.dt;
        self.w.forget_drift();
        let mut stats = Stats::default();
        open(
            &S::SPLITTING,
            &mut self.sweeps(chain, state, win, &mut stats),
            dt,
        );
    }

    /// The sweeps, then the watchers (inside an advance they see half-step velocities, on its
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
        if self.w.contact.is_some() && !last {
            let dt = self.w.dt;
            open(
                &S::SPLITTING,
                &mut self.sweeps(chain, state, win, stats),
                dt,
            );
        }
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
            self.event_loop(chain, state, win, n, stats)
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

/// The f64 carrier: a scene's state, stepped by fused sweeps over the window.
struct Sweeps<'a> {
    w: &'a mut SplitWorkspace,
    chain: &'a Chain,
    state: &'a mut State,
    win: &'a mut Window,
    stats: &'a mut Stats,
}

impl Flows for Sweeps<'_> {
    #[inline(always)]
    fn kick(&mut self, c: f64, h: f64) {
        let c = c * h;
        super::kick(&mut self.state.v, &self.w.a, c, self.win);
        super::gravity_kick(self.chain, &mut self.state.v, c, self.win);
    }

    /// The drift ([`SplitWorkspace::drift`]: the damped drift with damped contacts, when the
    /// sweep's own drift is zero), then one fused sweep.
    #[inline(always)]
    fn stage(&mut self, _stage: usize, d: f64, k: f64, h: f64, closing: bool) {
        let Sweeps {
            w,
            chain,
            state,
            win,
            stats,
        } = self;
        let c = k * h;
        let drift = w.drift(chain, state, d * h, win, stats);
        chain.drift_forces_kick(&mut state.u, &mut state.v, &mut w.a, drift, c, closing, win);
        super::gravity_kick(chain, &mut state.v, c, win);
        super::count_eval(win, stats);
    }

    /// Damping (absorbing layers) as one more flow of the splitting, exact
    /// (`v *= exp(-rate dt)`).
    #[inline(always)]
    fn central(&mut self) {
        super::damp(
            self.chain,
            &mut self.state.v,
            &self.w.damp,
            self.win,
            self.stats,
        );
    }
}

/// The f64 carrier cut at events: each piece a whole step (open, sweeps, close) of its own
/// length, the grid's step `h` restored after it.
struct Pieces<'a> {
    s: Sweeps<'a>,
    h: f64,
    sp: &'static Splitting,
}

impl Cuts for Pieces<'_> {
    #[inline(always)]
    fn next_cut(&mut self, left: f64) -> Option<(f64, usize)> {
        let s = &mut self.s;
        s.w.next_event(s.chain, s.state, s.win, left)
    }

    #[inline(always)]
    fn piece(&mut self, tau: f64, _event: Option<usize>) {
        let h = self.h;
        if tau != h {
            self.s.w.set_step(self.s.chain, tau);
        }
        self.s.w.forget_drift();
        whole(self.sp, &mut self.s, tau);
        if tau != h {
            self.s.w.set_step(self.s.chain, h);
        }
    }
}

/// The workspace of the splitting methods: accelerations, contact forces (for the start only:
/// the sweeps keep forces in registers), damping factors and peak speeds.
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

    /// The first contact event within `left` of `state` and its contact ([`Events::first`];
    /// `None` without events). With damped contacts the prediction reads the dashpots'
    /// accelerations too.
    pub fn next_event(
        &mut self,
        chain: &Chain,
        state: &State,
        win: &Window,
        left: f64,
    ) -> Option<(f64, usize)> {
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
