//! The step-size check (`--check-step`): every figure again at `dt / STEP_FACTOR`, the
//! containers also with a chaos twin, and the differences, as numbers. Each unit computes its
//! own checks in its analysis, with its own typed quantities (`Fig1Quantity`, `Fig3Quantity`,
//! `ContainerQuantity`), and renders their text; the section and `check_step.csv` are
//! `render::step_check`'s.

/// Step-size check of one run: quantities of type `Q` compared between the run at `dt` and at
/// `dt / STEP_FACTOR`.
#[derive(Clone, Debug)]
pub struct StepCheck<Q> {
    /// The run checked, as the tables name it (`fig1`, `fig3`, `fig4 (a)`).
    pub run: String,
    /// The integration method of both runs.
    pub method: &'static str,
    /// The step taken by the run at dt (as the scene asks, possibly shortened to divide the
    /// output interval).
    pub dt: f64,
    /// The step taken by the run at `dt / STEP_FACTOR`.
    pub dt_fine: f64,
    /// What was compared and its difference.
    pub rows: Vec<(Q, f64)>,
}

/// `|a - b| / |b|` (`|a|` when `b` is 0).
pub(crate) fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}
