//! The step-size check (`--check-step`): every figure again at `dt / STEP_FACTOR`, the
//! containers also with a chaos twin, and the differences, as numbers. Each unit computes its
//! own checks in its analysis; the text is `render::step_check`'s.

/// What a step check is of.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CheckTarget {
    /// Fig. 1 and its control run.
    Fig1,
    /// Fig. 3.
    Fig3,
    /// A container by its key.
    Container(String),
}

/// A side of the container (Fig. 3's leading waves).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Left of the container (away from the striker).
    Left,
    /// Right of the container (the striker's side).
    Right,
}

/// A quantity compared between the run at `dt` and at `dt / STEP_FACTOR`, with what the report
/// says beside its value.
#[derive(Clone, Debug, PartialEq)]
pub enum Quantity {
    /// Fig. 1: both velocity snapshots, max |dv| / max |v|.
    VelocitySnapshots,
    /// Fig. 1: energies of the `waves` leading transmitted waves; pulses found at each step.
    TransmittedEnergies {
        /// Leading waves compared (at most 10, and no more than either run found).
        waves: usize,
        /// Transmitted pulses found at `dt`.
        found: usize,
        /// Transmitted pulses found at `dt / STEP_FACTOR`.
        found_fine: usize,
    },
    /// Fig. 1: reflected energy over incident.
    Reflected,
    /// Fig. 3: energy of the leading wave on one side.
    LeadingWave(Side),
    /// Fig. 3: container energy over the run.
    ContainerEnergy {
        /// Output index of the largest relative difference.
        at: usize,
        /// First output index at which the relative difference exceeds
        /// the curve comparison's level, 1e-4 (`None`: never).
        first_above: Option<usize>,
    },
    /// Container: first snapshot at which dt and dt/8 differ by more than 1e-4 (the row's value
    /// is that output index, NaN when never).
    FirstStepDifference {
        /// Output index at which `E_R` (at dt) peaks.
        peak: usize,
    },
    /// Container: first snapshot at which the twin differs by more than 1e-4 (the row's value
    /// is that output index, NaN when never).
    FirstTwinDifference,
    /// Container: E_R over the run, dt vs dt/8 (the row's value: largest relative difference).
    StepDifference {
        /// Output index of the largest relative difference.
        at: usize,
    },
    /// Container: E_R over the run, twin vs dt (the row's value: largest relative difference).
    TwinDifference {
        /// Output index of the largest relative difference.
        at: usize,
    },
    /// Container: gamma over `window` at dt, dt/8 and of the twin (the row's value:
    /// `|gamma(dt) - gamma(dt/8)|`).
    Gamma {
        /// The fit window, first and last output index ([`crate::analysis::decay::fit_window`] of the run at
        /// dt).
        window: (usize, usize),
        /// gamma of the run at dt (NaN: no fit).
        dt: f64,
        /// gamma of the run at dt/8 (NaN: no fit).
        fine: f64,
        /// gamma of the chaos twin (NaN: no fit).
        twin: f64,
        /// `|gamma(dt) - gamma(twin)|`.
        twin_difference: f64,
    },
    /// Container other than (a): alpha at dt and dt/8 (the row's value: their relative
    /// difference).
    Alpha {
        /// alpha of the run at dt onto (a) at dt.
        dt: f64,
        /// alpha of the run at dt/8 onto (a) at dt.
        fine: f64,
    },
}

/// Step-size check of one run.
#[derive(Clone, Debug)]
pub struct StepCheck {
    /// The figure or container checked.
    pub target: CheckTarget,
    /// The integration method of both runs.
    pub method: &'static str,
    /// The step taken by the run at dt (as the scene asks, possibly shortened to divide the
    /// output interval).
    pub dt: f64,
    /// The step taken by the run at `dt / STEP_FACTOR`.
    pub dt_fine: f64,
    /// What was compared and its difference.
    pub rows: Vec<(Quantity, f64)>,
}

/// `|a - b| / |b|` (`|a|` when `b` is 0).
pub(crate) fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}
