//! Dormand-Prince 5(4) (Hairer, Norsett & Wanner, Solving ODEs I, II.5) for the first-order
//! system (u, v)' = (v, a(u)), with first-same-as-last and PI step control
//! ([`super::step_control`]). The step is shortened to land exactly on each output time.

use super::simd::dispatch_simd;
use super::step_control::{PiController, Verdict};
use super::{check_finite, eval, Integrator, PeakSpeeds, Stats, StepError};
use crate::chain::{Chain, Window};
use crate::state::State;

const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

const ERR: [f64; 7] = [E1, 0.0, E3, E4, E5, E6, E7];

/// `out[i] = base[i] + h * sum_j c[j] k[j][i]`, summed in order of j (so the arithmetic is that
/// of the textbook loop), with the grain loop innermost so it vectorizes.
#[inline(always)]
fn stage<const J: usize>(out: &mut [f64], base: &[f64], h: f64, c: &[f64; J], k: [&[f64]; J]) {
    let n = out.len();
    let base = &base[..n];
    let k = k.map(|s| &s[..n]);
    for i in 0..n {
        let mut acc = 0.0;
        for j in 0..J {
            acc += c[j] * k[j][i];
        }
        out[i] = base[i] + h * acc;
    }
}

/// Retries per step to put a contact switch at the end of the step.
const MAX_SWITCH_RETRIES: u32 = 3;
/// How far past the estimated switch time (as a fraction of the step) the shortened step ends,
/// so that the switch falls inside it despite the error of the linear estimate.
const SWITCH_OVERSHOOT: f64 = 0.02;
/// The step after a switch may be at most this many times the shortened step (the controller
/// still judges it).
const FAC_MAX_AFTER_SWITCH: f64 = 50.0;

/// The earliest fraction of the step at which a compression-only contact in the window (or at
/// its margin) opens or closes, estimated by linear interpolation of its overlap between the
/// displacements `u0` and `u1`; None when no contact switches in a way that matters.
///
/// A switch matters when the kink it puts into the force could make an error above the
/// tolerance: the non-smooth part of the force over the step is at most `F(|x1 - x0|)`, which
/// moves the lighter grain by about `F(|x1 - x0|) h^2 / m` within the step. Switches whose
/// estimate is below `atol + rtol |u|` are ignored: among them the super-exponential tail at the
/// front of every wave, which switches a contact at nearly every step, and the many weak
/// contacts of a train of small waves.
fn first_switch(
    chain: &Chain,
    u0: &[f64],
    u1: &[f64],
    win: &Window,
    h: f64,
    rtol: f64,
    atol: f64,
) -> Option<f64> {
    let n = chain.len();
    let k0 = win.lo.saturating_sub(1);
    let k1 = (win.hi + 1).min(n);
    let mut best: Option<f64> = None;
    for k in k0..=k1 {
        let Some(kern) = chain.contact_kernel(k) else {
            continue;
        };
        if kern.tension {
            continue;
        }
        let (Some(x0), Some(x1)) = (chain.overlap(u0, k), chain.overlap(u1, k)) else {
            continue;
        };
        let cut = kern.cut;
        if (x0 > cut) == (x1 > cut) {
            continue;
        }
        // The lighter of the contact's grains (a wall is immovable).
        let im = match k {
            0 => chain.inv_mass[0],
            k if k == n => chain.inv_mass[n - 1],
            k => chain.inv_mass[k - 1].max(chain.inv_mass[k]),
        };
        let g = if k == 0 { 0 } else { k - 1 };
        let scale = atol + rtol * u0[g].abs().max(u1[g].abs());
        if kern.force_at((x1 - x0).abs()) * h * h * im > scale {
            let theta = ((x0 - cut) / (x0 - x1)).clamp(0.0, 1.0);
            best = Some(best.map_or(theta, |b: f64| b.min(theta)));
        }
    }
    best
}

/// Dormand-Prince 5(4) with PI step control on the max norm of the error, FSAL; lands exactly
/// on output times ([`super::Method::Dopri5`]).
pub struct Dopri5 {
    h: f64,
    rtol: f64,
    atol: f64,
    ctrl: PiController,
    /// Stage derivatives: `ku[s] = v` at stage s, `kv[s] = a(u)` at stage s.
    ku: [Vec<f64>; 7],
    kv: [Vec<f64>; 7],
    us: Vec<f64>,
    vs: Vec<f64>,
    f: Vec<f64>,
    /// Smallest step allowed relative to the current time scale before giving up.
    h_min: f64,
    peaks: PeakSpeeds,
}

impl Dopri5 {
    /// For a chain of `n` grains (a striker included): initial step `h0` (in the scene's time
    /// units), relative and absolute tolerances `rtol`, `atol`.
    pub fn new(h0: f64, rtol: f64, atol: f64, n: usize) -> Self {
        Dopri5 {
            h: h0,
            rtol,
            atol,
            ctrl: PiController::new(5.0),
            ku: std::array::from_fn(|_| vec![0.0; n]),
            kv: std::array::from_fn(|_| vec![0.0; n]),
            us: vec![0.0; n],
            vs: vec![0.0; n],
            f: vec![0.0; n + 1],
            h_min: 0.0,
            peaks: PeakSpeeds::default(),
        }
    }

    /// Try one step of size h from `state`; on return `us`, `vs` hold the new state and the
    /// result is the scaled max-norm error.
    #[inline(always)]
    fn attempt(
        &mut self,
        chain: &Chain,
        state: &State,
        win: &mut Window,
        h: f64,
        stats: &mut Stats,
    ) -> f64 {
        for s in 1..7 {
            let rg = win.range();
            let (us, vs) = (&mut self.us[rg.clone()], &mut self.vs[rg.clone()]);
            let (u0, v0) = (&state.u[rg.clone()], &state.v[rg.clone()]);
            macro_rules! st {
                ($c:expr, $($j:literal),+) => {{
                    stage(us, u0, h, &$c, [$(&self.ku[$j][rg.clone()]),+]);
                    stage(vs, v0, h, &$c, [$(&self.kv[$j][rg.clone()]),+]);
                }};
            }
            match s {
                1 => st!([A21], 0),
                2 => st!([A31, A32], 0, 1),
                3 => st!([A41, A42, A43], 0, 1, 2),
                4 => st!([A51, A52, A53, A54], 0, 1, 2, 3),
                5 => st!([A61, A62, A63, A64, A65], 0, 1, 2, 3, 4),
                _ => st!([A71, 0.0, A73, A74, A75, A76], 0, 1, 2, 3, 4, 5),
            }
            let (ku, kv) = (&mut self.ku, &mut self.kv);
            // Stage derivative of u is the stage velocity.
            eval(chain, &self.us, &mut self.f, &mut kv[s], win, stats);
            let rg = win.range();
            ku[s][rg.clone()].copy_from_slice(&self.vs[rg]);
        }
        // Error estimate, max norm over the window (zeros elsewhere would not change it).
        let mut err: f64 = 0.0;
        for i in win.range() {
            let (mut eu, mut ev) = (0.0, 0.0);
            for (j, &c) in ERR.iter().enumerate() {
                eu += c * self.ku[j][i];
                ev += c * self.kv[j][i];
            }
            let su = self.atol + self.rtol * state.u[i].abs().max(self.us[i].abs());
            let sv = self.atol + self.rtol * state.v[i].abs().max(self.vs[i].abs());
            let e = (h * eu).abs() / su;
            let e2 = (h * ev).abs() / sv;
            // NaN must not be swallowed by max(): treat it as infinite error.
            if e.is_nan() || e2.is_nan() {
                return f64::INFINITY;
            }
            err = err.max(e).max(e2);
        }
        err
    }

    fn largest_error_grain(&self, state: &State, win: &Window) -> usize {
        let mut best = (win.lo, -1.0);
        for i in win.range() {
            let d = (self.vs[i] - state.v[i]).abs();
            if d > best.1 || d.is_nan() {
                best = (i, d);
            }
        }
        best.0
    }
}

impl Dopri5 {
    #[inline(always)]
    fn advance_impl(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        t_end: f64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        // Below this the step no longer changes t in floating point: give up with an error.
        self.h_min = 1e-14 * t_end.abs().max(1.0);
        // Contact switches: a step over which a contact opens or closes integrates a force that is
        // only C^1 there, and the embedded estimate can miss the error. Such a step is retried so
        // that the switch falls at its end (the step is cut at the switch time estimated by
        // linear interpolation of the overlap, plus SWITCH_OVERSHOOT), and the next step starts
        // on the other side. At most MAX_SWITCH_RETRIES per step; retries count as rejections.
        let mut forced: Option<f64> = None;
        let mut retries = 0;
        let mut resume_h = self.h;
        while state.t < t_end {
            let remaining = t_end - state.t;
            // Land exactly on t_end; avoid a sliver of a last step.
            let want = forced.take().unwrap_or(self.h);
            let last = want >= remaining * (1.0 - 1e-12);
            let h = if last { remaining } else { want.min(remaining) };
            let err = self.attempt(chain, state, win, h, stats);
            if err <= 1.0 && retries < MAX_SWITCH_RETRIES {
                if let Some(theta) =
                    first_switch(chain, &state.u, &self.us, win, h, self.rtol, self.atol)
                {
                    let cut = h * (theta + SWITCH_OVERSHOOT).min(1.0);
                    if theta + SWITCH_OVERSHOOT < 1.0 && cut > 1e3 * self.h_min {
                        if retries == 0 {
                            resume_h = self.h;
                        }
                        retries += 1;
                        stats.rejected += 1;
                        forced = Some(cut);
                        continue;
                    }
                }
            }
            match self.ctrl.judge(h, err) {
                Verdict::Accept { next_h } => {
                    let rg = win.range();
                    state.u[rg.clone()].copy_from_slice(&self.us[rg.clone()]);
                    state.v[rg.clone()].copy_from_slice(&self.vs[rg.clone()]);
                    state.t = if last { t_end } else { state.t + h };
                    // First same as last: stage 7 is the derivative at the new state.
                    let (ku, kv) = (&mut self.ku, &mut self.kv);
                    let g = win.lo.saturating_sub(1)..(win.hi + 1).min(state.len());
                    let (k0, k6) = kv.split_at_mut(6);
                    k0[0][g.clone()].copy_from_slice(&k6[0][g.clone()]);
                    let (k0, k6) = ku.split_at_mut(6);
                    k0[0][g.clone()].copy_from_slice(&k6[0][g]);
                    self.peaks.update(&state.v, win);
                    stats.steps += 1;
                    // Keep the controller's proposal unless this step was cut short to land on
                    // an output time; after a step cut at a switch, do not let the short step
                    // shrink the next one below the step proposed before the switch.
                    if retries > 0 {
                        self.h = next_h.max(resume_h.min(FAC_MAX_AFTER_SWITCH * h));
                        retries = 0;
                    } else if !last || h >= self.h {
                        self.h = next_h;
                    }
                    check_finite(chain, state, win, stats.steps)?;
                }
                Verdict::Reject { retry_h } => {
                    stats.rejected += 1;
                    self.h = retry_h;
                    if !(self.h > self.h_min) {
                        let grain = chain.grain_number(self.largest_error_grain(state, win));
                        return Err(if err.is_finite() {
                            StepError::StepSizeUnderflow {
                                time: state.t,
                                step: stats.steps,
                                h: self.h,
                                grain,
                            }
                        } else {
                            StepError::NonFinite {
                                time: state.t,
                                step: stats.steps,
                                grain,
                            }
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

dispatch_simd!(Dopri5, advance, advance_impl, (chain: &Chain, state: &mut State, win: &mut Window, t_end: f64, stats: &mut Stats) -> Result<(), StepError>);

impl Integrator for Dopri5 {
    fn init(&mut self, chain: &Chain, state: &State, win: &mut Window, stats: &mut Stats) {
        for k in self.ku.iter_mut().chain(self.kv.iter_mut()) {
            k.iter_mut().for_each(|x| *x = 0.0);
        }
        self.ctrl = PiController::new(5.0);
        eval(chain, &state.u, &mut self.f, &mut self.kv[0], win, stats);
        self.ku[0].copy_from_slice(&state.v);
    }

    fn advance_to(
        &mut self,
        chain: &Chain,
        state: &mut State,
        win: &mut Window,
        t_end: f64,
        stats: &mut Stats,
    ) -> Result<(), StepError> {
        self.advance(chain, state, win, t_end, stats)
    }

    fn step_size(&self) -> f64 {
        self.h
    }

    fn peak_speeds(&mut self) -> Option<&mut PeakSpeeds> {
        Some(&mut self.peaks)
    }
}
