//! Pulse tracking against physics: one Nesterenko solitary wave on a uniform Hertz chain
//! (physics.md 2 and 3), followed from output to output by the recorder.

use crate::common;

use common::{g, record_one, Row};
use grainchain_engine::Recorder;
use grainchain_engine::{ChainBuilder, ContactLaw, SimulationBuilder};
use grainchain_engine::{PulseRule, Track, TrackPoint, TrackRule};

const N: usize = 400;
const ETA: f64 = 5657.0;
/// Output interval: not a multiple of the time the wave takes per grain, so the output instants
/// fall at every phase of the wave between grains.
const INTERVAL: f64 = 0.0173;
/// The measured stretch of the chain: from grain 40 (the wave has formed: its energy changes by
/// less than 1e-5 relative after about 10 grains) to grain 280 (far from the free end).
const FROM: f64 = 40.0;
const TO: f64 = 280.0;

struct Wave {
    /// All tracks of the run.
    tracks: Vec<Track>,
    /// The points of the wave's track inside the measured stretch.
    points: Vec<TrackPoint>,
    speed: f64,
}

/// Grain 0 of a uniform Hertz chain (m = 1) struck at speed `v0` (verlet, dt = 1e-4), tracked at
/// every output until the wave is past grain `TO`.
fn wave(v0: f64) -> Wave {
    let chain = ChainBuilder::new()
        .grains(N, 1.0, ContactLaw::hertz(ETA))
        .build()
        .unwrap();
    // Measured: about 26.6 grains per unit time at v0 = 1, scaling as v0^(1/5) (physics.md 3).
    let duration = (TO + 20.0) / (26.6 * v0.powf(0.2));
    let mut sim = SimulationBuilder::new(chain)
        .schedule(duration, INTERVAL)
        .velocity(0, v0)
        .build()
        .unwrap();
    let rec = Recorder::new()
        .time_series(false)
        .tracks(PulseRule::default(), TrackRule::default(), 1)
        .record(&mut sim)
        .unwrap();
    assert!(rec.finished);
    let tracks = rec.tracks;
    let main = tracks
        .iter()
        .max_by(|a, b| a.points[0].energy.total_cmp(&b.points[0].energy))
        .unwrap();
    let points: Vec<TrackPoint> = main
        .points
        .iter()
        .filter(|p| p.position >= FROM && p.position <= TO)
        .cloned()
        .collect();
    let sub = Track {
        id: main.id,
        points: points.clone(),
    };
    Wave {
        speed: sub.speed().unwrap(),
        tracks,
        points,
    }
}

fn spread(x: impl Iterator<Item = f64> + Clone) -> (f64, f64, f64) {
    let lo = x.clone().fold(f64::INFINITY, f64::min);
    let hi = x.clone().fold(f64::NEG_INFINITY, f64::max);
    let n = x.clone().count() as f64;
    (lo, hi, x.sum::<f64>() / n)
}

/// One wave, one track; its speed is constant and its true peak velocity too, while the peak
/// at the output instant scatters below it.
#[test]
fn a_solitary_wave_is_one_track_with_constant_speed_and_peak() {
    let w = wave(1.0);
    // The wave's track holds every detection from the strike on (it never broke up). A second,
    // slow track is the struck grain's small backward residue (0.6 % of the energy), left
    // behind at grain 0.
    let big: Vec<&Track> = w
        .tracks
        .iter()
        .filter(|t| t.points.last().unwrap().energy > 0.1)
        .collect();
    let n_points = w.points.len();
    // Speed constancy: local speeds over one grain transit (about 2 outputs apart, 1/26.6 =
    // 0.0376 > 2 x 0.0173) against the fit over the whole stretch.
    let step = 3;
    let local: Vec<f64> = w
        .points
        .windows(step + 1)
        .map(|p| (p[step].position - p[0].position) / (p[step].time - p[0].time))
        .collect();
    let (slo, shi, _) = spread(local.iter().copied());
    let speed_dev = (shi - slo) / w.speed;
    // True peak constancy.
    let (plo, phi, pmean) = spread(w.points.iter().map(|p| p.peak_velocity));
    let peak_dev = (phi - plo) / pmean;
    // The instant peak.
    let (ilo, ihi, imean) = spread(w.points.iter().map(|p| p.instant_peak_velocity));
    // One pulse: a single track of energy above 0.1 (the wave holds 0.497 of 0.5), holding
    // every output of the stretch, consecutive.
    let one = big.len() == 1
        && w.points.windows(2).all(|p| p[1].index == p[0].index + 1)
        && n_points > 400;
    record_one(
        Row::new("tracking: one solitary wave", "p=1.5, v0=1", "physics.md 2")
            .expected("one track over grains 40..280")
            .measured(format!(
                "{} track(s) of energy > 0.1, {n_points} points",
                big.len()
            ))
            .tolerance("exact")
            .pass(one),
    );
    assert!(one, "{} big tracks, {n_points} points", big.len());
    // Speed: the centre of energy of a discrete wave jitters by a few 1e-3 grains with the phase
    // between grains, so local speeds over a 1.4-grain baseline scatter by a few 1e-3
    // (measured 2.9e-3); 1 % fails a wave that slows by 1 % over the stretch.
    let ok = speed_dev < 0.01;
    record_one(
        Row::new("tracking: constant speed", "p=1.5, v0=1", "physics.md 2")
            .expected(format!("{} grains/time throughout", g(w.speed)))
            .measured(format!(
                "local {}..{} (spread {:.2e})",
                g(slo),
                g(shi),
                speed_dev
            ))
            .tolerance("1e-2 relative")
            .pass(ok),
    );
    assert!(ok, "local speeds {slo}..{shi}");
    // True peak: every grain reaches the same peak in a steady wave; verlet samples it once per
    // step, at most dt/2 from the maximum, where the velocity profile ~ cos^4(k x) (physics.md 2,
    // k = 0.632 per grain) has dropped by 2 (k V dt/2)^2 = 1.4e-6 relative at V = 26.6, dt = 1e-4
    // (measured spread 1.9e-6); 1e-5 leaves room for that and fails a peak taken at an output.
    let ok = peak_dev < 1e-5;
    record_one(
        Row::new(
            "tracking: constant true peak",
            "p=1.5, v0=1",
            "physics.md 2",
        )
        .expected("the same peak velocity at every grain")
        .measured(format!("{}..{} (spread {:.2e})", g(plo), g(phi), peak_dev))
        .tolerance("1e-5 relative")
        .pass(ok),
    );
    assert!(ok, "true peaks {plo}..{phi}");
    // The peak at the output instant: the output falls at any phase of the wave between two
    // grains' peaks (one per 1/V = 0.038 time units), so it scatters below the true peak by tens
    // of percent (measured down to 0.76 of it); asked: at least 10 % below at some output and
    // never above.
    let ok = ilo < 0.9 * pmean
        && w.points
            .iter()
            .all(|p| p.instant_peak_velocity <= p.peak_velocity);
    record_one(
        Row::new(
            "tracking: instant peak scatters below",
            "p=1.5, v0=1",
            "definition",
        )
        .expected("instant peak <= true peak, down to < 0.9 of it")
        .measured(format!(
            "{}..{} (mean {}), true {}",
            g(ilo),
            g(ihi),
            g(imean),
            g(pmean)
        ))
        .tolerance("min < 0.9 true")
        .pass(ok),
    );
    assert!(ok, "instant peaks {ilo}..{ihi}, true {pmean}");
}

/// The Hertz speed law V ~ v_max^(1/5) (physics.md 2; exact for the discrete chain by the
/// amplitude symmetry of physics.md 3), from the tracks of two striker speeds.
#[test]
fn wave_speed_scales_as_the_fifth_root_of_the_true_peak() {
    let (a, b) = (wave(1.0), wave(8.0));
    let peak = |w: &Wave| spread(w.points.iter().map(|p| p.peak_velocity)).2;
    let expo = (b.speed / a.speed).ln() / (peak(&b) / peak(&a)).ln();
    let inst = |w: &Wave| spread(w.points.iter().map(|p| p.instant_peak_velocity)).2;
    let expo_inst = (b.speed / a.speed).ln() / (inst(&b) / inst(&a)).ln();
    // The amplitude symmetry makes the exponent exact; what is measured carries the speed fit
    // (jitter 3e-3 over 1.4 grains, averaged over ~500 points: ~1e-5 relative), the true peak
    // (1.4e-6 relative at v0 = 1, 8^(2/5) x that at v0 = 8) and the integrators' O(dt^2) phase
    // error (~1e-5): ratio errors of ~1e-5, i.e. 5e-6 in the exponent over ln 8. 1e-4 leaves
    // room and fails any other law ((p-1)/(p+1) for p = 1.6 is 0.23).
    let ok = (expo - 0.2).abs() < 1e-4;
    record_one(
        Row::new(
            "tracking: V ~ v_max^(1/5)",
            "p=1.5, v0=1 and 8",
            "physics.md 2, 3",
        )
        .expected("0.2")
        .measured(format!(
            "{} (speeds {}, {}; true peaks {}, {}; from instant peaks {})",
            g(expo),
            g(a.speed),
            g(b.speed),
            g(peak(&a)),
            g(peak(&b)),
            g(expo_inst)
        ))
        .tolerance("1e-4 absolute")
        .pass(ok),
    );
    assert!(ok, "exponent {expo}");
}
