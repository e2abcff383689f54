//! Pulses in printed grain numbers, shared by the units of Fig. 1 and Fig. 3.
//!
//! Definition (also stated in REPORT.md): a *pulse* is a run of grains found by
//! [`detect_pulses`] with the scene's pulse rule (a grain belongs to a pulse when its energy
//! exceeds `threshold` times the largest grain energy of the slice searched; deep valleys split
//! runs).

use crate::batch::{RunData, Snap};
use crate::error::Error;
use crate::reproduce::render::text::num;
use crate::reproduce::table::Cell;
use grainchain_engine::{detect_pulses, PulseRule};

/// A pulse in printed grain numbers.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PulseOut {
    /// First grain of the pulse (printed number: 1-based, a left striker is 0).
    pub first: i64,
    /// Last grain of the pulse (printed number), inclusive.
    pub last: i64,
    /// Energy-weighted centre (grain number).
    pub position: f64,
    /// Velocity of largest magnitude in the pulse, with its sign.
    pub peak_velocity: f64,
    /// Energy of the pulse: the sum of its grains' energies.
    pub energy: f64,
    /// Energy over the figure's reference (incident) energy.
    pub fraction: f64,
    /// `100 * fraction`: energy in % of the reference energy.
    pub percent: f64,
}

/// Pulses among internal grains `a..=b` of a snapshot (rule applied to that slice).
pub(super) fn pulses_in(
    s: &Snap,
    a: usize,
    b: usize,
    rule: &PulseRule,
    first_grain: i64,
) -> Vec<PulseOut> {
    detect_pulses(&s.energy[a..=b], &s.velocity[a..=b], rule)
        .into_iter()
        .map(|p| PulseOut {
            first: (p.first + a) as i64 + first_grain,
            last: (p.last + a) as i64 + first_grain,
            position: p.position + a as f64 + first_grain as f64,
            peak_velocity: p.peak_velocity,
            energy: p.energy,
            fraction: f64::NAN,
            percent: f64::NAN,
        })
        .collect()
}

pub(super) fn with_fraction(mut p: PulseOut, reference: f64) -> PulseOut {
    p.fraction = p.energy / reference;
    p.percent = 100.0 * p.fraction;
    p
}

pub(super) fn snap_pair(d: &RunData, fig: &str) -> Result<(Snap, Snap), Error> {
    match (d.snaps.first(), d.snaps.last()) {
        (Some(a), Some(b)) if d.snaps.len() >= 2 => Ok((a.clone(), b.clone())),
        _ => Err(crate::error::ReproduceError::SnapshotsNotListed {
            figure: fig.to_string(),
        }
        .into()),
    }
}

/// A pulse as a row of the pulse tables: `lead`, then its grains, position, peak velocity,
/// energy and `share` (its fraction or percent of the incident energy).
pub(super) fn pulse_row(lead: Cell, p: &PulseOut, share: f64) -> Vec<Cell> {
    vec![
        lead,
        p.first.into(),
        p.last.into(),
        num(p.position),
        num(p.peak_velocity),
        num(p.energy),
        num(share),
    ]
}
