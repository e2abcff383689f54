//! The validation suite: one integration-test binary, one module per file of `validation/`.
//!
//! Every `[[test]]` target links the whole crate at opt-level 3 (`[profile.test]`), so one
//! target per file spent most of a fresh `cargo test` compiling and linking; one binary links it
//! once. Test names carry their module (`horizon::a_too_tight_horizon_is_caught`), so one file's
//! tests run with `cargo test --test validation horizon::` (a substring filter: `figures::` also
//! runs `golden_figures::`). The tests run as threads of one
//! process: a test must not change the current directory or the environment, and the process id
//! no longer tells modules apart, so temporary folders carry the module's name too
//! (`grainchain-<module>-<name>-<pid>`).

mod common;

mod analytic;
mod bad_input;
mod conservation;
mod convergence;
mod counters;
mod damping;
mod design;
mod figures;
mod folders;
mod golden_figures;
mod gravity;
mod horizon;
mod integrators;
mod interfaces;
mod islands;
mod keys;
mod lammps;
mod layers;
mod materials;
mod mechanism;
mod memory;
mod multirate;
mod outer;
mod outputs;
mod protector;
mod published;
mod smoke;
mod speed;
mod stress;
mod study;
mod tracking;
mod verdicts;
