//! The analysis of each figure: from recorded runs to the numbers the paper states.
//!
//! Definitions (also stated in REPORT.md):
//! - A *pulse* is a run of grains found by [`detect_pulses`] with the scene's pulse rule (a grain
//!   belongs to a pulse when its energy exceeds `threshold` times the largest grain energy of the
//!   slice searched; deep valleys split runs).
//! - Fig. 1: the *incident wave* is the largest pulse of the heavy section in the first listed
//!   snapshot; the *transmitted waves* are the pulses of the light section in the last one, leading
//!   (rightmost) first; the *reflected energy* is the energy left in the heavy section minus the
//!   energy left in the same grains of a control run whose light section is heavy too (so the
//!   striker's own slow rebound, present in both, cancels).
//! - Fig. 3: the *incident energy* is the energy of the largest pulse right of the container in the
//!   first listed snapshot (the solitary wave launched by the striker, before it reaches the
//!   container); the *leading waves* are the outermost pulses left and right of the container in
//!   the figure's snapshot, among pulses found over the whole chain, excluding pulses that touch an
//!   end of the chain (on the right that is the striker's slow rebound, which never was in the
//!   container).

use super::analysis::{self, Collapse, CollapseRule, LogPoint, PowerFit};
use super::jobs::{RunData, Snap};
use crate::error::Error;
use crate::observables::{detect_pulses, PulseRule};

/// A pulse in printed grain numbers.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PulseOut {
    pub first: i64,
    pub last: i64,
    /// Energy-weighted centre (grain number).
    pub position: f64,
    pub peak_velocity: f64,
    pub energy: f64,
    /// Energy over the figure's reference (incident) energy.
    pub fraction: f64,
}

/// Pulses among internal grains `a..=b` of a snapshot (rule applied to that slice).
fn pulses_in(s: &Snap, a: usize, b: usize, rule: &PulseRule, first_grain: i64) -> Vec<PulseOut> {
    detect_pulses(&s.energy[a..=b], &s.velocity[a..=b], rule)
        .into_iter()
        .map(|p| PulseOut {
            first: (p.first + a) as i64 + first_grain,
            last: (p.last + a) as i64 + first_grain,
            position: p.position + a as f64 + first_grain as f64,
            peak_velocity: p.peak_velocity,
            energy: p.energy,
            fraction: f64::NAN,
        })
        .collect()
}

fn with_fraction(mut p: PulseOut, reference: f64) -> PulseOut {
    p.fraction = p.energy / reference;
    p
}

fn snap_pair(d: &RunData, fig: &str) -> Result<(Snap, Snap), Error> {
    match (d.snaps.first(), d.snaps.last()) {
        (Some(a), Some(b)) if d.snaps.len() >= 2 => Ok((a.clone(), b.clone())),
        _ => Err(Error::Other(format!(
            "{fig}: the scene must list two snapshots in output.snapshots.at (before, after)"
        ))),
    }
}

/// Fig. 1: heavy-to-light interface.
#[derive(Clone, Debug)]
pub struct Fig1 {
    pub before: Snap,
    pub after: Snap,
    pub first_grain: i64,
    /// First grain of the light section.
    pub interface: i64,
    /// Grains of the heavy and light sections.
    pub heavy: usize,
    pub light: usize,
    pub rule: PulseRule,
    pub striker_energy: f64,
    pub incident: PulseOut,
    /// Pulses of the light section, leading first; `fraction` is of the incident wave's energy.
    pub transmitted: Vec<PulseOut>,
    pub heavy_after: f64,
    pub heavy_control: f64,
    /// `heavy_after - heavy_control`.
    pub reflected: f64,
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

pub fn fig1(main: &RunData, control: &RunData, rule: PulseRule) -> Result<Fig1, Error> {
    let (before, after) = snap_pair(main, "fig1")?;
    let (h, l) = (main.region_ranges[0], main.region_ranges[1]);
    let fg = main.first_grain;
    let incident = pulses_in(&before, h.0, h.1, &rule, fg)
        .into_iter()
        .max_by(|a, b| a.energy.total_cmp(&b.energy))
        .ok_or_else(|| Error::Other("fig1: no incident wave in the heavy section".into()))?;
    let e_inc = incident.energy;
    let mut transmitted: Vec<PulseOut> = pulses_in(&after, l.0, l.1, &rule, fg)
        .into_iter()
        .map(|p| with_fraction(p, e_inc))
        .collect();
    transmitted.sort_by(|a, b| b.position.total_cmp(&a.position));
    let k = after.index as usize;
    let heavy_after = main.energies[0][k];
    let heavy_control = control.energies[0][k];
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
        light_after: main.energies[1][k],
        margin: main.run.grains - main.run.ever.1,
        before,
        after,
    })
}

/// Fig. 3: the standard container's leaks at the paper's 280th snapshot.
#[derive(Clone, Debug)]
pub struct Fig3 {
    pub snap: Snap,
    pub first_grain: i64,
    pub container: (i64, i64),
    pub rule: PulseRule,
    pub striker_energy: f64,
    /// The incident solitary wave (first listed snapshot).
    pub incident: PulseOut,
    pub incident_index: u64,
    /// Pulses outside the container, `fraction` of the incident energy; side "left"/"right".
    pub outside: Vec<(&'static str, PulseOut)>,
    pub left_lead: Option<PulseOut>,
    pub right_lead: Option<PulseOut>,
    pub container_energy: f64,
    pub margin: usize,
}

pub fn fig3(d: &RunData, rule: PulseRule) -> Result<Fig3, Error> {
    let (first, snap) = snap_pair(d, "fig3")?;
    let (a, b) = d.region_ranges[0];
    let fg = d.first_grain;
    let n = d.run.grains;
    let incident = pulses_in(&first, b + 1, n - 1, &rule, fg)
        .into_iter()
        .max_by(|x, y| x.energy.total_cmp(&y.energy))
        .ok_or_else(|| {
            Error::Other(
                "fig3: no incident wave right of the container in the first snapshot".into(),
            )
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
        container_energy: d.energies[0][snap.index as usize],
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

/// Bins per decade of the log-log fits and collapses.
pub const BINS_PER_DECADE: usize = 20;

/// Fraction of the peak energy at which a container counts as leaking (start of the collapse
/// range): after half the energy that entered has left again.
pub const ONSET_FRACTION: f64 = 0.5;

/// The fit window of a curve of `n` snapshots: the last decade, `[n/10, n]`, but never before
/// the leak onset (in a short run `n/10` can fall before the incident wave has even arrived).
pub fn fit_window(n: usize, onset: Option<usize>) -> (usize, usize) {
    ((n / 10).max(onset.unwrap_or(0)), n)
}

/// The windows of the sensitivity table, as fractions of `n` (starts clamped to the leak onset).
pub const WINDOWS: [(f64, f64); 5] = [
    (0.05, 1.0),
    (0.1, 1.0),
    (0.25, 1.0),
    (0.1, 0.5),
    (0.025, 0.25),
];

/// Fit `E_R / E0` in percent over snapshots `lo..=hi`.
pub fn fit_percent(e: &[f64], e0: f64, lo: usize, hi: usize) -> Option<PowerFit> {
    let pct: Vec<f64> = e.iter().map(|x| 100.0 * x / e0).collect();
    analysis::fit_power_law(&analysis::log_bins(&pct, lo, hi, BINS_PER_DECADE))
}

/// One container's curve and its analysis.
#[derive(Clone, Debug)]
pub struct ContainerFit {
    pub key: String,
    pub label: String,
    pub e0: f64,
    pub er: Vec<f64>,
    pub window: (usize, usize),
    pub fit: Option<PowerFit>,
    pub onset: Option<usize>,
    pub collapse: Option<Collapse>,
    /// Fits over [`WINDOWS`].
    pub windows: Vec<((usize, usize), Option<PowerFit>)>,
}

/// Binned curve of a container from its leak onset on (the collapse input).
pub fn onset_bins(e: &[f64]) -> (Option<usize>, Vec<LogPoint>) {
    let onset = analysis::leak_onset(e, ONSET_FRACTION);
    let bins = onset.map_or_else(Vec::new, |o| {
        analysis::log_bins(e, o, e.len() - 1, BINS_PER_DECADE)
    });
    (onset, bins)
}

/// Fit every container and collapse each onto the reference (key `a`).
pub fn fig45(curves: Vec<(String, String, Vec<f64>, f64)>) -> Result<Vec<ContainerFit>, Error> {
    let reference = curves
        .iter()
        .find(|c| c.0 == "a")
        .ok_or_else(|| Error::Other("fig5: the reference container (a) is missing".into()))?;
    let (_, ref_bins) = onset_bins(&reference.2);
    let rule = CollapseRule::default();
    let mut out = Vec::new();
    for (key, label, er, e0) in curves {
        let n = er.len() - 1;
        let (onset, bins) = onset_bins(&er);
        let window = fit_window(n, onset);
        let fit = fit_percent(&er, e0, window.0, window.1);
        let collapse = if key == "a" {
            Some(Collapse {
                alpha: 1.0,
                rms: 0.0,
                t_lo: ref_bins.first().map_or(f64::NAN, |p| p.ln_t.exp()),
                t_hi: ref_bins.last().map_or(f64::NAN, |p| p.ln_t.exp()),
            })
        } else {
            analysis::collapse(&ref_bins, &bins, &rule)
        };
        let windows = WINDOWS
            .iter()
            .map(|&(a, b)| {
                let w = (
                    ((a * n as f64).round() as usize).max(onset.unwrap_or(1)),
                    (b * n as f64).round() as usize,
                );
                (w, fit_percent(&er, e0, w.0, w.1))
            })
            .collect();
        out.push(ContainerFit {
            key,
            label,
            e0,
            er,
            window,
            fit,
            onset,
            collapse,
            windows,
        });
    }
    Ok(out)
}

/// Comparison of two `E_R` curves over their common snapshots.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CurveDiff {
    /// Largest `|E - E_ref| / E_ref` over snapshots with `E_ref >= floor * E0`.
    pub max_rel: f64,
    pub at: usize,
    /// First snapshot whose bits differ.
    pub first_bit_difference: Option<usize>,
    /// First snapshot at which the relative difference exceeds `level` (1e-4).
    pub first_above_level: Option<usize>,
    pub snapshots: usize,
}

/// Relative differences are taken where the reference holds at least this fraction of the
/// striker's energy: below it only the super-exponentially small precursor of the incident wave
/// has entered, whose relative value means nothing.
pub const ENERGY_FLOOR: f64 = 1e-3;

/// The accuracy level of the issue (requirement 6).
pub const LEVEL: f64 = 1e-4;

pub fn curve_diff(e: &[f64], reference: &[f64], e0: f64) -> CurveDiff {
    let m = e.len().min(reference.len());
    let mut d = CurveDiff {
        max_rel: 0.0,
        at: 0,
        first_bit_difference: None,
        first_above_level: None,
        snapshots: m,
    };
    for k in 0..m {
        if d.first_bit_difference.is_none() && e[k].to_bits() != reference[k].to_bits() {
            d.first_bit_difference = Some(k);
        }
        if reference[k] >= ENERGY_FLOOR * e0 {
            let r = (e[k] - reference[k]).abs() / reference[k];
            if r > d.max_rel {
                d.max_rel = r;
                d.at = k;
            }
            if r > LEVEL && d.first_above_level.is_none() {
                d.first_above_level = Some(k);
            }
        }
    }
    d
}

/// Largest relative difference over snapshots `0..end` (same floor as [`curve_diff`]).
pub fn max_rel_until(e: &[f64], reference: &[f64], e0: f64, end: usize) -> f64 {
    let m = e.len().min(reference.len()).min(end);
    (0..m)
        .filter(|&k| reference[k] >= ENERGY_FLOOR * e0)
        .map(|k| (e[k] - reference[k]).abs() / reference[k])
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_diff_finds_first_difference_and_ignores_the_floor() {
        let r = vec![0.0, 1e-9, 100.0, 100.0, 100.0];
        let e = vec![0.0, 2e-9, 100.0, 100.02, 100.0];
        let d = curve_diff(&e, &r, 100.0);
        assert_eq!(d.first_bit_difference, Some(1));
        assert_eq!(d.first_above_level, Some(3));
        assert_eq!(d.at, 3);
        assert!((d.max_rel - 2e-4).abs() < 1e-12);
    }
}
