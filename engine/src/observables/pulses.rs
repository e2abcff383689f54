//! Splitting a snapshot into separate pulses.
//!
//! The rule, applied to the per-grain energies `e_i` of one snapshot:
//! 1. A grain is *lit* when `e_i > threshold * max_j e_j` (and `e_i > 0`).
//! 2. A maximal run of consecutive lit grains is a candidate pulse.
//! 3. Inside a candidate, a local minimum `e_m` between two local maxima splits it in two when
//!    `e_m < valley * min(left peak, right peak)`: two solitary waves whose tails overlap are
//!    still two pulses once a clear dip separates them.
//! 4. Each pulse reports its grain range, its energy-weighted centre, its peak velocity (the
//!    velocity of largest magnitude, with its sign) and its energy (the sum of `e_i`).
//!
//! Defaults: threshold 1e-4, valley 0.25. A discrete solitary wave is about five grains wide
//! and its tails fall super-exponentially, so one wave lights 5-9 grains at these settings.

use serde::{Deserialize, Serialize};

/// The thresholds of the pulse rule.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PulseRule {
    /// A grain belongs to a pulse when its energy exceeds this fraction of the largest grain
    /// energy in the snapshot.
    #[serde(default = "default_threshold")]
    pub threshold: f64,
    /// A dip below this fraction of the smaller neighbouring peak splits a run in two.
    #[serde(default = "default_valley")]
    pub valley: f64,
}

fn default_threshold() -> f64 {
    1e-4
}
fn default_valley() -> f64 {
    0.25
}

impl Default for PulseRule {
    fn default() -> Self {
        PulseRule {
            threshold: default_threshold(),
            valley: default_valley(),
        }
    }
}

/// One detected pulse. Grain indices are positions in the slices passed to [`detect_pulses`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Pulse {
    /// Index of the pulse's first grain (inclusive).
    pub first: usize,
    /// Index of the pulse's last grain (inclusive).
    pub last: usize,
    /// Energy-weighted centre (in the same index units).
    pub position: f64,
    /// Velocity of largest magnitude in the pulse, with its sign.
    pub peak_velocity: f64,
    /// Energy of the pulse: the sum of its grains' energies.
    pub energy: f64,
}

/// Split `energy` (per grain) into pulses by the rule in the module docs.
pub fn detect_pulses(energy: &[f64], velocity: &[f64], rule: &PulseRule) -> Vec<Pulse> {
    let emax = energy.iter().cloned().fold(0.0, f64::max);
    let mut out = Vec::new();
    if emax <= 0.0 || !emax.is_finite() {
        return out;
    }
    let cut = rule.threshold * emax;
    let mut i = 0;
    let n = energy.len();
    while i < n {
        if !(energy[i] > cut && energy[i] > 0.0) {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && energy[i] > cut && energy[i] > 0.0 {
            i += 1;
        }
        split_run(energy, velocity, start, i, rule.valley, &mut out);
    }
    out
}

/// Split the run `[a, b)` at deep valleys and push the pieces.
fn split_run(e: &[f64], v: &[f64], a: usize, b: usize, valley: f64, out: &mut Vec<Pulse>) {
    // Local maxima and minima in order (plateaus count once).
    let mut cuts = vec![a];
    let mut last_peak: Option<f64> = None;
    let mut pending_min: Option<(usize, f64)> = None;
    for i in a..b {
        let left = if i > a { e[i - 1] } else { f64::NEG_INFINITY };
        let right = if i + 1 < b {
            e[i + 1]
        } else {
            f64::NEG_INFINITY
        };
        if e[i] >= left && e[i] > right {
            // a peak
            if let (Some(p), Some((m, em))) = (last_peak, pending_min) {
                if em < valley * p.min(e[i]) {
                    cuts.push(m);
                    last_peak = Some(e[i]);
                    pending_min = None;
                    continue;
                }
            }
            last_peak = Some(last_peak.map_or(e[i], |p| p.max(e[i])));
            pending_min = None;
        } else if i > a && i + 1 < b && e[i] <= left && e[i] < right {
            // a valley: remember the lowest since the last peak
            if pending_min.is_none_or(|(_, em)| e[i] < em) {
                pending_min = Some((i, e[i]));
            }
        }
    }
    cuts.push(b);
    for w in cuts.windows(2) {
        let (s, t) = (w[0], w[1]);
        if s >= t {
            continue;
        }
        let energy: f64 = e[s..t].iter().sum();
        let position = (s..t).map(|i| i as f64 * e[i]).sum::<f64>() / energy;
        let peak_velocity =
            v[s..t]
                .iter()
                .cloned()
                .fold(0.0, |m: f64, x| if x.abs() > m.abs() { x } else { m });
        out.push(Pulse {
            first: s,
            last: t - 1,
            position,
            peak_velocity,
            energy,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bump(n: usize, centre: f64, height: f64, e: &mut [f64]) {
        for (i, x) in e.iter_mut().enumerate().take(n) {
            let d = i as f64 - centre;
            *x += height * (-d * d).exp();
        }
    }

    #[test]
    fn separated_bumps_are_separate_pulses() {
        let mut e = vec![0.0; 60];
        bump(60, 10.0, 1.0, &mut e);
        bump(60, 40.0, 0.3, &mut e);
        let v = e.iter().map(|x| x.sqrt()).collect::<Vec<_>>();
        let p = detect_pulses(&e, &v, &PulseRule::default());
        assert_eq!(p.len(), 2);
        assert!((p[0].position - 10.0).abs() < 1e-9 && (p[1].position - 40.0).abs() < 1e-9);
        // Only lit grains count: |d| <= 3 for the first bump, |d| <= 2 for the second (threshold
        // 1e-4 of the peak), so the ratio is 1/0.3 up to the truncated Gaussian tails (~2e-4).
        assert!((p[0].energy / p[1].energy * 0.3 - 1.0).abs() < 1e-3);
        assert_eq!(p[0].peak_velocity, 1.0);
    }

    #[test]
    fn touching_bumps_split_at_deep_valley_only() {
        let mut e = vec![0.0; 40];
        bump(40, 10.0, 1.0, &mut e);
        bump(40, 14.0, 0.5, &mut e); // valley ~ 1.9e-2 at grain 12: deep -> split
        let v = vec![0.0; 40];
        assert_eq!(detect_pulses(&e, &v, &PulseRule::default()).len(), 2);
        let mut e = vec![0.0; 40];
        bump(40, 10.0, 1.0, &mut e);
        bump(40, 11.5, 0.5, &mut e); // shallow dip: one pulse
        assert_eq!(detect_pulses(&e, &v, &PulseRule::default()).len(), 1);
    }

    #[test]
    fn empty_and_zero_snapshots() {
        assert!(detect_pulses(&[], &[], &PulseRule::default()).is_empty());
        assert!(detect_pulses(&[0.0; 5], &[0.0; 5], &PulseRule::default()).is_empty());
    }
}
