//! grainchain: one-dimensional granular chains with power-law contacts, and a validation and
//! benchmark harness around them. See `ARCHITECTURE.md` for the map of the crate.
//!
//! # Scripting a study
//!
//! A small granular container built in code (light Hertz grains between two linear walls, inside
//! long chains of heavy grains), struck by a heavy grain; the energy left inside is recorded at
//! every snapshot and fitted with a power law `E_R = A t^-gamma` from its leak onset on:
//!
//! ```
//! use grainchain::analysis::{fit_power_law, leak_onset, log_bins};
//! use grainchain::chain::{ChainBuilder, ContactLaw, Section};
//! use grainchain::integrators::{IntegrationParams, Method};
//! use grainchain::recorder::Recorder;
//! use grainchain::run::SimulationBuilder;
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

pub mod analysis;
pub mod batch;
pub mod chain;
pub mod error;
pub mod integrators;
pub mod number;
pub mod observables;
pub mod paper;
pub mod problems;
pub mod recorder;
pub mod report;
pub mod reproduce;
pub mod run;
pub mod scene;
pub mod state;
pub mod study;
pub mod units;
pub mod work_precision;

/// This build: `grainchain <version> (git <revision>)`, the revision with `-dirty` when the work
/// tree had staged changes (`build.rs`). Member files and output manifests record it, and a
/// study's digest includes it, so members of different builds are never merged.
pub const PROGRAM: &str = concat!(
    "grainchain ",
    env!("CARGO_PKG_VERSION"),
    " (git ",
    env!("GRAINCHAIN_GIT"),
    ")"
);

pub use chain::{
    Chain, ChainBuilder, ChainError, ContactDamping, ContactLaw, DampingModel, End, InterfaceRule,
    Section, Striker, StrikerEnd, Window,
};
pub use integrators::{IntegrationParams, Method, Sleep, Stats};
pub use run::{Horizon, Simulation, SimulationBuilder};
pub use state::State;
