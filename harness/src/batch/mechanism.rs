//! The paper's mechanism in one member: the reflections counted at the container's edges
//! ([`grainchain_engine::Simulation::watch_reflections`]) and the speed of the pulses inside,
//! summed in bins of time and of amplitude, so that members add up into ensemble rates.
//!
//! - Time bins: 5 per decade of the output index (edges `round(10^(j/5))`, distinct, from 1 to
//!   the run's last output), the study's `t` in snapshots.
//! - A hit is a *reflection* when it sent energy out (transmitted >= 0); a hit that brought
//!   energy in (the impulse entering, a wave coming back from outside) is *inflow* and counted
//!   apart.
//! - Amplitude bins of the reflections: 4 per decade of the incident energy over the member's
//!   initial energy, from 1e-12 to 1.
//! - Speeds: the pulses of the container ([`grainchain_engine::detect_pulses`] over its grains
//!   at every output) linked output to output ([`grainchain_engine::Tracker`]); a link's speed is
//!   its move from one output to the next, in grains per snapshot, weighted by the pulse's energy.

use grainchain_engine::{detect_pulses, Pulse, PulseRule, Reflection, TrackRule, Tracker};
use serde::{Deserialize, Serialize};

/// Time bins per decade.
pub const TIME_BINS_PER_DECADE: f64 = 5.0;
/// Amplitude bins per decade, and the smallest amplitude binned.
pub const AMPLITUDE_BINS_PER_DECADE: f64 = 4.0;
/// The lowest amplitude bin's lower edge, as a power of ten.
pub const AMPLITUDE_FROM_DECADE: i32 = -12;

/// The edges of the time bins of a run of `outputs` outputs, in outputs.
pub fn time_edges(outputs: u64) -> Vec<u64> {
    let mut e: Vec<u64> = Vec::new();
    let mut j = 0;
    loop {
        let x = 10f64.powf(j as f64 / TIME_BINS_PER_DECADE).round() as u64;
        if x > outputs {
            break;
        }
        if e.last() != Some(&x) {
            e.push(x);
        }
        j += 1;
    }
    if e.last() != Some(&outputs) && outputs > 1 {
        e.push(outputs);
    }
    e
}

/// The lower edge of amplitude bin `j` (incident energy over initial energy).
pub fn amplitude_edge(j: usize) -> f64 {
    10f64.powf(AMPLITUDE_FROM_DECADE as f64 + j as f64 / AMPLITUDE_BINS_PER_DECADE)
}

/// Number of amplitude bins (up to 1).
pub fn amplitude_bins() -> usize {
    (-AMPLITUDE_FROM_DECADE as f64 * AMPLITUDE_BINS_PER_DECADE) as usize
}

/// Sums over one time bin.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TimeBin {
    /// Reflections (hits that sent energy out), both edges.
    pub hits: u64,
    /// Their incident energies.
    pub incident: f64,
    /// Their transmitted energies.
    pub transmitted: f64,
    /// Inflow hits and the energy they brought in.
    pub inflow_hits: u64,
    /// The energy the inflow hits brought in (positive).
    pub inflow: f64,
    /// Sum over pulse links of energy times speed (grains per snapshot).
    pub speed_weighted: f64,
    /// Sum over pulse links of energy.
    pub speed_weight: f64,
}

/// Sums over one amplitude bin of the reflections.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AmplitudeBin {
    /// Reflections.
    pub hits: u64,
    /// Their incident energies.
    pub incident: f64,
    /// Their transmitted energies.
    pub transmitted: f64,
}

/// One member's mechanism (module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MemberMechanism {
    /// The time bins' edges, in outputs ([`time_edges`]).
    pub edges: Vec<u64>,
    /// Per time bin.
    pub time: Vec<TimeBin>,
    /// Per amplitude bin ([`amplitude_edge`]).
    pub amplitude: Vec<AmplitudeBin>,
}

impl MemberMechanism {
    /// Empty bins for a run of `outputs` outputs.
    pub fn new(outputs: u64) -> Self {
        let edges = time_edges(outputs);
        MemberMechanism {
            time: vec![TimeBin::default(); edges.len().saturating_sub(1)],
            edges,
            amplitude: vec![AmplitudeBin::default(); amplitude_bins()],
        }
    }

    /// The time bin of output `x` (fractional), if inside the bins (the last bin holds its
    /// upper edge, the run's end).
    fn bin_of(&self, x: f64) -> Option<usize> {
        let (first, last) = (*self.edges.first()?, *self.edges.last()?);
        if x < first as f64 || x > last as f64 || self.time.is_empty() {
            return None;
        }
        Some((self.edges.partition_point(|&e| (e as f64) <= x) - 1).min(self.time.len() - 1))
    }

    /// Add the hits of a run with output interval `interval` and initial energy `e0`.
    pub fn add_hits(&mut self, hits: &[Reflection], interval: f64, e0: f64) {
        for h in hits {
            let Some(b) = self.bin_of(h.time / interval) else {
                continue;
            };
            let t = &mut self.time[b];
            if h.transmitted < 0.0 {
                t.inflow_hits += 1;
                t.inflow -= h.transmitted;
                continue;
            }
            t.hits += 1;
            t.incident += h.incident;
            t.transmitted += h.transmitted;
            let a = h.incident / e0;
            if a > 0.0 {
                let j = ((a.log10() - AMPLITUDE_FROM_DECADE as f64) * AMPLITUDE_BINS_PER_DECADE)
                    .floor();
                if j >= 0.0 && (j as usize) < self.amplitude.len() {
                    let x = &mut self.amplitude[j as usize];
                    x.hits += 1;
                    x.incident += h.incident;
                    x.transmitted += h.transmitted;
                }
            }
        }
    }

    /// Add the pulse speeds from the container's grains at every output: `energy[t]` and
    /// `velocity[t]` the grains' energies and velocities at output `t`, `interval` the output
    /// interval.
    pub fn add_speeds(&mut self, energy: &[Vec<f64>], velocity: &[Vec<f64>], interval: f64) {
        let rule = PulseRule::default();
        let mut tracker = Tracker::new(TrackRule::default());
        let mut ended = Vec::new();
        let zeros = vec![0.0; energy.first().map_or(0, |e| e.len())];
        let mut previous: Vec<(u64, f64)> = Vec::new();
        for (t, (e, v)) in energy.iter().zip(velocity).enumerate() {
            let pulses: Vec<Pulse> = detect_pulses(e, v, &rule);
            tracker.push(t as u64, t as f64 * interval, &pulses, &zeros, &mut ended);
            ended.clear();
            // Each open track's newest point: a link when its previous point was the last
            // output.
            let mut now = Vec::new();
            for tr in tracker.open_tracks() {
                let p = tr.points.last().expect("a track has a point");
                now.push((tr.id, p.position));
                if let Some(&(_, x0)) = previous.iter().find(|(id, _)| *id == tr.id) {
                    if tr.points.len() >= 2 {
                        if let Some(b) = self.bin_of(t as f64 - 0.5) {
                            let speed = (p.position - x0).abs();
                            self.time[b].speed_weighted += p.energy * speed;
                            self.time[b].speed_weight += p.energy;
                        }
                    }
                }
            }
            previous = now;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_edges_are_distinct_and_end_at_the_run() {
        let e = time_edges(8000);
        assert_eq!(&e[..6], &[1, 2, 3, 4, 6, 10]);
        assert_eq!(*e.last().unwrap(), 8000);
        assert!(e.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn hits_fall_in_their_bins() {
        let mut m = MemberMechanism::new(1000);
        let hit = |time: f64, incident: f64, transmitted: f64| Reflection {
            edge: grainchain_engine::Edge::Left,
            time,
            peak_force: 1.0,
            incident,
            transmitted,
        };
        // Interval 0.5: output 15 is t = 7.5, in bin [10, 16).
        m.add_hits(&[hit(7.5, 0.1, 0.02), hit(7.6, 0.0, -0.3)], 0.5, 1.0);
        let b = m.edges.iter().position(|&e| e == 10).unwrap();
        assert_eq!(m.time[b].hits, 1);
        assert_eq!(m.time[b].inflow_hits, 1);
        assert_eq!(m.time[b].inflow, 0.3);
        let j = ((0.1f64.log10() + 12.0) * 4.0).floor() as usize;
        assert_eq!(m.amplitude[j].hits, 1);
        assert_eq!(m.amplitude[j].transmitted, 0.02);
    }
}
