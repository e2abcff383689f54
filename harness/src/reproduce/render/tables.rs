//! `runs.csv`: every simulation of the run (shared by all units).

use super::text::num;
use crate::reproduce::jobs::RunEntry;
use crate::reproduce::table::Table;

/// `runs.csv`.
pub(super) fn runs(runs: &[RunEntry]) -> Table {
    let mut t = Table::new(
        "runs.csv",
        &[
            "run",
            "grains",
            "first_touched",
            "last_touched",
            "end_margin",
            "method",
            "dt",
            "steps",
            "outputs",
            "grain_evaluations",
            "wall_s",
            "max_rel_energy_error",
        ],
    );
    for r in runs {
        t.push(vec![
            r.label().into(),
            r.run.grains.into(),
            r.run.ever.0.into(),
            r.run.ever.1.into(),
            r.run.end_margin().into(),
            r.run.method.into(),
            num(r.run.dt),
            r.run.stats.steps.into(),
            r.recorded.into(),
            r.run.stats.grain_evals.into(),
            num(r.wall),
            num(r.run.max_energy_error),
        ]);
    }
    t
}
