//! The statistics of a study and its files: CSV tables, SVG figures and STUDY.md.
//!
//! Per container (a key), from its members' container energy normalized by each member's own
//! incident energy, `f_k(t) = E_R,k(t) / E0_k`:
//! - **band**: mean, median, 5 % and 95 % over members at every snapshot (`ensemble.csv`);
//! - **budget**: the mean fraction of the incident energy in the container and in every section
//!   outside it at the snapshots [`budget_outputs`] (`budget.csv`; member files hold the sections
//!   outside the container at those snapshots only);
//! - **gamma** of the mean curve over the fit window `[N/10, N]` (never before the leak onset,
//!   as in `reproduce`), with the jackknife interval over members
//!   ([`grainchain_engine::analysis::ensemble`]), and each member's own gamma over the same window
//!   (`fits.csv`); also per decade of time from the leak onset `t_on` (`[t_on, 10 t_on]`, ..., a last partial
//!   decade if it spans at least 0.3 decade);
//! - **local slope** `d ln E / d ln t` of the mean curve from its peak on, 10 log bins per
//!   decade, least squares over +-2 bins (half a decade), with its jackknife interval
//!   (`slope.csv`), and the longest stretch where it stays within +-0.05 of a constant;
//! - **alpha by level**: the time `t_X(L)` at which the binned mean curve first falls to level
//!   `L` after its peak; `alpha = t_ref(L) / t_X(L)` (so that `E_X(t) = E_ref(alpha t)`, the
//!   convention of `reproduce`), with the jackknife standard errors of `ln t_ref` and `ln t_X`
//!   combined in quadrature (the two ensembles are independent) and Student t with
//!   `min(n_ref, n_X) - 1` degrees of freedom (`alpha.csv`); beside it the collapse alpha of
//!   `reproduce` (least RMS mismatch) of the mean curves.
//!
//! Random containers get the same gamma with interval; `random.csv` lists them with their
//! designs, and STUDY.md gives the distribution of gamma and its correlation with each design
//! parameter.

mod analyse;
pub mod mechanism;
mod plots;
mod report;
mod reproduce;
mod write;

pub use analyse::analyse;
pub use report::report;
pub use reproduce::reproduce_section;
pub use write::write;

use super::random::Design;
use super::sweep::{budget_outputs, log_thinned};
use crate::batch::Gauge;
use grainchain_engine::analysis::ensemble::{Band, Estimate};
use grainchain_engine::analysis::statistics::mean_se;
use grainchain_engine::analysis::Collapse;

/// A point of the local slope with its jackknife interval.
#[derive(Clone, Copy, Debug)]
pub struct SlopeRow {
    /// Time of the point, in snapshots since the strike (`exp` of the mean `ln t` of its bin).
    pub t: f64,
    /// Local slope `d ln E_R / d ln t` of the mean curve (`-gamma` of a local power law).
    pub slope: f64,
    /// Jackknife standard error of the slope over members.
    pub se: f64,
    /// Lower end of the 95 % interval (Student t, members - 1 degrees of freedom).
    pub ci_lo: f64,
    /// Upper end of the 95 % interval.
    pub ci_hi: f64,
}

/// A fit over a stated window.
#[derive(Clone, Debug)]
pub struct WindowFit {
    /// First snapshot of the window.
    pub t_lo: usize,
    /// Last snapshot of the window (inclusive).
    pub t_hi: usize,
    /// gamma fitted to the mean curve over the window with its jackknife interval over members;
    /// None when the fit fails or is withheld.
    pub est: Option<Estimate>,
    /// Why no gamma is given over this window (`analysis::decay::gamma_withheld`: no leak onset,
    /// a window before it or shorter than `MIN_FIT_DECADES`); None when one is fitted.
    pub withheld: Option<String>,
}

impl WindowFit {
    /// The text of a missing gamma: the reason it is withheld, else "the fit failed".
    pub fn why_missing(&self) -> String {
        self.withheld
            .clone()
            .unwrap_or_else(|| "the fit failed (too few points with energy)".into())
    }
}

/// Everything measured for one container.
#[derive(Clone, Debug)]
pub struct KeyResult {
    /// The container's key (`a`, `r-007`).
    pub key: String,
    /// Number of members merged.
    pub members: usize,
    /// Region names of the member files: `container` first, then the sections outside it.
    pub regions: Vec<String>,
    /// Mean incident energy over members.
    pub e0: f64,
    /// Mean, median and 5-95 % band of `E_R / E_0` over members at every snapshot.
    pub band: Vec<Band>,
    /// The snapshots of the energy budget ([`budget_outputs`]).
    pub budget_at: Vec<usize>,
    /// `budget[r][j]`: mean fraction of the incident energy in region `r` at snapshot
    /// `budget_at[j]`.
    pub budget: Vec<Vec<f64>>,
    /// The main fit: gamma over snapshots from `max(N/10, leak onset)` to `N` (the run length).
    pub fit: WindowFit,
    /// gamma of each member's own curve over the main fit's window (None where the fit fails).
    pub member_gamma: Vec<Option<f64>>,
    /// gamma over successive decades of time from the leak onset on (`[t_on, 10 t_on]`, ...; a
    /// last, shorter window only if it spans at least 0.3 decade).
    pub decades: Vec<WindowFit>,
    /// Where the decades start: the leak onset, or `None` when no onset was found (then at
    /// snapshot 100).
    pub onset: Option<usize>,
    /// The local slope over time, from the peak of the mean curve on.
    pub slope: Vec<SlopeRow>,
    /// Longest stretch of the local slope within +-0.05 of a constant: first and last `t`, the
    /// constant (mid-range).
    pub constant: Option<(f64, f64, f64)>,
    /// The local slope where the mean curve first falls to each level of the sweep (interpolated
    /// in `ln t` between slope points): comparing containers at equal `E_R` rather than at equal
    /// time removes the time rescaling alpha, so under the paper's claim (one power law, curves
    /// that differ by a time scale) these agree across containers.
    pub level_slopes: Vec<(f64, Option<f64>)>,
    /// Random containers: the drawn design (None for a container from a scene file).
    pub design: Option<Design>,
    /// Largest relative energy error of any member at any output time.
    pub max_energy_error: f64,
    /// Smallest end margin of any member: grains between the furthest disturbance and the nearer
    /// chain end at the end of the run.
    pub min_end_margin: usize,
    /// Mean wall time per member (seconds).
    pub wall_per_member: f64,
    /// The outer medium's hold on the container (member files with gauges:
    /// [`crate::batch::GAUGES`]).
    pub gauges: Option<Gauges>,
    /// The striker's speed of the sweep's container entry (`containers[i].speed`), if it sets
    /// one.
    pub speed: Option<f64>,
}

/// The gauges of a container over the late window `[N/2, N]`, per member, and their mean
/// curves.
#[derive(Clone, Debug)]
pub struct Gauges {
    /// The late window, first and last snapshot.
    pub window: (usize, usize),
    /// Per member, the mean of `E_R / E0` over the window.
    pub er: Vec<f64>,
    /// Per member, the mean of each gauge over the window, in [`Gauge::ALL`] order.
    pub members: Vec<Vec<f64>>,
    /// Per gauge ([`Gauge::ALL`] order), its mean over members at [`KeyResult::budget_at`] (a
    /// force is the instantaneous one at those outputs).
    pub curves: Vec<Vec<f64>>,
}

impl Gauges {
    /// Member `m`'s mean of gauge `g` over the window.
    pub fn of(&self, m: usize, g: Gauge) -> f64 {
        self.members[m][g.index()]
    }

    /// The mean over members of `E_R / E0` with its standard error.
    pub fn mean_er(&self) -> (f64, f64) {
        mean_se(&self.er)
    }

    /// The mean over members of gauge `g` with its standard error.
    pub fn mean(&self, g: Gauge) -> (f64, f64) {
        let x: Vec<f64> = (0..self.members.len()).map(|m| self.of(m, g)).collect();
        mean_se(&x)
    }

    /// Gauge `g`'s mean curve at [`KeyResult::budget_at`].
    pub fn curve(&self, g: Gauge) -> &[f64] {
        &self.curves[g.index()]
    }
}

/// alpha of one container at one level.
#[derive(Clone, Debug)]
pub struct AlphaRow {
    /// The container's key.
    pub key: String,
    /// The E_R level (fraction of the incident energy).
    pub level: f64,
    /// Time at which the reference's mean curve falls to the level (snapshots; None if it never
    /// does).
    pub t_ref: Option<f64>,
    /// Time at which this container's mean curve falls to the level (snapshots).
    pub t_key: Option<f64>,
    /// `t_ref / t_key`: the time rescaling such that `E_key(t) = E_ref(alpha t)` at this level
    /// (1 for the reference itself).
    pub alpha: Option<f64>,
    /// Lower end of the 95 % interval of alpha, from the jackknifed `ln t` of both containers
    /// (NaN for the reference itself or with too few members).
    pub ci_lo: f64,
    /// Upper end of the 95 % interval of alpha.
    pub ci_hi: f64,
}

/// One reading of `[search]`, scored with one time origin.
#[derive(Clone, Debug)]
pub struct SearchRow {
    /// The reading's number (1: the reconstruction).
    pub index: u64,
    /// The reading.
    pub reading: crate::study::search::Reading,
    /// Where `t` starts.
    pub origin: crate::study::search::TimeOrigin,
    /// gamma of (a), alpha of (c), (d), (e) and the distance to the paper.
    pub score: crate::study::search::Score,
    /// gamma of (a) over each decade from its leak onset (with `t` from the strike).
    pub decades: Vec<Option<f64>>,
    /// Why `score.gamma` is missing, when it is withheld (`search::gamma_withheld_of`).
    pub note: Option<String>,
    /// Members per container.
    pub members: usize,
}

/// The whole study.
#[derive(Clone, Debug)]
pub struct Study {
    /// The sweep's `name`.
    pub name: String,
    /// The sweep's `description`.
    pub description: Option<String>,
    /// The sweep's run digest (the member files' `sweep`).
    pub digest: String,
    /// Run length of every member, in snapshots.
    pub snapshots: u64,
    /// The perturbation, in words (for `STUDY.md`).
    pub perturbation: String,
    /// Results of the `[[containers]]` entries, in study order.
    pub containers: Vec<KeyResult>,
    /// Results of the random containers, in study order.
    pub random: Vec<KeyResult>,
    /// The search's readings, each scored with `t` from the strike and from the arrival
    /// (empty without `[search]`).
    pub search: Vec<SearchRow>,
    /// The search's containers (`s-<reading>-<container>`), each as measured (empty without
    /// `[search]`).
    pub searched: Vec<KeyResult>,
    /// Key of the reference container of alpha and the collapse, if the sweep names one.
    pub reference: Option<String>,
    /// alpha of every container at every level (empty without a reference).
    pub alpha: Vec<AlphaRow>,
    /// For each container, the collapse of its mean curve onto the reference's (from the leak
    /// onsets on); None for the reference itself or when no overlap fits.
    pub collapse: Vec<(String, Option<Collapse>)>,
    /// Sum of the members' wall times.
    pub job_seconds: f64,
    /// Members not (yet) run, when merged with `--partial`.
    pub missing: Vec<String>,
    /// The paper's mechanism per container (sweep key `mechanism`; empty without it).
    pub mechanism: Vec<mechanism::Mechanism>,
}

/// The group of a key: the part before its first `-` (`a` of `a-free`), so the outer media of
/// one container share a group and its plots.
pub(super) fn group_of(key: &str) -> &str {
    key.split('-').next().unwrap_or(key)
}

pub(super) fn all(study: &Study) -> impl Iterator<Item = &KeyResult> {
    study.containers.iter().chain(&study.random)
}
