//! What every method's step shares, below the methods and below the registry (`mod.rs`:
//! `Method`, its table of facts and `make`): the work counters (`Stats`), the step error, the
//! `Integrator` trait, the per-step peak speeds, and the force evaluation, kick, damping and
//! blow-up check the methods' loops call.

use crate::chain::{Chain, Window};
use crate::state::State;
use serde::Serialize;

/// Counts kept by every integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (adaptive methods).
    pub rejected: u64,
    /// Force (acceleration) evaluations of the whole window.
    pub force_evals: u64,
    /// Sum over force evaluations of the number of grains evaluated: the work done (the
    /// islands and the one margin grain beside each edge).
    pub grain_evals: u64,
    /// Sum over force evaluations of the number of grains integrated (the islands, margins not
    /// counted): the mean window is this over `force_evals`, counted like `max_window`.
    pub window_evals: u64,
    /// Largest number of grains integrated at once (summed over islands, margins not counted).
    pub max_window: usize,
    /// Grains taken out of the islands at output times (exactly at rest, or put to rest by the
    /// sleep rule).
    pub slept_grains: u64,
    /// Kinetic energy removed by the sleep rule (zero under the exact rule).
    pub slept_energy: f64,
    /// Kinetic energy taken out by damped sections (absorbing layers).
    pub absorbed_energy: f64,
    /// Momentum taken out by damped sections.
    pub absorbed_momentum: f64,
    /// Energy dissipated by contact damping (the kinetic energy its flow took out).
    pub dissipated_energy: f64,
    /// Grains dropped from the integration by the causal horizon ([`crate::run::Horizon`]).
    pub dropped_grains: u64,
    /// Kinetic energy the dropped grains had when they were dropped (their velocity is set to
    /// zero: each stays where it is, a fixed wall for its neighbour inside).
    pub dropped_energy: f64,
}

impl std::fmt::Display for Stats {
    /// One line: `640000 steps (0 rejected), 3840001 force evaluations, 1.04e10 grain
    /// evaluations, mean window 2696, max 5399` (and what sleep and damping took, when nonzero).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} steps ({} rejected), {} force evaluations, {:.3e} grain evaluations, mean window \
             {:.0}, max {}",
            self.steps,
            self.rejected,
            self.force_evals,
            self.grain_evals as f64,
            self.mean_window(),
            self.max_window
        )?;
        if self.slept_grains > 0 {
            write!(
                f,
                ", {} grains put to rest ({:.3e} kinetic energy)",
                self.slept_grains, self.slept_energy
            )?;
        }
        if self.absorbed_energy != 0.0 {
            write!(f, ", {:.6e} energy absorbed", self.absorbed_energy)?;
        }
        if self.dropped_grains > 0 {
            write!(
                f,
                ", {} grains dropped beyond the horizon ({:.3e} kinetic energy)",
                self.dropped_grains, self.dropped_energy
            )?;
        }
        Ok(())
    }
}

impl Stats {
    /// Mean number of grains integrated per force evaluation (summed over islands, margins not
    /// counted, as in `max_window`, so it is never above it; the work including the margins is
    /// `grain_evals`).
    pub fn mean_window(&self) -> f64 {
        if self.force_evals == 0 {
            0.0
        } else {
            self.window_evals as f64 / self.force_evals as f64
        }
    }

    /// Fraction of the grain-steps of a run that integrates all `n` grains that were saved.
    pub fn saved_fraction(&self, n: usize) -> f64 {
        if self.force_evals == 0 || n == 0 {
            0.0
        } else {
            1.0 - self.grain_evals as f64 / (self.force_evals as f64 * n as f64)
        }
    }
}

/// A failure during integration.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A displacement or velocity became NaN or infinite.
    #[error("numerical blow-up at t = {}, step {step}: grain {grain} has a non-finite displacement or velocity (the step is too large, or the scene is unstable)", crate::number::Num(*.time))]
    NonFinite {
        /// Time of the failure, in the scene's time units.
        time: f64,
        /// Steps taken so far.
        step: u64,
        /// The grain at fault (the first non-finite one; for dopri5 the one with the largest
        /// error estimate), as its printed grain number.
        grain: i64,
    },
    /// The adaptive step fell below its smallest allowed size.
    #[error("step size underflow at t = {time}, step {step}: the adaptive step fell to {h:e} near grain {grain}")]
    StepSizeUnderflow {
        /// Time of the failure, in the scene's time units.
        time: f64,
        /// Steps taken so far.
        step: u64,
        /// The step size it fell to.
        h: f64,
        /// The grain with the largest error estimate, as its printed grain number.
        grain: i64,
    },
}

/// An integration method.
pub trait Integrator {
    /// Prepare the method for `state` (computes accelerations and internal history). Must be
    /// called before the first `advance_to` and after any outside change of the state.
    fn init(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats);
    /// Integrate until `state.t == t_end` exactly.
    fn advance_to(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        t_end: f64,
        stats: &mut Stats,
    ) -> Result<(), StepError>;
    /// The step size used last (fixed-step: the step).
    fn step_size(&self) -> f64;
    /// The running maxima of |v| per grain this method keeps after every step when switched on,
    /// or `None` for a method that does not keep them (gear5 holds no per-step velocities,
    /// multirate no synchronized ones for its slow grains).
    fn peak_speeds(&mut self) -> Option<&mut PeakSpeeds> {
        None
    }
    /// The watch on one contact's force after every whole step
    /// ([`crate::Simulation::watch_load`]), or `None` for a method that does not keep it (only
    /// the fixed-step splitting methods, whose steps end on whole positions, do).
    fn load_watch(&mut self) -> Option<&mut super::LoadWatch> {
        None
    }
    /// The reflections counted at a stretch's edges after every step
    /// ([`crate::Simulation::watch_reflections`]), or `None` for a method that does not count
    /// them (the splitting methods and multirate, whose fast region holds the edges, do).
    fn reflection_watch(&mut self) -> Option<&mut super::ReflectionWatch> {
        None
    }
}

/// Running maximum of |v| per grain over the steps of a run (for the true peak velocity of a
/// pulse, which the state at output times misses). Off by default; while off, a step pays one
/// branch. The splitting methods sample the velocities inside a step after a kick (shifted in
/// time by a fraction of the step), which changes the maximum of a smooth velocity curve only
/// at O(dt^2).
#[derive(Clone, Debug, Default)]
pub struct PeakSpeeds {
    on: bool,
    max: Vec<f64>,
}

impl PeakSpeeds {
    /// Switch on for `n` grains, starting from the speeds `v` (a later call starts again).
    pub fn start(&mut self, v: &[f64]) {
        self.on = true;
        self.max.clear();
        self.max.extend(v.iter().map(|x| x.abs()));
    }

    /// Whether the maxima are kept.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// Largest |v| of each grain since the last [`PeakSpeeds::reset`] (empty while off).
    pub fn max(&self) -> &[f64] {
        &self.max
    }

    /// Start a new interval at the current speeds `v`, over `range` (grains outside it are at
    /// rest and were at rest since the last reset).
    pub fn reset(&mut self, v: &[f64], range: std::ops::Range<usize>) {
        if self.on {
            for i in range {
                self.max[i] = v[i].abs();
            }
        }
    }

    /// Fold in the speeds after a step over the window's envelope.
    #[inline(always)]
    pub(crate) fn update(&mut self, v: &[f64], win: &Window) {
        if self.on {
            let r = win.range();
            for (m, x) in self.max[r.clone()].iter_mut().zip(&v[r]) {
                let s = x.abs();
                if s > *m {
                    *m = s;
                }
            }
        }
    }
}

/// Number of steps between blow-up checks inside a fixed-step `advance_to`.
pub(crate) const CHECK_EVERY: u64 = 256;

/// Evaluate accelerations and keep the work counters.
#[inline(always)]
pub(crate) fn eval(
    chain: &Chain,
    u: &[f64],
    f: &mut [f64],
    a: &mut [f64],
    win: &mut Window,
    stats: &mut Stats,
) {
    chain.accelerations(u, f, a, win);
    count_eval(win, stats);
}

/// Count one force evaluation of the window (plus its margin).
#[inline(always)]
pub(crate) fn count_eval(win: &Window, stats: &mut Stats) {
    let integrated = win.len();
    let margins = if win.skip { 2 * win.islands().len() } else { 0 };
    stats.force_evals += 1;
    stats.grain_evals += (integrated + margins) as u64;
    stats.window_evals += integrated as u64;
    stats.max_window = stats.max_window.max(integrated);
}

/// `v += c * a` over every island.
#[inline(always)]
pub(crate) fn kick(v: &mut [f64], a: &[f64], c: f64, win: &Window) {
    for isl in win.islands() {
        let r = isl.range();
        for (v, a) in v[r.clone()].iter_mut().zip(&a[r]) {
            *v += c * a;
        }
    }
}

/// The kick of gravity ([`Chain::gravity`]), `v += c g` on every grain of the window: the
/// splitting methods' kick of gravity's potential `-g m u`, which commutes with the contacts'
/// kick (both move velocities only), so a method's kick `c` of the contacts followed by this one
/// is its kick of the whole force. Without gravity it returns before touching a grain: the
/// no-gravity run's arithmetic is unchanged (one test per kick, none per grain).
#[inline(always)]
pub(crate) fn gravity_kick(chain: &Chain, v: &mut [f64], c: f64, win: &Window) {
    let g = chain.gravity();
    if g == 0.0 {
        return;
    }
    let dv = c * g;
    for isl in win.islands() {
        for v in &mut v[isl.range()] {
            *v += dv;
        }
    }
}

/// Apply the damped sections' flow (`factors` from [`Chain::damping_factors`]) over the islands
/// and count what it took out; shared by the splitting methods.
#[inline(always)]
pub(crate) fn damp(chain: &Chain, v: &mut [f64], factors: &[f64], win: &Window, stats: &mut Stats) {
    if factors.is_empty() {
        return;
    }
    let mut out = (stats.absorbed_energy, stats.absorbed_momentum);
    chain.damp(v, factors, win, &mut out);
    (stats.absorbed_energy, stats.absorbed_momentum) = out;
}

/// Fixed-step bookkeeping shared by the fixed-step methods: how many steps reach `t_end`.
pub(crate) fn fixed_steps(t: f64, t_end: f64, dt: f64) -> u64 {
    let n = ((t_end - t) / dt).round();
    if n <= 0.0 {
        0
    } else {
        n as u64
    }
}

/// Blow-up check shared by all methods.
pub(crate) fn check_finite(
    chain: &Chain,
    state: &State,
    win: &Window,
    step: u64,
) -> Result<(), StepError> {
    match state.first_non_finite(win.range()) {
        None => Ok(()),
        Some(i) => Err(StepError::NonFinite {
            time: state.t,
            step,
            grain: chain.grain_number(i),
        }),
    }
}
