//! Time integrators: one small file per method, one trait, one parameters struct.
//!
//! | method | order | steps | force evaluations per step |
//! |---|---|---|---|
//! | [`Verlet`] | 2 | fixed | 1 |
//! | [`BlanesMoan4`] | 4 | fixed | 6 |
//! | [`Gear5`] | 5 on smooth forces (predictor-corrector, not symplectic) | fixed | 1 |
//! | [`Dopri5`] | 5(4), embedded error estimate | adaptive | 6 (FSAL) |
//! | [`Multirate`] | 2 in the slow step, 4 in the fast one | fixed, two rates | 6 per fast step on the fast region |
//!
//! The facts of each method (and the options it supports) are declared once, in
//! [`Method::information`]. The fixed-step methods implement [`FixedStep`] (their step block and
//! start-up) and get the rest of [`Integrator`] from it; [`IntegrationParams::validate`] is the
//! one check of the settings.
//!
//! Every method integrates only the active [`Window`]; grains outside it are exactly at rest and
//! stay bit-for-bit as they would be if they were integrated.

mod blanes_moan;
mod dopri5;
mod events;
mod fixed;
mod gear5;
mod load;
pub mod multirate;
mod params;
mod reflections;
pub(crate) mod simd;
mod splitting;
mod step;
pub mod step_control;
mod verlet;

pub use blanes_moan::BlanesMoan4;
pub use dopri5::Dopri5;
pub(crate) use events::Events;
pub use fixed::FixedStep;
pub use gear5::Gear5;
pub(crate) use load::{contact_force, Above, Parabola};
pub use load::{Load, LoadSample, LoadWatch};
pub use multirate::{Multirate, MultirateParams};
pub use params::{ParamsError, MAX_STEPS_PER_OUTPUT};
pub use reflections::{Edge, EdgeWork, Reflection, ReflectionRule, ReflectionWatch};
pub(crate) use splitting::{cut_at_events, whole, Cuts, Flows, Splitting};
pub use step::{Integrator, PeakSpeeds, Stats, StepError};
pub use verlet::Verlet;

pub(crate) use step::{
    check_finite, count_eval, damp, eval, fixed_steps, gravity_kick, kick, CHECK_EVERY,
};

use serde::{Deserialize, Serialize};

/// The integration methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Velocity Verlet: second order, symplectic, time-reversible.
    Verlet,
    /// Blanes & Moan (2002) optimized 6-stage symmetric symplectic RKN method of order 4.
    BlanesMoan4,
    /// Gear's fifth-order predictor-corrector (6 Nordsieck values, second-order ODE).
    Gear5,
    /// Dormand-Prince 5(4) with embedded error control.
    Dopri5,
    /// Multiple time stepping: Blanes-Moan 4 on a fast region (a container), velocity Verlet at
    /// a multiple of the step elsewhere (`multirate`, [`MultirateParams`]). Needs [`IntegrationParams::multirate`].
    Multirate,
}

/// The facts of one method, declared once in [`Method::information`]: what it is and which
/// options it supports. Every question about a method (the scene checks, the builder, the run
/// loop, the reports) is answered from here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodInfo {
    /// Name in scene files and on the command line.
    pub name: &'static str,
    /// Nominal order of the global error on smooth problems (multirate: in the slow step).
    pub order: u32,
    /// Adaptive step (takes `rtol`/`atol`); otherwise a fixed `dt`.
    pub adaptive: bool,
    /// Symplectic: no secular energy drift.
    pub symplectic: bool,
    /// Force evaluations of the window per step (multirate: per fast step on the fast region).
    pub evaluations_per_step: u32,
    /// Keeps the running maxima of |v| over every step (`PeakSpeeds`, `output.tracks`).
    pub tracks: bool,
    /// Accepts a [`Sleep`] rule.
    pub sleep: bool,
    /// Applies damping: of damped sections (absorbing layers) and of damped contacts (contact
    /// damping, carried by the damped drift: second order overall, `chain::damping`).
    pub damping: bool,
    /// Sweeps island by island, and the run splits its window into islands at output times.
    pub islands: bool,
    /// Takes [`MultirateParams`] (`integrator.multirate`).
    pub multirate: bool,
    /// Runs under a causal horizon ([`crate::run::Horizon`], `run.horizon`): a fixed step (an
    /// adaptive step would depend on the grains dropped) and margin grains reset to rest.
    pub horizon: bool,
    /// Applies gravity ([`crate::ChainBuilder::gravity`]): its kick is one more flow of the
    /// splitting (`integrators::gravity_kick`).
    pub gravity: bool,
    /// Cuts its steps at contact events ([`IntegrationParams::events`]): the instant a contact
    /// closes or opens is predicted inside the step, and each piece is a whole step
    /// (`integrators::events`).
    pub events: bool,
    /// Bytes per grain at the peak of a run with this method and no outputs, `[[initial]]` or
    /// damping: the larger of the chain's build (160 for every method) and the method's run
    /// (its state and workspace), measured and rounded up (BENCHMARKS.md, "Memory"); the scene's
    /// memory estimate starts from it.
    pub bytes_per_grain: u64,
}

impl Method {
    /// Every method, in the order of the table in [`Method::information`].
    pub const ALL: [Method; 5] = [
        Method::Verlet,
        Method::BlanesMoan4,
        Method::Gear5,
        Method::Dopri5,
        Method::Multirate,
    ];

    /// The four single-rate methods (multirate, which needs a fast region, is not among them).
    pub const SINGLE_RATE: [Method; 4] = [
        Method::Verlet,
        Method::BlanesMoan4,
        Method::Gear5,
        Method::Dopri5,
    ];

    /// The facts of the method: the one table of them.
    pub const fn information(self) -> MethodInfo {
        // Rows differ from this one only where they say so.
        const SPLITTING: MethodInfo = MethodInfo {
            name: "",
            order: 2,
            adaptive: false,
            symplectic: true,
            evaluations_per_step: 1,
            tracks: true,
            sleep: true,
            damping: true,
            islands: true,
            multirate: false,
            horizon: true,
            gravity: true,
            events: true,
            bytes_per_grain: 160,
        };
        match self {
            Method::Verlet => MethodInfo {
                name: "verlet",
                ..SPLITTING
            },
            Method::BlanesMoan4 => MethodInfo {
                name: "blanes-moan4",
                order: 4,
                evaluations_per_step: 6,
                ..SPLITTING
            },
            // Keeps no per-step velocities; one interval window.
            Method::Gear5 => MethodInfo {
                name: "gear5",
                order: 5,
                symplectic: false,
                tracks: false,
                sleep: false,
                damping: false,
                islands: false,
                horizon: false,
                gravity: false,
                events: false,
                // Five Nordsieck vectors, `a`, `f` and four start-up accelerations.
                bytes_per_grain: 220,
                ..SPLITTING
            },
            Method::Dopri5 => MethodInfo {
                name: "dopri5",
                order: 5,
                adaptive: true,
                symplectic: false,
                evaluations_per_step: 6,
                sleep: false,
                damping: false,
                islands: false,
                horizon: false,
                gravity: false,
                events: false,
                // Seven stages of `u` and `v`, the stage state and forces.
                bytes_per_grain: 235,
                ..SPLITTING
            },
            // Second order in the slow step (fourth in the fast one); no synchronized per-step
            // velocities for its slow grains; one interval window that holds the fast region.
            Method::Multirate => MethodInfo {
                name: "multirate",
                evaluations_per_step: 6,
                tracks: false,
                sleep: false,
                damping: false,
                islands: false,
                multirate: true,
                gravity: false,
                events: false,
                ..SPLITTING
            },
        }
    }

    /// The method's name as in scene files and on the command line (`verlet`, `blanes-moan4`,
    /// `gear5`, `dopri5`, `multirate`).
    pub fn name(self) -> &'static str {
        self.information().name
    }

    /// Nominal order of the global error on smooth problems.
    pub fn nominal_order(self) -> u32 {
        self.information().order
    }

    /// True for the method with an adaptive step (dopri5), which takes `rtol`/`atol` instead of
    /// a fixed `dt`.
    pub fn is_adaptive(self) -> bool {
        self.information().adaptive
    }

    /// True for the symplectic methods (verlet, blanes-moan4, multirate): no secular energy
    /// drift.
    pub fn is_symplectic(self) -> bool {
        self.information().symplectic
    }

    /// True for the methods whose sweeps run island by island (the fused splitting methods):
    /// only they split the window into islands, put grains to sleep or apply damping. The others
    /// integrate one interval, from the first grain ever disturbed to the last.
    pub fn uses_islands(self) -> bool {
        self.information().islands
    }

    /// The weights of a splitting method (verlet, blanes-moan4: [`Splitting`]), for a carrier
    /// other than a scene's run (a protector's derivatives); `None` for the others.
    pub(crate) fn splitting(self) -> Option<&'static Splitting> {
        match self {
            Method::Verlet => Some(&verlet::KDK),
            Method::BlanesMoan4 => Some(&blanes_moan::SRKN6B),
            Method::Gear5 | Method::Dopri5 | Method::Multirate => None,
        }
    }

    /// The names of the methods with `ability`, joined for a message: `verlet or blanes-moan4`
    /// (`conjunction` "or"), `verlet, blanes-moan4 and dopri5`.
    pub(crate) fn names_with(ability: impl Fn(&MethodInfo) -> bool, conjunction: &str) -> String {
        let names: Vec<&str> = Method::ALL
            .iter()
            .map(|m| m.information())
            .filter(|i| ability(i))
            .map(|i| i.name)
            .collect();
        match names.split_last() {
            None => String::new(),
            Some((last, [])) => last.to_string(),
            Some((last, rest)) => format!("{} {conjunction} {last}", rest.join(", ")),
        }
    }
}

/// Sleep rule: grains that have nearly come to rest leave the islands (approximate; off by
/// default).
///
/// At every output time, a grain whose speed is at most `velocity` and on which the net contact
/// force is at most `force` (in absolute value) is put to rest: its velocity is set to zero and,
/// where such grains form a stretch at the end of an island or a stretch of at least
/// `MIN_GAP` (3) grains inside one, they leave the islands. A resting grain ignores
/// net forces up to `force` and wakes, by the ordinary margin rule, when the net force on it
/// exceeds `force`. The error is the work of the ignored forces and the kinetic energy set to zero
/// (at most `m velocity^2 / 2` per grain put to rest; counted in [`Stats::slept_energy`]); the
/// validation suite measures its effect. Only the splitting methods (verlet, blanes-moan4), whose
/// sweeps run island by island, use it.
///
/// Without a sleep rule the same splitting happens under the exact rule: a grain leaves the
/// islands only when its velocity and the net force on it are exactly zero, which changes no bit
/// of the result.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sleep {
    /// Largest speed of a grain put to rest.
    pub velocity: f64,
    /// Largest net force on a grain put to rest; a resting grain wakes above it.
    pub force: f64,
}

/// Everything that controls integration, in one documented place.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct IntegrationParams {
    /// The method.
    pub method: Method,
    /// Step size of the fixed-step methods; the initial step of adaptive ones. Fixed-step runs
    /// shorten it so that a whole number of steps fits each output interval.
    pub dt: f64,
    /// Relative tolerance of adaptive methods.
    pub rtol: f64,
    /// Absolute tolerance of adaptive methods (applies to displacements and velocities).
    pub atol: f64,
    /// Skip grains that no disturbance has reached (exact; on by default).
    pub skip_untouched: bool,
    /// Optional sleep rule (approximate; off by default): see [`Sleep`].
    pub sleep: Option<Sleep>,
    /// Stop with an error when |E - E0| / E0 exceeds this at an output time.
    pub max_energy_error: f64,
    /// The fast region and step ratio of [`Method::Multirate`] (None for the other methods).
    pub multirate: Option<MultirateParams>,
    /// Cut each step where a contact closes or opens (`integrator.events`; off by default, when
    /// every run is bit for bit what it was before events existed): see [`MethodInfo::events`].
    pub events: bool,
}

impl Default for IntegrationParams {
    fn default() -> Self {
        IntegrationParams {
            method: Method::Verlet,
            dt: 1e-4,
            rtol: 1e-8,
            atol: 1e-10,
            skip_untouched: true,
            sleep: None,
            max_energy_error: 1e-2,
            multirate: None,
            events: false,
        }
    }
}

/// Build the integrator named in `params` for a chain of `n` grains.
pub fn make(params: &IntegrationParams, n: usize) -> Box<dyn Integrator + Send> {
    match params.method {
        Method::Verlet => Box::new(Verlet::new(params.dt, n).with_events(params.events)),
        Method::BlanesMoan4 => Box::new(BlanesMoan4::new(params.dt, n).with_events(params.events)),
        Method::Gear5 => Box::new(Gear5::new(params.dt, n)),
        Method::Dopri5 => Box::new(Dopri5::new(params.dt, params.rtol, params.atol, n)),
        Method::Multirate => Box::new(Multirate::new(params.dt, params.multirate, n)),
    }
}
