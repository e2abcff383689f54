//! Fig. 3: the standard container's leaks at the paper's 280th snapshot.

use super::{pulses_in, snap_pair, with_fraction, PulseOut};
use crate::batch::{RunData, Snap};
use crate::error::Error;
use crate::observables::PulseRule;

/// Fig. 3: the standard container's leaks at the paper's 280th snapshot.
#[derive(Clone, Debug)]
pub struct Fig3 {
    /// The figure's snapshot (the last listed, the paper's 280th).
    pub snap: Snap,
    /// Printed grain number of internal grain 0.
    pub first_grain: i64,
    /// First and last grain of the container region (printed numbers, inclusive).
    pub container: (i64, i64),
    /// The scene's pulse rule, used for every pulse here.
    pub rule: PulseRule,
    /// E0: the energy at t = 0, all the striker's.
    pub striker_energy: f64,
    /// The incident solitary wave (first listed snapshot).
    pub incident: PulseOut,
    /// Output index of the first listed snapshot, where `incident` was found.
    pub incident_index: u64,
    /// Pulses outside the container, `fraction` of the incident energy; side "left"/"right".
    pub outside: Vec<(&'static str, PulseOut)>,
    /// The leading wave on the left: the leftmost pulse of `outside` left of the container
    /// (`None`: none there).
    pub left_lead: Option<PulseOut>,
    /// The leading wave on the right: the rightmost pulse of `outside` right of the container
    /// (`None`: none there).
    pub right_lead: Option<PulseOut>,
    /// Energy of the container region in the figure's snapshot.
    pub container_energy: f64,
    /// Grains between the left end of the chain and the leftmost grain ever disturbed.
    pub margin: usize,
}

/// Fig. 3 from the run `d`, which records the region `container` and two snapshots (the
/// incident wave's and the figure's); pulses found with `rule`.
pub fn fig3(d: &RunData, rule: PulseRule) -> Result<Fig3, Error> {
    let (first, snap) = snap_pair(d, "fig3")?;
    let container = d.region("container")?;
    let (a, b) = container.range;
    let fg = d.first_grain;
    let n = d.run.grains;
    let incident = pulses_in(&first, b + 1, n - 1, &rule, fg)
        .into_iter()
        .max_by(|x, y| x.energy.total_cmp(&y.energy))
        .ok_or(crate::reproduce::ReproduceError::NoIncidentWave {
            figure: "fig3",
            place: "right of the container in the first snapshot",
        })?;
    let e_inc = incident.energy;
    let all = pulses_in(&snap, 0, n - 1, &rule, fg);
    let (ca, cb) = (a as i64 + fg, b as i64 + fg);
    let (g0, g1) = (fg, n as i64 - 1 + fg);
    let mut outside = Vec::new();
    for p in all {
        if p.first == g0 || p.last == g1 {
            continue; // touches an end of the chain (the striker's rebound on the right)
        }
        let p = with_fraction(p, e_inc);
        if p.last < ca {
            outside.push(("left", p));
        } else if p.first > cb {
            outside.push(("right", p));
        }
    }
    let left_lead = outside
        .iter()
        .filter(|(s, _)| *s == "left")
        .min_by_key(|(_, p)| p.first)
        .map(|(_, p)| p.clone());
    let right_lead = outside
        .iter()
        .filter(|(s, _)| *s == "right")
        .max_by_key(|(_, p)| p.last)
        .map(|(_, p)| p.clone());
    Ok(Fig3 {
        container_energy: container.energy[snap.index as usize],
        first_grain: fg,
        container: (ca, cb),
        rule,
        striker_energy: d.run.initial_energy,
        incident: with_fraction(incident, e_inc),
        incident_index: first.index,
        outside,
        left_lead,
        right_lead,
        margin: d.run.ever.0,
        snap,
    })
}
