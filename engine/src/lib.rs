//! The engine of grainchain: one-dimensional granular chains with power-law contacts
//! (`m_n u''_n = F_{n-1} - F_n`, `F = eta delta^p`; Hong, PRL 94, 108001, 2005), their
//! integrators, observables and recorder, scene files, and the analysis of the remaining energy.
//! The command-line tool and its batch studies are the `grainchain` crate, built on this API
//! only. See `ARCHITECTURE.md` for the map.
//!
//! Every item is reachable at one path: the crate root for the simulation itself, and seven
//! namespaces for what is better read with its prefix: [`analysis`] (fits, bins, ensemble
//! statistics), [`file`](mod@file) (input files: the scene file's schema, its one parse and its
//! edits), [`format`](mod@format) (how numbers and sizes are written in messages), [`paper`] (the numbers
//! Hong states), [`problems`] (the catalogue of sample problems with reference values),
//! [`protector`] (designs in real materials and the load on what they protect) and [`units`]
//! (the SI scale).
//!
//! # A tour by task
//!
//! - **Run a scene file.** [`Scene::load`] reads and checks a scene (TOML; errors name the file
//!   and key), [`Scene::simulation`] builds its [`Simulation`], and [`Simulation::run`] calls
//!   back at every output time with a [`Frame`]. A checked scene stays valid: its edits
//!   ([`Scene::set_params`], [`Scene::set_schedule`], [`Scene::set_horizon`]) are checked again.
//!   What a scene will cost: [`Scene::estimate`], [`MemoryEstimate::of_run`].
//! - **Build a chain in code.** [`ChainBuilder`] lays out [`Section`]s of grains joined by a
//!   [`ContactLaw`] (with [`ContactDamping`], walls as [`End`]s, a [`Striker`]);
//!   [`SimulationBuilder`] adds the [`IntegrationParams`] (a [`Method`] and its facts in
//!   [`Method::information`]), the schedule, a causal [`Horizon`] and the initial state.
//! - **Record.** A [`Recorder`] says what to keep (regions, sections, snapshots of a
//!   [`Field`], probes, pulses, tracks) and runs the simulation into a [`Record`]; a [`Sink`]
//!   streams rows instead of keeping them.
//! - **Analyse.** [`analysis`]: log bins, power-law fits with confidence intervals, the leak
//!   onset, collapse of curves, the fit rules of the paper's figures ([`analysis::decay`]) and
//!   ensemble statistics; [`paper`] holds what Hong states, to compare against.
//! - **Evaluate a protector.** [`protector::evaluate`] runs a column of [`protector::Bead`]s
//!   in real materials ([`units`]) struck by an impactor and returns the peak force, impulse
//!   and duration on the protected face ([`protector::Evaluation`]).
//!
//! # Scripting a study
//!
//! A small granular container built in code (light Hertz grains between two linear walls, inside
//! long chains of heavy grains), struck by a heavy grain; the energy left inside is recorded at
//! every snapshot and fitted with a power law `E_R = A t^-gamma` from its leak onset on:
//!
//! ```
//! use grainchain_engine::analysis::{fit_power_law, leak_onset, log_bins};
//! use grainchain_engine::{ChainBuilder, ContactLaw, IntegrationParams, Method, Recorder, Section};
//! use grainchain_engine::SimulationBuilder;
//!
//! let hertz = ContactLaw::hertz(5657.0);
//! let wall = ContactLaw::new(1.0, 5657.0); // linear, compression-only
//! let chain = ChainBuilder::new()
//!     .section(Section::new("outer-left", 300, 100.0, hertz))
//!     .section(Section::new("wall-left", 10, 2.0, wall))
//!     .section(Section::new("inside", 20, 0.1, hertz))
//!     .section(Section::new("wall-right", 10, 2.0, wall))
//!     .section(Section::new("outer-right", 300, 100.0, hertz))
//!     .build()?;
//! // The striker: the 61st grain of the right outer chain, moving left at speed 10.
//! let striker = *chain.grains_of("outer-right")?.start() + 60;
//! let params = IntegrationParams {
//!     method: Method::BlanesMoan4,
//!     dt: 7.8125e-4,
//!     ..Default::default()
//! };
//! let mut sim = SimulationBuilder::new(chain)
//!     .params(params)
//!     .schedule(60.0, 0.125) // 480 snapshots
//!     .velocity(striker, -10.0)
//!     .build()?;
//! // The container, from its left wall to its right wall, found by section names.
//! let record = Recorder::new()
//!     .sections("container", "wall-left", "wall-right")
//!     .record(&mut sim)?;
//! let e_r = &record.region("container").unwrap().energy;
//!
//! // Fit from the leak onset (E_R down to 90 % of its maximum) to the end, 5 bins per decade.
//! let onset = leak_onset(e_r, 0.9).expect("the container leaks");
//! let fit = fit_power_law(&log_bins(e_r, onset, e_r.len() - 1, 5)).expect("enough bins");
//! assert!(fit.gamma > 0.0 && fit.ci_lo <= fit.gamma && fit.gamma <= fit.ci_hi);
//! println!("gamma = {:.3} [{:.3}, {:.3}]", fit.gamma, fit.ci_lo, fit.ci_hi);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// `!(x > 0.0)` and friends are how this crate makes a NaN fail a check (a NaN compares false
// both ways), so clippy's advice to rewrite them with `partial_cmp` is declined crate-wide.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]
// A public type that the façade does not export is a hole in it: warn.
#![warn(unnameable_types)]

pub mod analysis;
mod chain;
mod error;
mod integrators;
mod number;
mod observables;
pub mod paper;
pub mod problems;
pub mod protector;
mod recorder;
mod run;
mod scene;
mod state;
pub mod units;

// The chain: grains, sections, contact laws, ends.
pub use chain::law::FORCE_FLOOR;
pub use chain::{
    Chain, ChainBuilder, ChainError, ContactDamping, ContactLaw, DampingModel, End, InterfaceRule,
    Island, LawError, Section, SectionSpan, Striker, StrikerEnd, Window,
};
// Integrators: the method table, the parameters, the counters, the low-level stepping interface.
pub use integrators::{
    make as make_integrator, Edge, EdgeWork, IntegrationParams, Integrator, Load, LoadSample,
    LoadWatch, Method, MethodInfo, MultirateParams, ParamsError, PeakSpeeds, Reflection,
    ReflectionRule, ReflectionWatch, Sleep, Stats, StepError, MAX_STEPS_PER_OUTPUT,
};
// The run: building a simulation, its loop and its bookkeeping.
pub use run::{
    initial_energy, thread_pool, worker_threads, Frame, Horizon, RunError, RunSummary, Simulation,
    SimulationBuilder, Timings,
};
pub use state::State;
// Observables and what the recorder makes of them.
pub use observables::{
    detect_pulses, grain_energies, grain_energy, region_energy, totals, Field, Pulse, PulseRule,
    Schedule, Totals, Track, TrackPoint, TrackRule, Tracker,
};
pub use recorder::{
    ProbeSeries, PulseRecord, Pulses, Record, Recorder, RegionSeries, Row, Sink, Snapshot,
    SnapshotRecord,
};
// Scenes: the checked form of a scene file, and what it costs.
pub use error::{Error, InputError};
pub use scene::{
    MemoryEstimate, OutputEstimate, OutputSpec, PulseSpec, Region, Scene, SnapshotSpec, TrackSpec,
    MAX_GRAINS, MAX_OUTPUTS, MEMORY_BASE_BYTES, NAME_MAX_BYTES,
};

/// How numbers, sizes and durations are written in messages: [`format::Num`] (the one number
/// formatter of messages), [`format::human_bytes`], [`format::seconds`].
pub mod format {
    pub use crate::number::{human_bytes, seconds, Num};
}

/// The scene file's schema (TOML, unknown keys refused in every table) and the edits made to a
/// parsed file before it is checked: the outer medium of a container scene, the shift of grain
/// numbers it causes. [`crate::Scene::from_file`] checks a parsed file.
pub mod file {
    pub use crate::scene::file::*;
    pub use crate::scene::outer::{
        apply as apply_outer, method_problem as outer_method_problem, shift_grains,
        MIN_DISTANCE as MIN_OUTER_DISTANCE,
    };
    pub use crate::scene::{parse_file, parse_toml, Parsed};
}
