//! The SVG figures of a study.

use super::*;
use crate::analysis::ensemble::Band;
use crate::error::Error;
use crate::report::plot::{LineChart, Scale, Series};
use std::path::Path;

pub(super) fn plots(study: &Study, out: &Path) -> Result<(), Error> {
    let mut series = Vec::new();
    for k in &study.containers {
        // E_R from the leak onset on (before it the band holds the incident wave's arrival, down
        // to ~1e-45); a run too short to leak is drawn from its peak.
        let mean: Vec<f64> = k.band.iter().map(|b| b.mean).collect();
        let start = crate::analysis::leak_onset(&mean, crate::analysis::decay::ONSET_FRACTION)
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
            name: format!("({}) 5-95 %", k.key),
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
            title: "E_R / E0 from the leak onset: ensemble mean and 5-95 % band",
            x_label: "t (snapshots)",
            y_label: "E_R / E0",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
            series,
            ..Default::default()
        }
        .write(out.join("er_band.svg"))?;
    }
    let mut series = Vec::new();
    for k in &study.containers {
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
                        format!("({}) {name}", k.key)
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
