//! The SVG figures of a study.

use super::*;
use crate::batch::Gauge;
use crate::error::Error;
use crate::report::plot::{LineChart, Scale, Series};
use grainchain_engine::analysis::ensemble::Band;
use std::path::Path;

pub(super) fn plots(study: &Study, out: &Path) -> Result<(), Error> {
    let keys: Vec<&KeyResult> = study.containers.iter().collect();
    er_band(&keys, "", out.join("er_band.svg"))?;
    // The keys of one container in several outer media (`<group>-<medium>`), one plot each.
    let mut groups: Vec<&str> = keys.iter().map(|k| group_of(&k.key)).collect();
    groups.dedup();
    if groups.len() > 1 {
        for g in &groups {
            let of: Vec<&KeyResult> = (keys.iter().copied())
                .filter(|k| group_of(&k.key) == *g)
                .collect();
            if of.len() > 1 {
                er_band(
                    &of,
                    &format!(" ({g})"),
                    out.join(format!("er_band-{g}.svg")),
                )?;
            }
        }
    }
    gauges(study, &groups, out)?;
    gamma_vs_speed(study, out)?;
    slope_and_budget(study, out)
}

/// gamma of the ensemble mean (main fit window, 95 % interval dashed) against the striker's
/// speed, one line per group of keys (`<group>-<speed>`), when the sweep sets speeds.
fn gamma_vs_speed(study: &Study, out: &Path) -> Result<(), Error> {
    let with: Vec<(
        &KeyResult,
        f64,
        grainchain_engine::analysis::ensemble::Estimate,
    )> = (study.containers)
        .iter()
        .filter_map(|k| Some((k, k.speed?, k.fit.est?)))
        .collect();
    if with.is_empty() {
        return Ok(());
    }
    let mut groups: Vec<&str> = with.iter().map(|w| group_of(&w.0.key)).collect();
    groups.dedup();
    let mut series = Vec::new();
    for g in groups {
        let mut pts: Vec<(f64, grainchain_engine::analysis::ensemble::Estimate)> = (with.iter())
            .filter(|w| group_of(&w.0.key) == g)
            .map(|w| (w.1, w.2))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        series.push(Series {
            name: format!("({g})"),
            points: pts.iter().map(|(v, e)| (*v, e.value)).collect(),
            markers: true,
            ..Default::default()
        });
        for (name, f) in [
            (
                "95 % (jackknife)",
                &(|e: &grainchain_engine::analysis::ensemble::Estimate| e.ci_lo)
                    as &dyn Fn(&_) -> f64,
            ),
            (
                "",
                &|e: &grainchain_engine::analysis::ensemble::Estimate| e.ci_hi,
            ),
        ] {
            series.push(Series {
                name: if name.is_empty() {
                    String::new()
                } else {
                    format!("({g}) {name}")
                },
                points: pts
                    .iter()
                    .map(|(v, e)| (*v, f(e)))
                    .filter(|p| p.1.is_finite())
                    .collect(),
                dashed: true,
                same_color: true,
                ..Default::default()
            });
        }
    }
    series.push(Series {
        name: format!("paper: gamma = {}", grainchain_engine::paper::GAMMA),
        points: {
            let (lo, hi) = with.iter().fold((f64::INFINITY, 0.0f64), |(a, b), w| {
                (a.min(w.1), b.max(w.1))
            });
            vec![
                (lo, grainchain_engine::paper::GAMMA),
                (hi, grainchain_engine::paper::GAMMA),
            ]
        },
        reference: true,
        dashed: true,
        ..Default::default()
    });
    LineChart {
        title: "gamma of the ensemble mean against the striker's speed (program units)",
        x_label: "striker speed (program units; x 0.1727 m/s for 1 mm steel)",
        y_label: "gamma",
        x_scale: Scale::Log,
        y_scale: Scale::Linear,
        series,
        ..Default::default()
    }
    .write(out.join("gamma_vs_speed.svg"))
}

/// E_R bands of `keys` from their leak onsets, into `path`.
fn er_band(keys: &[&KeyResult], title: &str, path: std::path::PathBuf) -> Result<(), Error> {
    let mut series = Vec::new();
    for (j, k) in keys.iter().enumerate() {
        // E_R from the leak onset on (before it the band holds the incident wave's arrival, down
        // to ~1e-45); a run too short to leak is drawn from its peak.
        let mean: Vec<f64> = k.band.iter().map(|b| b.mean).collect();
        let start = grainchain_engine::analysis::leak_onset(
            &mean,
            grainchain_engine::analysis::decay::ONSET_FRACTION,
        )
        .or_else(|| {
            let peak = mean.iter().copied().fold(0.0, f64::max);
            mean.iter().position(|&m| peak > 0.0 && m == peak)
        })
        .unwrap_or(1);
        let idx: Vec<usize> = log_thinned(k.band.len() - 1)
            .into_iter()
            .filter(|&t| t >= start)
            .collect();
        let pts = |f: &dyn Fn(&Band) -> f64| -> Vec<(f64, f64)> {
            idx.iter()
                .map(|&t| (t as f64, f(&k.band[t])))
                .filter(|p| p.1 > 0.0)
                .collect()
        };
        series.push(Series {
            name: format!("({}) mean", k.key),
            points: pts(&|b| b.mean),
            ..Default::default()
        });
        series.push(Series {
            name: band_name(keys.len(), j, &k.key, "5-95 %"),
            points: pts(&|b| b.p05),
            markers: false,
            dashed: true,
            same_color: true,
            ..Default::default()
        });
        series.push(Series {
            name: String::new(),
            points: pts(&|b| b.p95),
            markers: false,
            dashed: true,
            same_color: true,
            ..Default::default()
        });
    }
    if !series.is_empty() {
        LineChart {
            title: &format!("E_R / E0 from the leak onset: ensemble mean and 5-95 % band{title}"),
            x_label: "t (snapshots)",
            y_label: "E_R / E0",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series,
            ..Default::default()
        }
        .write(path)?;
    }
    Ok(())
}

/// The volume over time per group, and late E_R against the volume, member by member.
fn gauges(study: &Study, groups: &[&str], out: &Path) -> Result<(), Error> {
    let with: Vec<(&KeyResult, &Gauges)> = (study.containers.iter())
        .filter_map(|k| k.gauges.as_ref().map(|g| (k, g)))
        .collect();
    if with.is_empty() {
        return Ok(());
    }
    for g in groups {
        let series: Vec<Series> = (with.iter())
            .filter(|(k, _)| group_of(&k.key) == *g)
            .map(|(k, gs)| Series {
                name: format!("({})", k.key),
                points: (k.budget_at.iter().zip(gs.curve(Gauge::Volume)))
                    .filter(|(&t, _)| t > 0)
                    .map(|(&t, &v)| (t as f64, v))
                    .collect(),
                ..Default::default()
            })
            .collect();
        LineChart {
            title: &format!(
                "({g}) container volume: right minus left outer displacement, mean over members"
            ),
            x_label: "t (snapshots)",
            y_label: "volume (length units)",
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series,
            ..Default::default()
        }
        .write(out.join(format!("volume-{g}.svg")))?;
    }
    // One colour per outer medium (the key after its group: `free` of `a-free`), every
    // container's members in it; each point its own series, so no line joins them.
    let variant = |key: &str| key.split_once('-').map_or(key, |v| v.1).to_string();
    let mut variants: Vec<String> = Vec::new();
    for (k, _) in &with {
        if !variants.contains(&variant(&k.key)) {
            variants.push(variant(&k.key));
        }
    }
    let mut series = Vec::new();
    for v in &variants {
        let points = (with.iter())
            .filter(|(k, _)| variant(&k.key) == *v)
            .flat_map(|(_, g)| (0..g.er.len()).map(|m| (g.of(m, Gauge::Volume), g.er[m])));
        for (j, p) in points.enumerate() {
            series.push(Series {
                name: if j == 0 { v.clone() } else { String::new() },
                points: vec![p],
                markers: true,
                ..Default::default()
            });
        }
    }
    let (lo, hi) = with[0].1.window;
    LineChart {
        title: &format!("Late E_R (mean over [{lo}, {hi}]) against the volume, per member"),
        x_label: "volume (length units)",
        y_label: "E_R / E0",
        x_scale: Scale::Linear,
        y_scale: Scale::Log,
        series,
        ..Default::default()
    }
    .write(out.join("er_vs_volume.svg"))
}

/// Legend entry of key `j`'s band (of `n` keys): its own up to [`OWN_BAND_ENTRIES`] keys; with
/// more, only the first key's, for all (a legend of two entries per key would not fit).
fn band_name(n: usize, j: usize, key: &str, what: &str) -> String {
    if n <= OWN_BAND_ENTRIES {
        format!("({key}) {what}")
    } else if j == 0 {
        format!("{what} (dashed, every key)")
    } else {
        String::new()
    }
}

/// Keys up to which each band has a legend entry of its own.
const OWN_BAND_ENTRIES: usize = 6;

fn slope_and_budget(study: &Study, out: &Path) -> Result<(), Error> {
    let mut series = Vec::new();
    let n = study.containers.len();
    for (j, k) in study.containers.iter().enumerate() {
        series.push(Series {
            name: format!("({})", k.key),
            points: k.slope.iter().map(|s| (s.t, s.slope)).collect(),
            markers: true,
            ..Default::default()
        });
        for (f, name) in [
            (
                &(|s: &SlopeRow| s.ci_lo) as &dyn Fn(&SlopeRow) -> f64,
                "95 % (jackknife)",
            ),
            (&|s: &SlopeRow| s.ci_hi, ""),
        ] {
            let pts: Vec<(f64, f64)> = k
                .slope
                .iter()
                .map(|s| (s.t, f(s)))
                .filter(|p| p.1.is_finite())
                .collect();
            if !pts.is_empty() {
                series.push(Series {
                    name: if name.is_empty() {
                        String::new()
                    } else {
                        band_name(n, j, &k.key, name)
                    },
                    points: pts,
                    markers: false,
                    dashed: true,
                    same_color: true,
                    ..Default::default()
                });
            }
        }
    }
    if !series.is_empty() {
        LineChart {
            title: "Local slope d ln E_R / d ln t of the ensemble mean",
            x_label: "t (snapshots)",
            y_label: "local slope",
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series,
            ..Default::default()
        }
        .write(out.join("slope.svg"))?;
    }
    for k in &study.containers {
        // Snapshot 0 has no place on a log axis.
        let series = k
            .regions
            .iter()
            .enumerate()
            .map(|(r, name)| Series {
                name: name.clone(),
                points: k
                    .budget_at
                    .iter()
                    .zip(&k.budget[r])
                    .filter(|(&t, _)| t > 0)
                    .map(|(&t, &x)| (t as f64, x))
                    .collect(),
                ..Default::default()
            })
            .collect();
        LineChart {
            title: &format!(
                "({}) where the energy is: mean fraction of E0 per region",
                k.key
            ),
            x_label: "t (snapshots)",
            y_label: "fraction of E0",
            x_scale: Scale::Log,
            y_scale: Scale::Linear,
            series,
            ..Default::default()
        }
        .write(out.join(format!("budget-{}.svg", k.key)))?;
    }
    let gammas: Vec<f64> = study
        .random
        .iter()
        .filter_map(|k| k.fit.est.map(|e| e.value))
        .collect();
    if !gammas.is_empty() {
        crate::report::plot::histogram(
            "gamma of random containers (ensemble mean, window [N/10, N])",
            "gamma",
            &gammas,
            0.1,
            out.join("gamma_hist.svg"),
        )?;
    }
    Ok(())
}
