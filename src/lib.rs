//! grainchain: one-dimensional granular chains with power-law contacts, and a validation and
//! benchmark harness around them. See `ARCHITECTURE.md` for the map of the crate.

// `!(x > 0.0)` and friends are how this crate makes a NaN fail a check (a NaN compares false
// both ways), so clippy's advice to rewrite them with `partial_cmp` is declined crate-wide.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod analysis;
pub mod chain;
pub mod error;
pub mod integrators;
pub mod observables;
pub mod report;
pub mod reproduce;
pub mod run;
pub mod scene;
pub mod state;
pub mod units;
pub mod work_precision;

pub use chain::{
    Chain, ChainBuilder, ContactLaw, End, InterfaceRule, Section, Striker, StrikerEnd, Window,
};
pub use integrators::{IntegrationParams, Method, Sleep, Stats};
pub use run::{Simulation, SimulationBuilder};
pub use state::State;
