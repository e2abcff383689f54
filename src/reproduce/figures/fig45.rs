//! Fig. 4 and 5: the containers' remaining energy, its power-law fits and the time rescaling of
//! each container onto (a).

use crate::analysis::decay::{fit_percent, fit_window, onset_bins, WINDOWS};
use crate::analysis::{self, Collapse, CollapseRule, PowerFit};
use crate::error::Error;

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
    /// Output index of the leak onset (`E_R` fallen to [`crate::analysis::decay::ONSET_FRACTION`] of its peak; `None`:
    /// not within the run).
    pub onset: Option<usize>,
    /// The time rescaling alpha onto (a), `E_R(t) = E_R^(a)(alpha t)`, fitted from the leak
    /// onsets on; for (a) itself alpha = 1 over (a)'s own range (`None`: no overlap found).
    pub collapse: Option<Collapse>,
    /// Fits over [`WINDOWS`].
    pub windows: Vec<((usize, usize), Option<PowerFit>)>,
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

/// Fit every container and collapse each onto the reference (key `a`).
pub fn fig45(curves: Vec<Curve>) -> Result<Vec<ContainerFit>, Error> {
    let reference = curves
        .iter()
        .find(|c| c.key == "a")
        .ok_or(crate::reproduce::ReproduceError::MissingReference)?;
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
