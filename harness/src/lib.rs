//! grainchain's harness: the batch layer, ensemble studies, the reproduction of Hong (2005),
//! the work-precision study, output folders, reports and plots, and the commands of the command-line
//! tool (`commands`: each one function, which the tool and the Python package call), all
//! built on the engine's public API (the `grainchain-engine` crate, `engine/`: chains,
//! integrators, runs, scenes, analysis). See `ARCHITECTURE.md` for the map.

// `!(x > 0.0)` and friends are how this crate makes a NaN fail a check (a NaN compares false
// both ways), so clippy's advice to rewrite them with `partial_cmp` is declined crate-wide.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod batch;
pub mod commands;
pub mod design;
pub mod error;
pub mod export;
pub mod report;
pub mod reproduce;
pub mod study;
pub mod work_precision;

// The README's library example runs as a doc-test of this crate (from the repository root, where
// its scene path points).
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
struct ReadmeExample;

/// This build: `grainchain <version> (git <revision>)`. Member files and output manifests record
/// it, and a study's digest includes it, so members of different builds are never merged.
///
/// The revision is told at start-up by the program that links this library
/// ([`set_revision`]: the command-line tool and the Python module, from the `grainchain-revision`
/// crate), not compiled in here: a commit would otherwise rebuild the whole harness. A program
/// that does not tell it is `git unknown`, never a wrong revision.
pub fn program() -> &'static str {
    PROGRAM.get_or_init(|| identify("unknown"))
}

/// Tell the library which git revision built the program (once, before anything is written;
/// a later call with another revision is ignored: the first one is what files already record).
pub fn set_revision(git: &str) {
    let _ = PROGRAM.set(identify(git));
}

static PROGRAM: std::sync::OnceLock<String> = std::sync::OnceLock::new();

fn identify(git: &str) -> String {
    format!("grainchain {} (git {git})", env!("CARGO_PKG_VERSION"))
}
