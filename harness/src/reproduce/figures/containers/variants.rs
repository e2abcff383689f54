//! The variants of container (a): gamma over the same window as the default run, and how far
//! the curve departs from it.

use super::{ContainerFit, Variant};
use crate::batch::RunData;
use crate::error::Error;
use crate::reproduce::figures::curves::{curve_diff, CurveDiff};
use grainchain_engine::analysis::decay::{fit_percent, ONSET_FRACTION};
use grainchain_engine::analysis::{self, PowerFit};

/// Results of one variant run of (a).
#[derive(Clone, Debug)]
pub struct VariantResult {
    /// Which variant.
    pub variant: Variant,
    /// Length of the variant's run in snapshots (output times after t = 0; at most
    /// [`crate::reproduce::VARIANT_SNAPSHOTS`]).
    pub snapshots: usize,
    /// The variant's power-law fit of `E_R / E0` in percent over `window`.
    pub fit: Option<PowerFit>,
    /// Default (a) fitted over the same window.
    pub default_fit: Option<PowerFit>,
    /// The common fit window, first and last output index: from the default run's window start
    /// (after both curves' leak onsets) to the variant's last snapshot.
    pub window: (usize, usize),
    /// gamma of the variant minus gamma of the default over the same window (`None`: either
    /// fit missing).
    pub delta_gamma: Option<f64>,
    /// The variant's `E_R` against the default (a)'s, over their common snapshots.
    pub diff: CurveDiff,
    /// `100 * diff.max_rel`: the largest relative difference of `E_R` in percent.
    pub diff_percent: f64,
    /// Grains between the furthest disturbance and the nearer chain end (`None` for the
    /// free-end variant, which is meant to reach its ends).
    pub margin: Option<usize>,
}

/// The variant `v` of (a), recorded in `d`, against the default run `a`.
pub(super) fn variant(v: Variant, d: &RunData, a: &ContainerFit) -> Result<VariantResult, Error> {
    let e = d.region("container")?.energy;
    let n = e.len() - 1;
    // The headline window's start (a tenth of the full run, not of the variant's shorter one),
    // after both curves' leak onsets; the variant's end.
    let onset = |x: &[f64]| analysis::leak_onset(x, ONSET_FRACTION).unwrap_or(0);
    let w = (a.window.0.max(onset(e)).max(onset(&a.er)), n);
    let fit = fit_percent(e, d.run.initial_energy, w.0, w.1);
    let default_fit = fit_percent(&a.er[..=n.min(a.er.len() - 1)], a.e0, w.0, w.1);
    let diff = curve_diff(e, &a.er, a.e0);
    Ok(VariantResult {
        variant: v,
        snapshots: n,
        fit,
        default_fit,
        delta_gamma: fit.zip(default_fit).map(|(f, g)| f.gamma - g.gamma),
        window: w,
        diff,
        diff_percent: 100.0 * diff.max_rel,
        margin: v.check_ends().then(|| d.run.end_margin()),
    })
}
