//! Pulses followed from one output to the next: tracks with a speed and a true peak velocity.
//!
//! [`detect_pulses`](super::detect_pulses) splits one snapshot into pulses. A [`Tracker`] links
//! the pulses of consecutive detections into [`Track`]s:
//!
//! 1. Prediction. A track with two or more points is predicted at `x + u dt` (`u` its speed over
//!    its last two points); a track with one point has no speed yet and may only move in the
//!    direction of its velocity (the sign of its peak velocity: a compression pulse moves the
//!    grains it passes the way it travels), by at most [`TrackRule::max_jump`] grains, with
//!    [`SLACK`] grains of slack backwards.
//! 2. Gate. A pulse is a candidate for a predicted track when it lies within
//!    `max(SLACK, GATE * |u dt|)` grains of the prediction (and within `max_jump` of the last
//!    position).
//! 3. Assignment. Candidate pairs are taken nearest first, each track and pulse at most once.
//!    A pulse left over starts a new track; a track left over ends.
//!
//! The *true peak velocity* of a track point is the largest |v| reached, at any step, by the
//! grains the pulse swept since the previous detection (from the previous extent to the current
//! one), with the sign of the pulse's velocity. The per-grain peaks come from the caller; the
//! [`Recorder`](crate::recorder::Recorder) keeps each grain's peak while a pulse covers the grain
//! at a detection and starts it again once none does, so a pulse that takes several detections
//! to pass a grain still gets that grain's whole peak. The peak at the output
//! instant (what a snapshot shows) is kept beside it: it depends on where between grains the
//! pulse happens to be at that instant and is below the true peak. Pulses that meet sweep the
//! same grains and may share a peak.

use super::Pulse;
use serde::{Deserialize, Serialize};

/// Slack in grains of the gates: a slow or standing pulse's centre of energy jitters by about a
/// grain between outputs.
pub const SLACK: f64 = 2.0;
/// Half-width of the gate around a prediction, relative to the predicted move: a pulse may change
/// speed by up to half between two detections (an interface between masses) and stay linked.
pub const GATE: f64 = 0.5;

/// Tracking settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackRule {
    /// Largest move in grains between two detections (infinite by default).
    pub max_jump: f64,
}

impl Default for TrackRule {
    fn default() -> Self {
        TrackRule {
            max_jump: f64::INFINITY,
        }
    }
}

/// A pulse on a track at one detection. Grain indices and positions are internal indices of the
/// chain.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackPoint {
    /// Output index and time.
    pub index: u64,
    /// Simulated time of the detection (`index * interval`).
    pub time: f64,
    /// Centre of energy.
    pub position: f64,
    /// Internal index of the pulse's first grain (inclusive).
    pub first: usize,
    /// Internal index of the pulse's last grain (inclusive).
    pub last: usize,
    /// Energy of the pulse: the sum of its grains' energies.
    pub energy: f64,
    /// The true peak: largest |v| reached by the grains swept since the previous detection, at
    /// any step, with the sign of the pulse's velocity (module docs).
    pub peak_velocity: f64,
    /// Velocity of largest magnitude in the pulse at the output instant, with its sign.
    pub instant_peak_velocity: f64,
}

/// One pulse followed over consecutive detections.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Track {
    /// 1, 2, ... in the order the tracks started (pulses of one detection: left to right).
    pub id: u64,
    /// The pulse at each detection it was found at, in time order (consecutive detections).
    pub points: Vec<TrackPoint>,
}

impl Track {
    /// Speed in grains per unit time: the least-squares slope of position against time over the
    /// whole track (`None` with fewer than two points).
    pub fn speed(&self) -> Option<f64> {
        let n = self.points.len();
        if n < 2 {
            return None;
        }
        let tm = self.points.iter().map(|p| p.time).sum::<f64>() / n as f64;
        let xm = self.points.iter().map(|p| p.position).sum::<f64>() / n as f64;
        let (mut sxt, mut stt) = (0.0, 0.0);
        for p in &self.points {
            sxt += (p.time - tm) * (p.position - xm);
            stt += (p.time - tm) * (p.time - tm);
        }
        (stt > 0.0).then(|| sxt / stt)
    }

    /// Speed over the last two points (`None` with fewer than two).
    fn last_speed(&self) -> Option<f64> {
        let n = self.points.len();
        if n < 2 {
            return None;
        }
        let (a, b) = (&self.points[n - 2], &self.points[n - 1]);
        (b.time > a.time).then(|| (b.position - a.position) / (b.time - a.time))
    }
}

/// Links pulses detection by detection (the module docs give the rule).
#[derive(Clone, Debug, Default)]
pub struct Tracker {
    rule: TrackRule,
    open: Vec<Track>,
    next_id: u64,
}

impl Tracker {
    /// A tracker with no tracks yet.
    pub fn new(rule: TrackRule) -> Self {
        Tracker {
            rule,
            open: Vec::new(),
            next_id: 1,
        }
    }

    /// Add the pulses of one detection at output `index`, time `time`. `pulses` are in internal
    /// grain indices of the chain, sorted left to right (as [`super::detect_pulses`] returns
    /// them, shifted); `peak_speed[i]` is the largest |v| of grain `i` since the previous
    /// detection (or since a pulse first covered it: see the module docs). Tracks that end here are pushed onto `ended`, in the order of their ids.
    pub fn push(
        &mut self,
        index: u64,
        time: f64,
        pulses: &[Pulse],
        peak_speed: &[f64],
        ended: &mut Vec<Track>,
    ) {
        let max_jump = self.rule.max_jump;
        // Candidate pairs (distance to the prediction, track, pulse).
        let mut pairs = Vec::new();
        for (k, tr) in self.open.iter().enumerate() {
            let last = tr.points.last().unwrap();
            let dt = time - last.time;
            for (j, p) in pulses.iter().enumerate() {
                let step = p.position - last.position;
                if step.abs() > max_jump {
                    continue;
                }
                let d = match tr.last_speed() {
                    Some(u) => {
                        let d = (p.position - (last.position + u * dt)).abs();
                        if d > SLACK.max(GATE * (u * dt).abs()) {
                            continue;
                        }
                        d
                    }
                    None => {
                        if step * last.peak_velocity.signum() < -SLACK {
                            continue;
                        }
                        step.abs()
                    }
                };
                pairs.push((d, k, j));
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut track_of = vec![None; pulses.len()];
        let mut taken = vec![false; self.open.len()];
        for (_, k, j) in pairs {
            if !taken[k] && track_of[j].is_none() {
                taken[k] = true;
                track_of[j] = Some(k);
            }
        }
        let point = |p: &Pulse, from: Option<&TrackPoint>| {
            // The grains swept since the previous detection.
            let (a, b) = match from {
                Some(q) => (p.first.min(q.first), p.last.max(q.last)),
                None => (p.first, p.last),
            };
            let b = b.min(peak_speed.len().saturating_sub(1));
            let peak = peak_speed
                .get(a..=b)
                .unwrap_or(&[])
                .iter()
                .fold(p.peak_velocity.abs(), |m, &x| m.max(x));
            TrackPoint {
                index,
                time,
                position: p.position,
                first: p.first,
                last: p.last,
                energy: p.energy,
                peak_velocity: peak.copysign(p.peak_velocity),
                instant_peak_velocity: p.peak_velocity,
            }
        };
        let mut next: Vec<Option<Track>> = self.open.drain(..).map(Some).collect();
        let mut open = Vec::with_capacity(pulses.len());
        for (j, p) in pulses.iter().enumerate() {
            match track_of[j] {
                Some(k) => {
                    let mut tr = next[k].take().unwrap();
                    let pt = point(p, tr.points.last());
                    tr.points.push(pt);
                    open.push(tr);
                }
                None => {
                    open.push(Track {
                        id: self.next_id,
                        points: vec![point(p, None)],
                    });
                    self.next_id += 1;
                }
            }
        }
        let mut gone: Vec<Track> = next.into_iter().flatten().collect();
        gone.sort_by_key(|t| t.id);
        ended.extend(gone);
        self.open = open;
    }

    /// The tracks still open (found at the latest detection), left to right.
    pub fn open_tracks(&self) -> &[Track] {
        &self.open
    }

    /// End every open track (at the end of a run), in the order of their ids.
    pub fn finish(&mut self) -> Vec<Track> {
        let mut all: Vec<Track> = self.open.drain(..).collect();
        all.sort_by_key(|t| t.id);
        all
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pulse(x: f64, v: f64) -> Pulse {
        Pulse {
            first: (x - 2.0).max(0.0) as usize,
            last: (x + 2.0) as usize,
            position: x,
            peak_velocity: v,
            energy: 1.0,
        }
    }

    #[test]
    fn two_pulses_moving_apart_keep_their_tracks() {
        let mut tr = Tracker::new(TrackRule::default());
        let peaks = vec![0.0; 200];
        let mut ended = vec![];
        // A right-moving pulse at 10 + 8t and a left-moving one at 100 - 6t, detected every 1.
        for k in 0..6u64 {
            let t = k as f64;
            let ps = [pulse(10.0 + 8.0 * t, 1.0), pulse(100.0 - 6.0 * t, -0.5)];
            tr.push(k, t, &ps, &peaks, &mut ended);
        }
        assert!(ended.is_empty());
        let all = tr.finish();
        assert_eq!(all.len(), 2);
        // Exact positions on a line: the fit is exact to round-off.
        assert!((all[0].speed().unwrap() - 8.0).abs() < 1e-12);
        assert!((all[1].speed().unwrap() + 6.0).abs() < 1e-12);
        assert!(all[1].points.iter().all(|p| p.peak_velocity == -0.5));
    }

    #[test]
    fn a_pulse_behind_the_direction_of_travel_starts_a_new_track() {
        let mut tr = Tracker::new(TrackRule::default());
        let peaks = vec![0.0; 100];
        let mut ended = vec![];
        tr.push(0, 0.0, &[pulse(50.0, 1.0)], &peaks, &mut ended);
        // Moving right (v > 0) but found 10 grains to the left: not the same pulse.
        tr.push(1, 1.0, &[pulse(40.0, 1.0)], &peaks, &mut ended);
        assert_eq!(ended.len(), 1);
        assert_eq!(ended[0].id, 1);
        assert_eq!(tr.open[0].id, 2);
    }

    #[test]
    fn true_peak_is_the_largest_swept_speed() {
        let mut tr = Tracker::new(TrackRule::default());
        let mut peaks = vec![0.0; 100];
        let mut ended = vec![];
        tr.push(0, 0.0, &[pulse(20.0, 0.8)], &peaks, &mut ended);
        // Between the detections grain 25 (between the two extents) reached 1.0.
        peaks[25] = 1.0;
        peaks[60] = 5.0; // not swept: ignored
        tr.push(1, 1.0, &[pulse(30.0, 0.7)], &peaks, &mut ended);
        let p = &tr.open[0].points[1];
        assert_eq!((p.peak_velocity, p.instant_peak_velocity), (1.0, 0.7));
    }
}
