//! The parts of a checked scene that `check.rs` builds and `Scene` holds: regions, the output
//! specs, initial conditions, and `Ctx`, the file an error names with its key. Below both, so
//! the checks and the scene do not import each other both ways.

use super::file::LawFile;
use crate::chain::ContactLaw;
use crate::error::InputError;
use crate::integrators::ParamsError;
use crate::observables::{Field, PulseRule, Schedule, TrackRule};
use std::path::Path;

/// A named grain range (printed grain numbers, inclusive).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Region {
    /// The region's name (key `regions[i].name`): the column suffix in `energies.csv`
    /// (`E_<name>`, `P_<name>`) and the name `integrator.multirate.fast` refers to.
    pub name: String,
    /// First grain, as a printed grain number (chain grains 1..=N, a left striker 0, a right
    /// striker N + 1).
    pub first: i64,
    /// Last grain, as a printed grain number (inclusive).
    pub last: i64,
}

/// What to record.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct OutputSpec {
    /// Time series of total energies, momentum and region energies.
    pub energies: bool,
    /// Per-grain snapshots (`snapshots.csv`), if asked for.
    pub snapshots: Option<SnapshotSpec>,
    /// Pulse detection (`pulses.csv`), if asked for.
    pub pulses: Option<PulseSpec>,
    /// Pulses followed from one detection to the next (`tracks.csv`).
    pub tracks: Option<TrackSpec>,
}

/// Which snapshots to record.
#[derive(Clone, Debug, PartialEq)]
pub struct SnapshotSpec {
    /// The per-grain fields recorded, in the order of the columns.
    pub fields: Vec<Field>,
    /// Record output indices that are multiples of `every` ...
    pub every: u64,
    /// ... or exactly these output indices (when not empty).
    pub at: Vec<u64>,
    /// Printed grain numbers, inclusive.
    pub first: i64,
    /// Last grain recorded (printed grain number, inclusive).
    pub last: i64,
}

impl SnapshotSpec {
    /// The outputs recorded (`Schedule::wants` says whether one is).
    pub fn schedule(&self) -> Schedule {
        schedule(self.every, &self.at)
    }
}

/// `at` when it is not empty, else every `every`-th output.
fn schedule(every: u64, at: &[u64]) -> Schedule {
    if at.is_empty() {
        Schedule::Every(every)
    } else {
        Schedule::At(at.to_vec())
    }
}

/// Pulse detection settings.
#[derive(Clone, Debug, PartialEq)]
pub struct PulseSpec {
    /// Detect at output indices that are multiples of `every` ...
    pub every: u64,
    /// ... or exactly at these output indices (when not empty).
    pub at: Vec<u64>,
    /// The thresholds that split an energy profile into pulses.
    pub rule: PulseRule,
}

impl PulseSpec {
    /// The outputs pulses are detected at (`Schedule::wants` says whether one is).
    pub fn schedule(&self) -> Schedule {
        schedule(self.every, &self.at)
    }
}

/// Pulse tracking settings (`output.tracks`): pulses detected with `rule` at every `every`-th
/// output and linked by `track` (`observables::tracking`).
#[derive(Clone, Debug, PartialEq)]
pub struct TrackSpec {
    /// Detect and link at output indices that are multiples of this (>= 1).
    pub every: u64,
    /// How pulses are found in the energy profile at each detection.
    pub rule: PulseRule,
    /// How pulses are linked from one detection to the next.
    pub track: TrackRule,
}

/// One grain's initial condition from `[[initial]]`: printed grain number, displacement and
/// velocity (each optional).
pub(super) type InitialGrain = (i64, Option<f64>, Option<f64>);

/// Where a check is: the file its errors name.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a Path,
}

impl Ctx<'_> {
    pub(super) fn err(&self, key: impl Into<String>, message: impl Into<String>) -> InputError {
        InputError::Invalid {
            file: self.file.to_path_buf(),
            key: key.into(),
            message: message.into(),
        }
    }

    pub(super) fn positive(&self, key: &str, x: f64) -> Result<f64, InputError> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number > 0, got {x}")))
        }
    }

    /// A settings error of [`IntegrationParams::validate`] under its scene key.
    pub(super) fn params(&self, e: ParamsError) -> InputError {
        self.err(e.key, e.message)
    }

    pub(super) fn non_negative(&self, key: &str, x: f64) -> Result<f64, InputError> {
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number >= 0, got {x}")))
        }
    }

    /// The law of a section, wall or striker, checked by [`ContactLaw::validate`] (the one place
    /// the rules live) and its error put under the scene key of the parameter at fault.
    pub(super) fn law(&self, key: &str, l: &LawFile) -> Result<ContactLaw, InputError> {
        let missing = |k: &str| {
            self.err(
                format!("{key}.{k}"),
                "missing: give `p` and `eta` (program units), or a `material` (SI)",
            )
        };
        let p = l.p.ok_or_else(|| missing("p"))?;
        let eta = l.eta.ok_or_else(|| missing("eta"))?;
        let law = ContactLaw {
            p,
            eta,
            delta0: l.delta0.unwrap_or(0.0),
            tension: l.tension.unwrap_or(false),
            damping: l
                .contact_damping
                .map(|d| crate::chain::law::ContactDamping {
                    model: d.model,
                    c: d.c,
                }),
        };
        law.validate()
            .map_err(|e| self.err(format!("{key}.{}", e.key()), e.problem()))?;
        Ok(law)
    }
}
