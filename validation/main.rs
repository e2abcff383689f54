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

/// A test with cases: `name::case_1`, `name::case_2`, … each call `name` with its arguments, as
/// rstest's `#[case]` named them. Written out here instead of using rstest (issue 37): its
/// proc macro, regex and a fuller syn were some 40 s of a fresh clone's 2-core `cargo test`
/// build, for what these few lines do.
///
/// ```ignore
/// cases! {
///     /// What the test checks.
///     fn name(p: f64, file: &str) { ... }
///     #[ignore = "why"]           // optional attributes of every case
///     case_1(1.5, "a.toml"),
///     case_2(2.0, "b.toml"),
/// }
/// ```
macro_rules! cases {
    (
        $(#[$attr:meta])*
        fn $name:ident $args:tt $body:block
        $(#[$each:meta])*
        $($case:ident $values:tt),+ $(,)?
    ) => {
        $(#[$attr])*
        fn $name $args $body

        mod $name {
            #[allow(unused_imports)]
            use super::*;
            cases!(@each [$(#[$each])*] $name; $($case $values),+);
        }
    };
    (@each $each:tt $name:ident; $($case:ident ($($value:expr),* $(,)?)),+) => {
        $(cases!(@one $each $name $case ($($value),*));)+
    };
    (@one [$($each:tt)*] $name:ident $case:ident ($($value:expr),*)) => {
        #[test]
        $($each)*
        fn $case() {
            super::$name($($value),*)
        }
    };
}

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
mod orders;
mod outer;
mod outputs;
mod protector;
mod protector_gradients;
mod protector_reference;
mod published;
mod robust;
mod smoke;
mod speed;
mod stress;
mod study;
mod tolerances;
mod tracking;
mod verdicts;
