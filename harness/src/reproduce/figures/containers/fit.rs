//! Fig. 4 and 5: the containers' remaining energy, its power-law fits and the time rescaling of
//! each container onto (a), with every curve the figures draw.

use crate::error::Error;
use grainchain_engine::analysis::decay::{
    fit_percent, fit_window, onset_bins, BINS_PER_DECADE, WINDOWS,
};
use grainchain_engine::analysis::{self, Collapse, CollapseRule, PowerFit};

/// One container's curve and its analysis.
#[derive(Clone, Debug)]
pub struct ContainerFit {
    /// The container's key (`a` for `a-standard.toml`).
    pub key: String,
    /// Its name from the file name (`standard`).
    pub label: String,
    /// E0: the striker's energy (the energy at t = 0).
    pub e0: f64,
    /// `E_R`, the energy in the container, at every output index `k` (t = k * output interval,
    /// 0 included).
    pub er: Vec<f64>,
    /// The fit window, first and last output index ([`fit_window`]).
    pub window: (usize, usize),
    /// Power-law fit of `E_R / E0` in percent over `window` (`None`: too few points).
    pub fit: Option<PowerFit>,
    /// Output index of the leak onset (`E_R` fallen to [`ONSET_FRACTION`](grainchain_engine::analysis::decay::ONSET_FRACTION) of its peak; `None`:
    /// not within the run).
    pub onset: Option<usize>,
    /// The time rescaling alpha onto (a), `E_R(t) = E_R^(a)(alpha t)`, fitted from the leak
    /// onsets on; for (a) itself alpha = 1 over (a)'s own range (`None`: no overlap found).
    pub collapse: Option<Collapse>,
    /// Fits over [`WINDOWS`].
    pub windows: Vec<((usize, usize), Option<PowerFit>)>,
    /// `E_R / E0` in percent at every output index (Fig. 4).
    pub percent: Vec<f64>,
    /// The points of the collapse onto (a) (`fig5_collapse.csv`): `percent` in log bins
    /// ([`BINS_PER_DECADE`]) from half the leak onset on, with the time rescaled by alpha.
    pub collapse_points: Vec<CollapsePoint>,
    /// The curve of Fig. 5: (alpha t, `E_R` in %) from the curve's maximum on (before it, only
    /// the incident wave's super-exponentially small precursor has entered), where `E_R > 0`;
    /// alpha 1 when no collapse was found.
    pub rescaled: Vec<(f64, f64)>,
    /// The power law `fit` over `window`, 21 log-spaced points (empty without a fit).
    pub fit_curve: Vec<(f64, f64)>,
}

impl ContainerFit {
    /// alpha, 1 when no collapse was found (as the tables and Fig. 5 use it).
    pub fn alpha_or_one(&self) -> f64 {
        self.collapse.map_or(1.0, |x| x.alpha)
    }
}

/// A log bin of a container's `E_R` in percent, its time rescaled onto (a).
#[derive(Clone, Copy, Debug)]
pub struct CollapsePoint {
    /// Mean of `ln t` over the bin's snapshots.
    pub ln_t: f64,
    /// `ln t + ln alpha` (alpha 1 when no collapse was found).
    pub ln_alpha_t: f64,
    /// Mean of `ln E_R` (in percent) over the bin's snapshots.
    pub ln_e: f64,
}

/// `percent` in log bins from half the leak onset on, rescaled by `alpha`.
fn collapse_points(percent: &[f64], onset: Option<usize>, alpha: f64) -> Vec<CollapsePoint> {
    let start = onset.unwrap_or(1).max(2) / 2;
    analysis::log_bins(percent, start, percent.len() - 1, BINS_PER_DECADE)
        .into_iter()
        .map(|p| CollapsePoint {
            ln_t: p.ln_t,
            ln_alpha_t: p.ln_t + alpha.ln(),
            ln_e: p.ln_e,
        })
        .collect()
}

/// (alpha t, `E_R` in %) from the curve's maximum on, where `E_R > 0`.
fn rescaled(er: &[f64], percent: &[f64], alpha: f64) -> Vec<(f64, f64)> {
    let peak = er
        .iter()
        .enumerate()
        .fold(
            (0, f64::NEG_INFINITY),
            |b, (t, &e)| if e > b.1 { (t, e) } else { b },
        )
        .0;
    er.iter()
        .zip(percent)
        .enumerate()
        .skip(peak.max(1))
        .filter(|(_, (&e, _))| e > 0.0)
        .map(|(t, (_, &p))| (alpha * t as f64, p))
        .collect()
}

/// The power law `f` over `window`, 21 log-spaced points.
fn fit_curve(window: (usize, usize), f: PowerFit) -> Vec<(f64, f64)> {
    let (lo, hi) = (window.0.max(1) as f64, window.1 as f64);
    (0..=20)
        .map(|j| {
            let t = lo * (hi / lo).powf(j as f64 / 20.0);
            (t, f.a * t.powf(-f.gamma))
        })
        .collect()
}

/// The remaining energy of one container over its run.
#[derive(Clone, Debug)]
pub struct Curve {
    /// The container's key (`a` for `a-standard.toml`).
    pub key: String,
    /// Its name from the file name (`standard`).
    pub label: String,
    /// `E_R` at every snapshot.
    pub er: Vec<f64>,
    /// The striker's energy.
    pub e0: f64,
}

/// Fit every container, collapse each onto the reference (key `a`) and prepare its curves.
pub(super) fn fits(curves: Vec<Curve>) -> Result<Vec<ContainerFit>, Error> {
    let reference = curves
        .iter()
        .find(|c| c.key == "a")
        .ok_or(crate::error::ReproduceError::MissingReference)?;
    let (_, ref_bins) = onset_bins(&reference.er);
    let rule = CollapseRule::default();
    let mut out = Vec::new();
    for Curve { key, label, er, e0 } in curves {
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
        let percent: Vec<f64> = er.iter().map(|x| 100.0 * x / e0).collect();
        let alpha = collapse.map_or(1.0, |x| x.alpha);
        out.push(ContainerFit {
            collapse_points: collapse_points(&percent, onset, alpha),
            rescaled: rescaled(&er, &percent, alpha),
            fit_curve: fit.map_or_else(Vec::new, |f| fit_curve(window, f)),
            percent,
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
