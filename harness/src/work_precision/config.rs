//! The settings of a work-precision study ([`Config`]), which the study's problems and
//! `statistics.rs` both read.

use grainchain_engine::Method;
use std::path::PathBuf;

/// The settings a method's work-precision curve samples on the benchmark problems, coarsest
/// first: the fixed steps `dt` from the largest that still gives a result down to where rounding
/// takes over; for the adaptive method its relative tolerances `rtol`. Empty: the method is
/// measured elsewhere (multirate needs a fast region: `validation/multirate.rs`).
pub fn samples(method: Method) -> &'static [f64] {
    match method {
        Method::Verlet => &[8e-4, 4e-4, 2e-4, 1e-4, 5e-5, 2.5e-5, 1.25e-5],
        Method::BlanesMoan4 => &[3.2e-3, 1.6e-3, 8e-4, 4e-4, 2e-4, 1e-4],
        Method::Gear5 => &[4e-4, 2e-4, 1e-4, 5e-5],
        Method::Dopri5 => &[1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
        Method::Multirate => &[],
    }
}

/// The steps over the run that a fixed-step method's sweep takes on the problems that measure the
/// observed order ([`super::Benchmark::measures_order`]), coarsest first, each twice the last:
/// exact halvings of `dt` (the run's length is a whole number of every step), five of them. The
/// coarsest resolves the contact by about 100 (verlet), 30 (blanes-moan4) or 200 (gear5) steps
/// on each problem (the runs last 2.2 to 5.5 contact times); the finest stays above rounding.
/// Empty: the method is measured elsewhere (multirate). dopri5 sweeps [`samples`]' tolerances.
pub fn halvings(method: Method) -> Vec<u64> {
    let (first, count) = match method {
        Method::Verlet => (256, 6),
        Method::BlanesMoan4 => (64, 6),
        Method::Gear5 => (512, 6),
        Method::Dopri5 | Method::Multirate => return Vec::new(),
    };
    (0..count).map(|k| first << k).collect()
}

/// The steps per contact time `protector-40`'s sweep takes for a method (the splitting methods
/// a protector evaluation accepts), coarsest first, each twice the last: exact halvings of the
/// step, from 20 (an eighth of the default 160) to 2560. Empty for the other methods.
pub fn protector_steps(method: Method) -> Vec<u64> {
    match method {
        Method::Verlet | Method::BlanesMoan4 => (0..8).map(|k| 20 << k).collect(),
        Method::Gear5 | Method::Dopri5 | Method::Multirate => Vec::new(),
    }
}

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
