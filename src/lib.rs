//! grainchain's harness: the batch layer, ensemble studies, the reproduction of Hong (2005),
//! the work-precision study, output folders, reports and plots, and the command-line tool, all
//! built on the engine's public API (the `grainchain-engine` crate, `engine/`: chains,
//! integrators, runs, scenes, analysis). See `ARCHITECTURE.md` for the map.

// `!(x > 0.0)` and friends are how this crate makes a NaN fail a check (a NaN compares false
// both ways), so clippy's advice to rewrite them with `partial_cmp` is declined crate-wide.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod batch;
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
#[doc = include_str!("../README.md")]
struct ReadmeExample;

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
