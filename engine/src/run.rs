//! Running a simulation: the loop over output times, blow-up detection and stage timers.

use crate::chain::{Chain, Window};
use crate::integrators::{self, IntegrationParams, Integrator, Stats, StepError};
use crate::number::Num;
use crate::observables::{self, Totals};
use crate::state::State;
use serde::Serialize;
pub use std::ops::ControlFlow;
use std::time::{Duration, Instant};

/// Number of output times after t = 0 for a run of `duration` with outputs every `interval`: the
/// one count every caller uses (the run loop, progress bars, `check`), so they cannot drift. The
/// factor 1 + 1e-12 lets a duration that is a whole number of intervals up to round-off (0.3 /
/// 0.1 = 2.9999999999999996) count its last output.
pub fn output_count(duration: f64, interval: f64) -> u64 {
    (duration / interval * (1.0 + 1e-12)).floor() as u64
}

/// Why a run stopped early.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RunError {
    /// The integrator failed: a non-finite displacement or velocity, or the adaptive step fell
    /// below its smallest size.
    #[error(transparent)]
    Step(#[from] StepError),
    /// The relative energy error at an output time (energy in the chain plus what damping and
    /// the sleep rule took out, against the initial energy less that of grains still in their
    /// first free flight) exceeded
    /// [`IntegrationParams::max_energy_error`].
    #[error("numerical blow-up at t = {}, step {step}: relative energy error {rel:.3e} exceeds the bound {bound:e} (largest grain energy at grain {grain}); the step is too large or the tolerance too loose", Num(*.time))]
    EnergyDrift {
        /// Simulated time of the output at which the check failed.
        time: f64,
        /// Accepted steps taken so far.
        step: u64,
        /// The relative energy error (absolute when the initial energy is zero).
        rel: f64,
        /// The bound it exceeded.
        bound: f64,
        /// Printed grain number (chain grains from 1, a left striker 0) of the grain with the
        /// largest energy in the window, where the blow-up most likely is.
        grain: i64,
    },
    /// Settings that cannot work (schedule, step, tolerances, sleep rule, multirate region,
    /// initial conditions, recorder requests); the message names the setting.
    #[error("invalid run settings: {0}")]
    Settings(String),
    /// The chain could not be built (for callers that build chain and simulation under one
    /// error type).
    #[error("invalid chain: {0}")]
    Chain(#[from] crate::chain::ChainError),
}

/// Wall time spent in each stage of the run (rapier-style counters).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Timings {
    /// Integrating between output times.
    #[serde(serialize_with = "secs")]
    pub integrate: Duration,
    /// Blow-up checks and sleep bookkeeping at output times.
    #[serde(serialize_with = "secs")]
    pub checks: Duration,
    /// The output callback: observables and writing.
    #[serde(serialize_with = "secs")]
    pub output: Duration,
}

impl std::fmt::Display for Timings {
    /// One line: `integrate 12.048 s, checks 0.155 s, output 0.088 s`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "integrate {:.3} s, checks {:.3} s, output {:.3} s",
            self.integrate.as_secs_f64(),
            self.checks.as_secs_f64(),
            self.output.as_secs_f64()
        )
    }
}

fn secs<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(d.as_secs_f64())
}

/// What a run did, in one place: the bookkeeping every user of a [`Simulation`] reports
/// (`grainchain run`'s summary.json, `reproduce`'s runs table, scripts). Read it with
/// [`Simulation::summary`] at any time; the wall time of the whole run is the caller's.
#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    /// Method name.
    pub method: &'static str,
    /// The step asked for, and the step taken (fixed-step methods shorten it to divide the
    /// output interval).
    pub requested_dt: f64,
    /// The step taken: for fixed-step methods `requested_dt` shortened so a whole number of
    /// steps fits each output interval; for dopri5 the initial step, as asked for.
    pub dt: f64,
    /// Grains in the chain, a striker included.
    pub grains: usize,
    /// Output times after t = 0, and the time reached.
    pub outputs: u64,
    /// Simulated time reached so far (the time of the last output, `k * interval`).
    pub time: f64,
    /// Steps, evaluations, window and what sleep and damping took out.
    pub stats: Stats,
    /// Wall time per stage of the run loop.
    pub timings: Timings,
    /// Every grain ever integrated lies in `ever.0..ever.1`.
    pub ever: (usize, usize),
    /// Islands now.
    pub islands: usize,
    /// Energy at t = 0, and the largest relative energy and momentum errors at output times.
    pub initial_energy: f64,
    /// Largest relative energy error at an output time: energy in the chain (kinetic plus
    /// potential) plus what damping and the sleep rule took out, against `initial_energy` less
    /// the energy of the grains still in the free flight they started in, which no force has
    /// touched (at least a millionth of `initial_energy`; absolute when that is zero); under
    /// gravity the error beyond the totals' rounding (4 eps of the static state's elastic
    /// energy, which grows with a column's depth).
    pub max_energy_error: f64,
    /// Largest momentum change at an output time (damping's share added back), relative to the
    /// initial momentum (absolute when that is zero). Meaningful for free ends only.
    pub max_momentum_error: f64,
    /// The causal horizon's speed in grains per time unit, when the run has a horizon and
    /// something protected ([`Simulation::horizon_speed`]).
    pub horizon_speed: Option<f64>,
    /// The horizon's bound, [`Horizon::speed_bound`] of the run (grains per time unit), when
    /// the run has a horizon and something protected ([`Simulation::horizon_bound`]).
    pub horizon_bound: Option<f64>,
    /// What the run did that may make its numbers wrong and that the settings allowed
    /// explicitly (a horizon speed below its bound with `unsafe`), one sentence each.
    pub warnings: Vec<String>,
}

impl RunSummary {
    /// Grains never touched.
    pub fn untouched(&self) -> usize {
        self.grains - (self.ever.1 - self.ever.0)
    }

    /// Grains between the furthest disturbance and the nearer chain end.
    pub fn end_margin(&self) -> usize {
        self.ever.0.min(self.grains - self.ever.1)
    }
}

/// The causal horizon of a run that knows its end: at output `k` only the grains from which a
/// disturbance could still reach a protected grain range before that range's last output are
/// integrated; every other grain is dropped from the integration for good (its velocity set to
/// zero, its kinetic energy counted in [`Stats::dropped_energy`]; it stays where it is, a fixed
/// wall for its neighbour inside). A range is protected by [`Simulation::protect`]; the
/// [`crate::recorder::Recorder`] protects every region, probe and snapshot range it records
/// (pulses and tracks: the whole chain), each up to the last output it is recorded at. A run
/// under a horizon gives the protected ranges bit for bit the values of the run without it as
/// long as no disturbance travels faster than `speed`: what the dropping changes starts beyond
/// the reach and cannot arrive before the end (`validation/horizon.rs` checks this on containers
/// (a)-(e), and that a horizon made too tight is caught). The whole chain's totals (energies.csv's
/// `total`, the energy check) are those of the run with the dropped grains held still, plus
/// [`Stats::dropped_energy`]: not the long-chain run's.
///
/// Reach at output `k` of a range protected until output `K`: `ceil(speed (K - k) interval) +
/// pad` grains on each side. A multirate run also keeps its fast region.
///
/// The default speed ([`Horizon::speed_bound`]) is the fastest long-wave sound speed the run's
/// energy allows in the chain outside the protected ranges. How it compares with the fastest
/// back-signal measured on the container scenes (`examples/back_signal.rs`) is in BENCHMARKS.md,
/// "Causal horizon".
///
/// A `speed` below the bound is refused when the run starts ([`RunError::Settings`]; the scene
/// check refuses it before, [`Horizon::refusal`]): the bound is what makes the horizon
/// exact, and a slower speed drops grains whose influence can reach a protected range in time
/// (the recorded numbers then differ from the run without a horizon, with no other sign).
/// With `unsafe_speed` the run goes ahead and says so in [`RunSummary::warnings`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Horizon {
    /// The fastest a disturbance may travel towards a protected range, in grains per time unit;
    /// `None`: [`Horizon::speed_bound`] of the run.
    pub speed: Option<f64>,
    /// Grains kept beyond the reach on each side.
    pub pad: usize,
    /// Run with a `speed` below [`Horizon::speed_bound`] (scene key `run.horizon.unsafe`): the
    /// protected ranges are then no longer exact; the run records a warning.
    pub unsafe_speed: bool,
}

/// The run's times: `duration` and `interval` finite and > 0, the interval at most the
/// duration. The one place these rules live: the scene check puts an error under its scene key
/// (the error's key), [`SimulationBuilder::build`] refuses the run with it.
pub fn validate_schedule(duration: f64, interval: f64) -> Result<(), integrators::ParamsError> {
    positive("run.duration", duration)?;
    positive("run.output_interval", interval)?;
    if interval > duration {
        return Err(integrators::ParamsError {
            key: "run.output_interval",
            message: format!("must be at most run.duration ({duration}), got {interval}"),
        });
    }
    Ok(())
}

fn positive(key: &'static str, x: f64) -> Result<(), integrators::ParamsError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(integrators::ParamsError {
            key,
            message: format!("must be a finite number > 0, got {x}"),
        })
    }
}

impl Horizon {
    /// The horizon against the run's integration settings: a `speed`, when given, finite and
    /// above 0; a method that resets margin grains ([`crate::integrators::MethodInfo::horizon`]);
    /// grains at rest skipped. The one place these rules live (the scene check and
    /// [`SimulationBuilder::build`]).
    pub fn validate(&self, params: &IntegrationParams) -> Result<(), integrators::ParamsError> {
        if let Some(x) = self.speed {
            positive("run.horizon.speed", x)?;
        }
        let fail = |message: String| {
            Err(integrators::ParamsError {
                key: "run.horizon",
                message,
            })
        };
        if !params.method.information().horizon {
            return fail(format!(
                "needs a fixed-step method that resets margin grains ({}), not {}",
                crate::Method::names_with(|i| i.horizon, "or"),
                params.method.name()
            ));
        }
        if !params.skip_untouched {
            return fail(
                "needs grains at rest to be skipped (integrator.skip_untouched = true)".into(),
            );
        }
        Ok(())
    }

    /// Grains kept beyond the reach (the margin grain, and a little room): the default `pad`.
    pub const DEFAULT_PAD: usize = 8;

    /// The default: [`Horizon::speed_bound`] and [`Horizon::DEFAULT_PAD`].
    pub const DEFAULT: Horizon = Horizon {
        speed: None,
        pad: Horizon::DEFAULT_PAD,
        unsafe_speed: false,
    };

    /// Why a horizon speed `speed` below the run's bound `bound` ([`Horizon::speed_bound`]) is
    /// refused, if it is below: the one message of the scene check (under key
    /// `run.horizon.speed`) and of the run ([`RunError::Settings`]).
    pub fn refusal(speed: f64, bound: f64) -> Option<String> {
        let (speed, bound, below) = (Num(speed), Num(bound), speed < bound);
        below.then(|| {
            format!(
                "{speed} is below this run's bound of {bound} grains per time unit (the fastest \
                 sound speed its energy allows outside the recorded ranges): the horizon would \
                 drop grains whose influence can reach a recorded range before the end, and the \
                 recorded numbers would differ from the run without it; leave `speed` out to use \
                 the bound, or set `unsafe = true` to run anyway"
            )
        })
    }

    /// The warning of a run that goes ahead with `speed` below `bound` (`unsafe_speed`), if it
    /// is below: the scene check's and the run's ([`RunSummary::warnings`]).
    pub fn warning(speed: f64, bound: f64) -> Option<String> {
        let (speed, bound, below) = (Num(speed), Num(bound), speed < bound);
        below.then(|| {
            format!(
                "run.horizon.speed = {speed} is below this run's bound of {bound} grains per time \
                 unit (run.horizon.unsafe = true): the recorded numbers may differ from the run \
                 without a horizon"
            )
        })
    }

    /// An upper bound on how fast a disturbance crosses the grains outside `lo..hi` (internal
    /// indices) of a chain holding energy `energy`, in grains per time unit: the largest
    /// `sqrt(k / m)` over the contacts with both grains outside, `m` the lighter grain and `k`
    /// the contact's stiffness `p eta delta^(p-1)` at the largest overlap the energy allows
    /// (`eta delta^(p+1) / (p+1) = energy`, plus the precompression). The long-wave sound speed
    /// of a chain is `sqrt(k / m)` grains per time unit, and no contact can be stiffer than
    /// this. Zero when no contact lies outside.
    pub fn speed_bound(chain: &Chain, energy: f64, lo: usize, hi: usize) -> f64 {
        let n = chain.len();
        let m = chain.mass();
        let mut best: f64 = 0.0;
        for k in 1..n {
            // Grains k - 1 and k both outside lo..hi.
            if (lo..hi).contains(&(k - 1)) || (lo..hi).contains(&k) {
                continue;
            }
            let Some(law) = chain.contact_law(k) else {
                continue;
            };
            let stiffness = if law.tension || law.p == 1.0 {
                law.eta
            } else {
                let reach = ((law.p + 1.0) * energy.abs() / law.eta).powf(1.0 / (law.p + 1.0));
                law.p * law.eta * (law.delta0 + reach).powf(law.p - 1.0)
            };
            best = best.max((stiffness / m[k - 1].min(m[k])).sqrt());
        }
        best
    }
}

/// A protected grain range, `[lo, hi)`, needed up to output `until`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Target {
    lo: usize,
    hi: usize,
    until: u64,
}

/// What the output callback sees at each output time.
pub struct Frame<'a> {
    /// Output index: 0 is the initial state, k is t = k * interval.
    pub index: u64,
    /// The chain being integrated.
    pub chain: &'a Chain,
    /// The state at this output: `state.t` is the output time; `u` and `v` are indexed by
    /// internal grain index.
    pub state: &'a State,
    /// The active window: the islands of integrated grains and the grains ever touched.
    pub window: &'a Window,
    /// Work counters of the run so far (steps, evaluations, what sleep and damping took out).
    pub stats: &'a Stats,
    /// Totals (computed for the blow-up check anyway).
    pub totals: Totals,
    /// Largest |v| of each grain (indexed like `state.v`) over every step since the previous
    /// output, both output instants included; `None` unless
    /// [`Simulation::watch_peak_speeds`] switched it on.
    pub peak_speed: Option<&'a [f64]>,
    /// The watched contact's force now and its peak and impulse so far; `None` unless
    /// [`Simulation::watch_load`] switched the watch on.
    pub load: Option<crate::LoadSample>,
}

/// A chain, its state, an integrator and a schedule of output times.
pub struct Simulation {
    chain: Chain,
    state: State,
    params: IntegrationParams,
    win: Window,
    stats: Stats,
    timings: Timings,
    integrator: Box<dyn Integrator + Send>,
    interval: f64,
    outputs: u64,
    e0: f64,
    p0: f64,
    max_energy_error: f64,
    max_momentum_error: f64,
    done: u64,
    started: bool,
    /// Scratch: which grains of the envelope are at rest (reused at every output time).
    rest_mask: Vec<bool>,
    /// The step asked for (`params.dt` is the step taken).
    requested_dt: f64,
    /// The causal horizon, and the ranges it protects.
    horizon: Option<Horizon>,
    targets: Vec<Target>,
    /// The horizon's speed, once the targets are known (its bound depends on them).
    horizon_speed: Option<f64>,
    /// The horizon's bound ([`Horizon::speed_bound`]), computed with `horizon_speed`.
    horizon_bound: Option<f64>,
    /// [`RunSummary::warnings`].
    warnings: Vec<String>,
    /// The energy of the resting contacts outside the window, kept between checks.
    totals_cache: observables::TotalsCache,
    /// Under gravity, the rounding the energy totals may carry (`4 eps` times the static
    /// state's elastic energy, [`Chain::static_energy`]): the energy check counts only the error
    /// beyond it. 0 without gravity.
    energy_floor: f64,
    /// The grains moving at the start (in grain order), with their velocity then. While a grain's velocity is
    /// still exactly that, no force has acted on it and its energy is unchanged: the energy
    /// check leaves it out of the scale it measures the error against (`check`).
    drifting: Vec<(usize, f64)>,
}

/// Builds a [`Simulation`].
pub struct SimulationBuilder {
    chain: Chain,
    params: IntegrationParams,
    duration: f64,
    interval: f64,
    /// (internal grain index, displacement, velocity)
    initial: Vec<(usize, Option<f64>, Option<f64>)>,
    horizon: Option<Horizon>,
    /// The settings were checked by [`check_settings`] ([`SimulationBuilder::checked`]).
    checked: bool,
}

/// The run's settings, checked against each other and against the chain: the schedule
/// ([`validate_schedule`]), the integration parameters ([`IntegrationParams::validate`]), the
/// horizon ([`Horizon::validate`]), gravity and damping against the method. The one place these
/// rules are applied together: [`SimulationBuilder::build`] refuses a run with the error, a
/// scene's check and its edits ([`crate::Scene::set_params`] and the others) put it under its
/// scene key (the error's key).
pub(crate) fn check_settings(
    chain: &Chain,
    params: &IntegrationParams,
    duration: f64,
    interval: f64,
    horizon: Option<&Horizon>,
) -> Result<(), integrators::ParamsError> {
    validate_schedule(duration, interval)?;
    params.validate(interval, Some(chain.len()))?;
    if let Some(h) = horizon {
        h.validate(params)?;
    }
    if chain.gravity() != 0.0 {
        gravity_settings(params, horizon.is_some()).map_err(|why| integrators::ParamsError {
            key: "chain.gravity",
            message: why,
        })?;
    }
    let damped = chain.has_contact_damping() || chain.sections().iter().any(|s| s.damping != 0.0);
    if damped && !params.method.information().damping {
        return Err(integrators::ParamsError {
            key: "integrator.method",
            message: format!(
                "damping needs a splitting method ({}), not {}",
                crate::Method::names_with(|i| i.damping, "or"),
                params.method.name()
            ),
        });
    }
    Ok(())
}

impl SimulationBuilder {
    /// A simulation of `chain`, at rest but for a striker's velocity, with the default
    /// [`IntegrationParams`] and 1 time unit of run with outputs every 0.125.
    pub fn new(chain: Chain) -> Self {
        SimulationBuilder {
            chain,
            params: IntegrationParams::default(),
            duration: 1.0,
            interval: 0.125,
            initial: Vec::new(),
            horizon: None,
            checked: false,
        }
    }

    /// Settings already checked against this chain by [`check_settings`] and kept valid since
    /// (a [`crate::Scene`]'s, which checks every edit): [`SimulationBuilder::build`] does not
    /// check them again.
    pub(crate) fn checked(mut self) -> Self {
        self.checked = true;
        self
    }

    /// Integrate with `p` (method, step, tolerances, sleep rule, ...); `p.dt` is the step asked
    /// for, which [`SimulationBuilder::build`] shortens for fixed-step methods so a whole number
    /// of steps fits each output interval.
    pub fn params(mut self, p: IntegrationParams) -> Self {
        self.params = p;
        self
    }

    /// Total simulated time and spacing of output times.
    pub fn schedule(mut self, duration: f64, interval: f64) -> Self {
        self.duration = duration;
        self.interval = interval;
        self
    }

    /// Run under a causal horizon ([`Horizon`]; it acts on the ranges protected with
    /// [`Simulation::protect`] or by a [`crate::recorder::Recorder`]). Errors at
    /// [`SimulationBuilder::build`]: a speed that is not a finite number > 0, a method without
    /// a fixed step and margin reset ([`crate::integrators::MethodInfo::horizon`]), `skip_untouched` off.
    pub fn horizon(mut self, h: Option<Horizon>) -> Self {
        self.horizon = h;
        self
    }

    /// Give grain `i` (internal index) a velocity.
    pub fn velocity(mut self, i: usize, v: f64) -> Self {
        self.initial.push((i, None, Some(v)));
        self
    }

    /// Give grain `i` (internal index) a displacement.
    pub fn displacement(mut self, i: usize, u: f64) -> Self {
        self.initial.push((i, Some(u), None));
        self
    }

    /// Check the settings and set up the state at t = 0: every grain at rest, a striker at its
    /// velocity, then the displacements and velocities given (a later one for the same grain
    /// wins). Errors ([`RunError::Settings`]): a duration or output interval that is not a finite
    /// number > 0, an interval longer than the duration, what
    /// [`IntegrationParams::validate`] refuses (the message starts with the setting's scene key),
    /// a grain index outside the chain, a non-finite initial state.
    pub fn build(self) -> Result<Simulation, RunError> {
        let SimulationBuilder {
            chain,
            mut params,
            duration,
            interval,
            initial,
            horizon,
            checked,
        } = self;
        if checked {
            // A scene's settings: its check applied these rules under their keys.
            debug_assert_eq!(
                check_settings(&chain, &params, duration, interval, horizon.as_ref()),
                Ok(())
            );
        } else {
            check_settings(&chain, &params, duration, interval, horizon.as_ref())
                .map_err(|e| RunError::Settings(e.to_string()))?;
        }
        let requested_dt = params.dt;
        params.dt = params.fitted_step(interval);
        let outputs = output_count(duration, interval);
        let n = chain.len();
        let (state, mut win) = initial_state(&chain, &params, &initial)?;
        win.set_wake_force(params.sleep.map_or(0.0, |s| s.force));
        let integrator = integrators::make(&params, n);
        let t0 = observables::totals(&chain, &state, &win);
        // Each contact's energy is `V(delta0 + du) - V(delta0)`: its two terms are rounded at
        // the scale of the static energy, which under gravity grows with the depth (a column of
        // 1e5 grains holds 1e10 times the energy of a weak kick), so the totals carry an
        // absolute rounding of a few eps of it. Precompressed chains without gravity keep the
        // check as it was (their static energy is bounded by the walls' force).
        let energy_floor = if chain.gravity() != 0.0 {
            4.0 * f64::EPSILON * chain.static_energy()
        } else {
            0.0
        };
        let drifting = state
            .v
            .iter()
            .enumerate()
            .filter(|&(_, &v)| v != 0.0)
            .map(|(i, &v)| (i, v))
            .collect();
        Ok(Simulation {
            energy_floor,
            drifting,
            chain,
            state,
            params,
            win,
            stats: Stats::default(),
            timings: Timings::default(),
            integrator,
            interval,
            outputs,
            e0: t0.total,
            p0: t0.momentum,
            max_energy_error: 0.0,
            max_momentum_error: 0.0,
            done: 0,
            started: false,
            rest_mask: Vec::new(),
            requested_dt,
            horizon,
            targets: Vec::new(),
            horizon_speed: None,
            horizon_bound: None,
            warnings: Vec::new(),
            totals_cache: observables::TotalsCache::default(),
        })
    }
}

/// Why a run under gravity cannot have these settings, if it cannot (the scene check reports it
/// under `chain.gravity`, [`SimulationBuilder::build`] as [`RunError::Settings`]): a
/// method without gravity ([`crate::integrators::MethodInfo::gravity`]), a sleep rule (it puts
/// grains at rest, which under gravity is no fixed point), a causal horizon (it holds grains
/// still outside its reach).
pub(crate) fn gravity_settings(params: &IntegrationParams, horizon: bool) -> Result<(), String> {
    if !params.method.information().gravity {
        return Err(format!(
            "needs a splitting method ({}), not {}: gravity is one more flow of \
             their splitting, not implemented in the others",
            crate::Method::names_with(|i| i.gravity, "or"),
            params.method.name()
        ));
    }
    if params.sleep.is_some() {
        return Err("not with a sleep rule (integrator.sleep): under gravity a \
                    grain at rest is not a fixed point"
            .into());
    }
    if horizon {
        return Err("not with a causal horizon (run.horizon): it holds grains \
                    still, which under gravity is not their motion"
            .into());
    }
    Ok(())
}

/// The state at t = 0 and the window seeded from it: every grain at rest, a striker at its
/// velocity, then `initial`'s displacements and velocities (internal index; a later one for the
/// same grain wins). The one construction [`SimulationBuilder::build`] and [`initial_energy`]
/// share.
fn initial_state(
    chain: &Chain,
    params: &IntegrationParams,
    initial: &[(usize, Option<f64>, Option<f64>)],
) -> Result<(State, Window), RunError> {
    let n = chain.len();
    let mut state = State::at_rest(n);
    if chain.has_contact_damping() {
        state.dissipated = vec![0.0; n];
    }
    if let Some((i, v)) = chain.striker() {
        state.v[i] = v;
    }
    for &(i, u, v) in initial {
        if i >= n {
            return Err(RunError::Settings(format!(
                "grain index {i} is outside the chain of {n} grains"
            )));
        }
        if let Some(u) = u {
            state.u[i] = u;
        }
        if let Some(v) = v {
            state.v[i] = v;
        }
    }
    if let Some(i) = state.first_non_finite(0..n) {
        return Err(RunError::Settings(format!(
            "initial state of grain {} is not finite",
            chain.grain_number(i)
        )));
    }
    let islands = params.method.uses_islands();
    // Under gravity no grain is at rest: the window is the whole chain from the start.
    let skip = params.skip_untouched && chain.gravity() == 0.0;
    let win = Window::seed(chain, &state.u, &state.v, skip, islands);
    Ok((state, win))
}

/// The total energy at t = 0 of the simulation [`SimulationBuilder`] would build from `chain`,
/// `params` and `initial` (internal indices): [`Simulation::initial_energy`], bit for bit, without
/// building it (the scene check compares a horizon's speed with [`Horizon::speed_bound`] of this
/// energy before anything runs).
pub fn initial_energy(
    chain: &Chain,
    params: &IntegrationParams,
    initial: &[(usize, Option<f64>, Option<f64>)],
) -> Result<f64, RunError> {
    let (state, win) = initial_state(chain, params, initial)?;
    Ok(observables::totals(chain, &state, &win).total)
}

impl Simulation {
    /// The chain.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }
    /// The current state (at the last output handed over, or the initial state): `t`, and `u`
    /// and `v` by internal grain index.
    pub fn state(&self) -> &State {
        &self.state
    }
    /// The active window: the islands of integrated grains and the grains ever touched.
    pub fn window(&self) -> &Window {
        &self.win
    }
    /// Work counters so far: steps, force and grain evaluations, window sizes, and what sleep
    /// and damping took out.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }
    /// Wall time spent so far in integration, checks and output.
    pub fn timings(&self) -> &Timings {
        &self.timings
    }
    /// Parameters as used (fixed-step dt shortened to divide the output interval).
    pub fn params(&self) -> &IntegrationParams {
        &self.params
    }
    /// The step asked for; [`Simulation::params`] holds the step taken (shortened for fixed-step
    /// methods so a whole number of steps fits each output interval).
    pub fn requested_dt(&self) -> f64 {
        self.requested_dt
    }
    /// Time between outputs: output `k` is at `k * output_interval()`.
    pub fn output_interval(&self) -> f64 {
        self.interval
    }
    /// Number of output times after the initial one.
    pub fn outputs(&self) -> u64 {
        self.outputs
    }
    /// Energy at t = 0.
    pub fn initial_energy(&self) -> f64 {
        self.e0
    }
    /// Largest relative energy error seen at an output time.
    pub fn max_energy_error(&self) -> f64 {
        self.max_energy_error
    }
    /// Largest momentum change seen at an output time, relative to the initial momentum (or
    /// absolute when that is zero). Meaningful for free ends only: walls exchange momentum.
    pub fn max_momentum_error(&self) -> f64 {
        self.max_momentum_error
    }

    /// The bookkeeping of the run so far.
    pub fn summary(&self) -> RunSummary {
        RunSummary {
            method: self.params.method.name(),
            requested_dt: self.requested_dt,
            dt: self.params.dt,
            grains: self.chain.len(),
            outputs: self.outputs,
            time: self.state.t,
            stats: self.stats,
            timings: self.timings,
            ever: (self.win.ever_lo, self.win.ever_hi),
            islands: self.win.islands().len(),
            initial_energy: self.e0,
            max_energy_error: self.max_energy_error,
            max_momentum_error: self.max_momentum_error,
            horizon_speed: self.horizon_speed,
            horizon_bound: self.horizon_bound,
            warnings: self.warnings.clone(),
        }
    }

    /// The causal horizon, if the run has one.
    pub fn horizon(&self) -> Option<Horizon> {
        self.horizon
    }

    /// The speed the horizon uses (grains per time unit): the one set, or
    /// [`Horizon::speed_bound`] outside the protected ranges, once the run has started with
    /// something protected.
    pub fn horizon_speed(&self) -> Option<f64> {
        self.horizon_speed
    }

    /// The horizon's bound, [`Horizon::speed_bound`] outside the protected ranges at the
    /// initial energy, once the run has started with something protected.
    pub fn horizon_bound(&self) -> Option<f64> {
        self.horizon_bound
    }

    /// Protect grains `first..=last` (internal indices) up to output `until` from the causal
    /// horizon ([`Horizon`]): the grains from which a disturbance could reach them by then stay
    /// integrated. Without a horizon this does nothing; with one and nothing protected, nothing
    /// is dropped.
    pub fn protect(&mut self, first: usize, last: usize, until: u64) {
        let n = self.chain.len();
        if first <= last && first < n {
            self.targets.push(Target {
                lo: first,
                hi: (last + 1).min(n),
                until: until.min(self.outputs),
            });
        }
    }

    /// Drop every grain outside `lo..hi` (internal indices) from the integration from now on:
    /// the horizon's one operation ([`Horizon`]), public so that a measurement can cut a chain
    /// at a chosen distance and time (`examples/back_signal.rs`). Each dropped grain's velocity
    /// is set to zero and its kinetic energy counted in [`Stats::dropped_energy`]. Returns the
    /// number of grains dropped.
    pub fn drop_outside(&mut self, lo: usize, hi: usize) -> usize {
        let (v, m) = (&mut self.state.v, &self.chain.mass);
        let mut energy = 0.0;
        let n = self.win.clip(lo, hi, |i| {
            energy += 0.5 * m[i] * v[i] * v[i];
            v[i] = 0.0;
        });
        self.stats.dropped_grains += n as u64;
        self.stats.dropped_energy += energy;
        n
    }

    /// The horizon at output `k`: keep the reach of every range still protected (and a
    /// multirate fast region), drop the rest. At the first output with something protected the
    /// speed is fixed: the one set, refused below the bound unless `unsafe_speed` (then a
    /// warning), or the bound.
    fn apply_horizon(&mut self, k: u64) -> Result<(), RunError> {
        let Some(h) = self.horizon else {
            return Ok(());
        };
        if self.targets.is_empty() {
            return Ok(());
        }
        let speed = match self.horizon_speed {
            Some(x) => x,
            None => {
                let lo = self.targets.iter().map(|t| t.lo).min().unwrap_or(0);
                let hi = self.targets.iter().map(|t| t.hi).max().unwrap_or(0);
                let bound = Horizon::speed_bound(&self.chain, self.e0, lo, hi);
                self.horizon_bound = Some(bound);
                let x = h.speed.unwrap_or(bound);
                if h.unsafe_speed {
                    self.warnings.extend(Horizon::warning(x, bound));
                } else if let Some(why) = Horizon::refusal(x, bound) {
                    return Err(RunError::Settings(format!("run.horizon.speed: {why}")));
                }
                self.horizon_speed = Some(x);
                x
            }
        };
        let (mut lo, mut hi) = (usize::MAX, 0);
        for t in &self.targets {
            let left = t.until.saturating_sub(k);
            let reach = (speed * left as f64 * self.interval).ceil();
            // A reach beyond the chain keeps everything (and avoids a float-to-int overflow).
            let reach = if reach < self.chain.len() as f64 {
                reach as usize + h.pad
            } else {
                self.chain.len()
            };
            lo = lo.min(t.lo.saturating_sub(reach));
            hi = hi.max(t.hi.saturating_add(reach));
        }
        if let (crate::Method::Multirate, Some(m)) = (self.params.method, self.params.multirate) {
            lo = lo.min(m.first);
            hi = hi.max(m.last + 1);
        }
        self.drop_outside(lo, hi);
        Ok(())
    }

    /// Keep, from now on, the largest |v| of each grain over every step between outputs, and hand
    /// it to the output callback ([`Frame::peak_speed`]). It reads the velocities only, so the
    /// run is the same bit for bit. Errors for a method that keeps no per-step velocities
    /// (gear5, multirate).
    pub fn watch_peak_speeds(&mut self) -> Result<(), RunError> {
        let method = self.params.method;
        match self.integrator.peak_speeds() {
            Some(p) => {
                p.start(&self.state.v);
                Ok(())
            }
            None => Err(RunError::Settings(format!(
                "peak speeds between outputs need per-step velocities, which {} keep and {} \
                 does not",
                crate::Method::names_with(|i| i.tracks, "and"),
                method.name()
            ))),
        }
    }

    /// Watch the force of contact `contact` (`0..=n`; `n` is the right wall's) after every
    /// step from now on: its true peak and when, the impulse, the time at or above `fraction`
    /// of the peak, and the target's energy when the contact is the last one into the chain's
    /// last grain and that grain is `target` ([`Simulation::load`]). It reads the state only,
    /// so the run is the same bit for bit. Errors: a method without whole steps (gear5,
    /// dopri5, multirate), a run with a causal horizon (it stops integrating grains the watch
    /// may need), a contact that does not exist, a fraction outside `(0, 1]`.
    pub fn watch_load(
        &mut self,
        contact: usize,
        fraction: f64,
        target: bool,
    ) -> Result<(), RunError> {
        let n = self.chain.len();
        if self.chain.contact_law(contact).is_none() {
            return Err(RunError::Settings(format!(
                "the load on contact {contact}: there is no contact there (contacts 0..={n}, \
                 0 and {n} only with walls)"
            )));
        }
        if !(fraction > 0.0 && fraction <= 1.0) {
            return Err(RunError::Settings(format!(
                "the load's duration is counted above a fraction of its peak in (0, 1], got \
                 {fraction}"
            )));
        }
        if self.horizon.is_some() {
            return Err(RunError::Settings(
                "the load on a contact needs every grain integrated to the end, which the \
                 causal horizon does not do: leave out `run.horizon`"
                    .into(),
            ));
        }
        let method = self.params.method;
        let dt = self.params.dt;
        match self.integrator.load_watch() {
            Some(w) => {
                w.start(
                    &self.chain,
                    &self.state,
                    dt,
                    contact,
                    fraction,
                    target && contact + 1 == n,
                );
                w.locate_peak(self.params.events);
                Ok(())
            }
            None => Err(RunError::Settings(format!(
                "the load on a contact is watched after every whole step, which verlet and \
                 blanes-moan4 take and {} does not",
                method.name()
            ))),
        }
    }

    /// Count reflections at the two edges of grains `first..=last` (internal indices; a
    /// container) after every step from now on ([`ReflectionRule`](crate::ReflectionRule): the
    /// hits of pulses on each edge contact, each with its incident and transmitted energy;
    /// [`Simulation::take_reflections`]). It reads the state only, so the run is the same bit for
    /// bit. Errors: a stretch outside the chain or shorter than the rule's zone, a bad rule, a
    /// method without whole steps (gear5, dopri5), a multirate run whose fast region does not
    /// hold the stretch and the grain beyond each edge. Under a causal horizon the stretch and
    /// the grain beyond each edge are protected to the end.
    pub fn watch_reflections(
        &mut self,
        first: usize,
        last: usize,
        rule: crate::ReflectionRule,
    ) -> Result<(), RunError> {
        let n = self.chain.len();
        rule.check()
            .map_err(|e| RunError::Settings(format!("reflections: {e}")))?;
        if first > last || last >= n {
            return Err(RunError::Settings(format!(
                "reflections: the stretch {first}..={last} is not inside the chain of {n} grains"
            )));
        }
        if last + 1 - first < rule.zone {
            return Err(RunError::Settings(format!(
                "reflections: the stretch {first}..={last} is shorter than the zone of {} grains",
                rule.zone
            )));
        }
        let (lo, hi) = (first.saturating_sub(1), (last + 1).min(n - 1));
        if let (crate::Method::Multirate, Some(m)) = (self.params.method, self.params.multirate) {
            if lo < m.first || hi > m.last {
                return Err(RunError::Settings(format!(
                    "reflections: multirate counts them in its fast region ({}..={}), which \
                     must hold the stretch and the grain beyond each edge ({lo}..={hi})",
                    m.first, m.last
                )));
            }
        }
        self.protect(lo, hi, self.outputs);
        let method = self.params.method;
        let dt = self.params.dt;
        match self.integrator.reflection_watch() {
            Some(w) => {
                w.start(&self.chain, &self.state, dt, first, last, rule);
                Ok(())
            }
            None => Err(RunError::Settings(format!(
                "reflections are counted after every whole step, which verlet, blanes-moan4 and \
                 multirate take and {} does not",
                method.name()
            ))),
        }
    }

    /// The reflections [`Simulation::watch_reflections`] counted so far (hits that have ended),
    /// taken: a later call returns only those found since. Empty unless it was switched on.
    pub fn take_reflections(&mut self) -> Vec<crate::Reflection> {
        self.integrator
            .reflection_watch()
            .map(|w| w.take())
            .unwrap_or_default()
    }

    /// The hits [`Simulation::watch_reflections`] counted, those still going on ended now (at
    /// the end of a run: the hits then hold all the work through the edges), taken.
    pub fn end_reflections(&mut self) -> Vec<crate::Reflection> {
        self.integrator
            .reflection_watch()
            .map(|w| w.end())
            .unwrap_or_default()
    }

    /// The work sent through the watched edges so far ([`Simulation::watch_reflections`];
    /// `None` unless it was switched on).
    pub fn edge_work(&mut self) -> Option<crate::EdgeWork> {
        self.integrator
            .reflection_watch()
            .filter(|w| w.is_on())
            .map(|w| w.work())
    }

    /// What [`Simulation::watch_load`] found so far (`None` unless it was switched on).
    pub fn load(&mut self) -> Option<crate::Load> {
        self.integrator
            .load_watch()
            .filter(|w| w.is_on())
            .map(|w| w.load())
    }

    /// Run to the end, calling `on_output` at t = 0 and at every output time.
    pub fn run<E: From<RunError>>(
        &mut self,
        mut on_output: impl FnMut(&Frame) -> Result<(), E>,
    ) -> Result<(), E> {
        self.drive(&mut |fr: &Frame| on_output(fr).map(|()| ControlFlow::Continue(())))
            .map(|_| ())
    }

    /// Run until the end, or until `on_output` returns [`ControlFlow::Break`] (e.g. when the
    /// energy left in a region has fallen below a level). Returns `true` if the run reached its
    /// end. A later call goes on from where it stopped.
    ///
    /// ```
    /// use grainchain_engine::SimulationBuilder;
    /// use std::ops::ControlFlow;
    /// use grainchain_engine::{ChainBuilder, ContactLaw};
    ///
    /// let chain = ChainBuilder::new().grains(100, 1.0, ContactLaw::hertz(5657.0)).build()?;
    /// let mut sim = SimulationBuilder::new(chain).schedule(10.0, 0.125).velocity(0, 1.0).build()?;
    /// // Stop as soon as grain 50 moves.
    /// let finished = sim.run_until(|fr| {
    ///     if fr.state.v[50] != 0.0 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
    /// })?;
    /// assert!(!finished && sim.state().t < 10.0);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn run_until(
        &mut self,
        mut on_output: impl FnMut(&Frame) -> ControlFlow<()>,
    ) -> Result<bool, RunError> {
        self.drive(&mut |fr: &Frame| Ok::<_, RunError>(on_output(fr)))
    }

    /// The run loop: integrate output interval by output interval, check, split islands, and
    /// hand every output to `on_output` until it breaks or the run ends (`Ok(true)`).
    fn drive<E: From<RunError>>(
        &mut self,
        on_output: &mut dyn FnMut(&Frame) -> Result<ControlFlow<()>, E>,
    ) -> Result<bool, E> {
        if !self.started {
            self.integrator
                .init(&self.chain, &self.state, &mut self.win, &mut self.stats);
            self.started = true;
            let totals = observables::totals(&self.chain, &self.state, &self.win);
            self.apply_horizon(0)?;
            if self.emit(0, totals, on_output)?.is_break() {
                return Ok(false);
            }
        }
        while self.done < self.outputs {
            let k = self.done + 1;
            let t_end = k as f64 * self.interval;
            let t = Instant::now();
            self.integrator
                .advance_to(
                    &self.chain,
                    &mut self.state,
                    &mut self.win,
                    t_end,
                    &mut self.stats,
                )
                .map_err(RunError::from)?;
            self.timings.integrate += t.elapsed();
            let t = Instant::now();
            let totals = self.check()?;
            // Under gravity no grain is at rest: the window stays the whole chain.
            if self.params.method.uses_islands() && self.chain.gravity() == 0.0 {
                self.split_islands();
            }
            self.apply_horizon(k)?;
            self.timings.checks += t.elapsed();
            self.done = k;
            if self.emit(k, totals, on_output)?.is_break() {
                return Ok(self.done == self.outputs);
            }
        }
        Ok(true)
    }

    fn emit<E>(
        &mut self,
        index: u64,
        totals: Totals,
        on_output: &mut dyn FnMut(&Frame) -> Result<ControlFlow<()>, E>,
    ) -> Result<ControlFlow<()>, E> {
        let t = Instant::now();
        let load = self
            .integrator
            .load_watch()
            .filter(|w| w.is_on())
            .map(|w| w.sample());
        let peaks = self.integrator.peak_speeds().filter(|p| p.is_on());
        let frame = Frame {
            index,
            chain: &self.chain,
            state: &self.state,
            window: &self.win,
            stats: &self.stats,
            totals,
            peak_speed: peaks.as_ref().map(|p| p.max()),
            load,
        };
        let r = on_output(&frame);
        // The next interval starts at this output's speeds.
        if let Some(p) = peaks {
            p.reset(&self.state.v, self.win.ever());
        }
        self.timings.output += t.elapsed();
        r
    }

    /// Energy and momentum bookkeeping; the energy bound is the blow-up detector of last resort.
    fn check(&mut self) -> Result<Totals, RunError> {
        // Before the islands split and the horizon drops: the envelope is the widest it was
        // since the last check, which is what the cache's validity rests on.
        let tot = self
            .totals_cache
            .totals(&self.chain, &self.state, &self.win);
        // Energy and momentum taken out by damped sections and the sleep rule are part of the
        // budget: what is conserved is what is in the chain plus what left it.
        let st = &self.stats;
        let e = tot.total
            + st.absorbed_energy
            + st.slept_energy
            + st.dropped_energy
            + st.dissipated_energy;
        let p = tot.momentum + st.absorbed_momentum;
        // Beyond the rounding of the totals under gravity (`energy_floor`, 0 without).
        let mut err = (e - self.e0).abs();
        if self.energy_floor > 0.0 {
            err = (err - self.energy_floor).max(0.0);
        }
        // The scale: the initial energy less that of the grains still in the free flight they
        // started in (their energy is exact; a 1e12-mass grain drifting away beside a light
        // chain made the light chain's blow-up, 2.2e8 from 0.5, an error of 4e-4: issue 38).
        // At least a millionth of the initial energy: a striker before its impact may hold all
        // of it, and nothing has moved yet to compare with.
        let m = self.chain.mass();
        let idle: f64 = self
            .drifting
            .iter()
            .filter(|&&(i, v0)| self.state.v[i] == v0)
            .map(|&(i, v0)| 0.5 * m[i] * v0 * v0)
            .sum();
        let scale = (self.e0.abs() - idle).max(1e-6 * self.e0.abs());
        let rel = if self.e0 != 0.0 { err / scale } else { err };
        let prel = if self.p0 != 0.0 {
            (p - self.p0).abs() / self.p0.abs()
        } else {
            p.abs()
        };
        self.max_momentum_error = self.max_momentum_error.max(prel);
        if rel.is_nan() || rel > self.params.max_energy_error {
            let mut grain = self.win.lo;
            let mut best = -1.0;
            // The largest energy among the grains a force has acted on (not a drifting one;
            // `drifting` is in grain order).
            let idle = |i: usize| {
                self.drifting
                    .binary_search_by_key(&i, |&(j, _)| j)
                    .is_ok_and(|k| self.state.v[i] == self.drifting[k].1)
            };
            for i in self.win.range().filter(|&i| !idle(i)) {
                let e = observables::grain_energy(&self.chain, &self.state, i);
                if !(e <= best) {
                    best = e;
                    grain = i;
                }
            }
            return Err(RunError::EnergyDrift {
                time: self.state.t,
                step: self.stats.steps,
                rel,
                bound: self.params.max_energy_error,
                grain: self.chain.grain_number(grain),
            });
        }
        self.max_energy_error = self.max_energy_error.max(rel);
        Ok(tot)
    }

    /// Take the grains at rest out of the islands: under the exact rule (no sleep rule) those
    /// whose velocity and net force are exactly zero; under a [`Sleep`](crate::integrators::Sleep) rule those within its
    /// thresholds, whose velocity is then set to zero. Grains that stay in an island (a stretch
    /// too short to split off) keep their velocity.
    fn split_islands(&mut self) {
        let (lo, hi) = (self.win.lo, self.win.hi);
        let sleep = self.params.sleep;
        let (chain, state) = (&self.chain, &self.state);
        self.rest_mask.clear();
        // The velocity test first: it is cheap and almost always decides.
        self.rest_mask.extend((lo..hi).map(|i| {
            let v = state.v[i];
            match sleep {
                None => v == 0.0 && chain.net_force(&state.u, i) == 0.0,
                Some(s) => v.abs() <= s.velocity && chain.net_force(&state.u, i).abs() <= s.force,
            }
        }));
        let mask = &self.rest_mask;
        let (v, m) = (&mut self.state.v, &chain.mass);
        let mut energy = 0.0;
        let taken = self.win.split_at_rest(
            |i| mask[i - lo],
            |i| {
                energy += 0.5 * m[i] * v[i] * v[i];
                v[i] = 0.0;
            },
        );
        self.stats.slept_grains += taken as u64;
        self.stats.slept_energy += energy;
    }
}

/// The worker threads a batch of `jobs` independent runs gets when `asked` for: at least one,
/// at most one per job, and at most what the machine runs at once
/// (`std::thread::available_parallelism`, which counts the process's CPU affinity and quota):
/// more threads than that only add switching for work that computes all the time. The one rule
/// of every pool (studies, `reproduce`, `design`, `protector::evaluate_many`, Python's), whose
/// results never depend on it (issue 38: `design --threads 1000` started 1000 threads for a
/// 4-design search and took 20 times as long).
pub fn worker_threads(asked: usize, jobs: usize) -> usize {
    let machine = std::thread::available_parallelism().map_or(1, |n| n.get());
    asked.clamp(1, jobs.max(1)).min(machine)
}

/// A thread pool of [`worker_threads`]`(asked, jobs)` threads: the one place every pool of the
/// crate and the harness is built (studies, `reproduce`, the design search, its tolerances and
/// refinement, `protector::evaluate_many` and its kin).
pub fn thread_pool(
    asked: usize,
    jobs: usize,
) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(worker_threads(asked, jobs))
        .build()
}
