//! Fig. 1: a solitary wave through a heavy-to-light interface.

use super::{pulses_in, snap_pair, with_fraction, PulseOut};
use crate::batch::{RunData, Snap};
use crate::error::Error;
use crate::observables::PulseRule;

/// Fig. 1: heavy-to-light interface.
#[derive(Clone, Debug)]
pub struct Fig1 {
    /// The first listed snapshot: the incident wave still in the heavy section.
    pub before: Snap,
    /// The last listed snapshot, the figure's: the transmitted waves in the light section.
    pub after: Snap,
    /// Printed grain number of internal grain 0 (0 when, as in the scene file, the striker hits
    /// the left end).
    pub first_grain: i64,
    /// First grain of the light section (printed number).
    pub interface: i64,
    /// Grains of the heavy section.
    pub heavy: usize,
    /// Grains of the light section.
    pub light: usize,
    /// The scene's pulse rule, used for every pulse here.
    pub rule: PulseRule,
    /// E0: the energy at t = 0, all the striker's.
    pub striker_energy: f64,
    /// The incident wave: the largest pulse of the heavy section in `before` (`fraction` 1).
    pub incident: PulseOut,
    /// Pulses of the light section, leading first; `fraction` is of the incident wave's energy.
    pub transmitted: Vec<PulseOut>,
    /// Energy left in the heavy section in `after`.
    pub heavy_after: f64,
    /// Energy in the same grains at the same snapshot of the control run (light section made
    /// heavy): the striker's own rebound, without any reflection at the interface.
    pub heavy_control: f64,
    /// `heavy_after - heavy_control`.
    pub reflected: f64,
    /// Energy in the light section in `after`.
    pub light_after: f64,
    /// Grains between the furthest disturbance and the far end.
    pub margin: usize,
}

impl Fig1 {
    /// Transmitted waves carrying at least `fraction` of the incident energy.
    pub fn count_above(&self, fraction: f64) -> usize {
        self.transmitted
            .iter()
            .filter(|p| p.fraction >= fraction)
            .count()
    }
}

/// Fig. 1 from the run `main` and its control run `control` (light section made heavy), both
/// recording the regions `heavy` and `light` and two snapshots; pulses found with `rule`.
pub fn fig1(main: &RunData, control: &RunData, rule: PulseRule) -> Result<Fig1, Error> {
    let (before, after) = snap_pair(main, "fig1")?;
    let (heavy, light) = (main.region("heavy")?, main.region("light")?);
    let (h, l) = (heavy.range, light.range);
    let fg = main.first_grain;
    let incident = pulses_in(&before, h.0, h.1, &rule, fg)
        .into_iter()
        .max_by(|a, b| a.energy.total_cmp(&b.energy))
        .ok_or(crate::reproduce::ReproduceError::NoIncidentWave {
            figure: "fig1",
            place: "in the heavy section",
        })?;
    let e_inc = incident.energy;
    let mut transmitted: Vec<PulseOut> = pulses_in(&after, l.0, l.1, &rule, fg)
        .into_iter()
        .map(|p| with_fraction(p, e_inc))
        .collect();
    transmitted.sort_by(|a, b| b.position.total_cmp(&a.position));
    let k = after.index as usize;
    let heavy_after = heavy.energy[k];
    let heavy_control = control.region("heavy")?.energy[k];
    Ok(Fig1 {
        interface: l.0 as i64 + fg,
        heavy: h.1 - h.0 + 1,
        light: l.1 - l.0 + 1,
        first_grain: fg,
        rule,
        striker_energy: main.run.initial_energy,
        incident: with_fraction(incident, e_inc),
        transmitted,
        heavy_after,
        heavy_control,
        reflected: heavy_after - heavy_control,
        light_after: light.energy[k],
        margin: main.run.grains - main.run.ever.1,
        before,
        after,
    })
}
