//! The settings of a work-precision study ([`Config`]), which the study's problems and
//! `statistics.rs` both read.

use std::path::PathBuf;

/// Settings of a study.
#[derive(Clone, Debug)]
pub struct Config {
    /// Fewer points and shorter problems (for smoke tests).
    pub quick: bool,
    /// Timing repeats per point (median).
    pub repeats: usize,
    /// Where the scenes live.
    pub scenes: PathBuf,
    /// Worker threads of `container-a-statistics`'s ensembles ([`crate::batch::Pool`]); its
    /// numbers do not depend on it (its timings do).
    pub threads: usize,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            quick: false,
            repeats: 3,
            scenes: PathBuf::from("scenes"),
            threads: 2,
        }
    }
}
