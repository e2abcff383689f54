//! The step-size check in REPORT.md and `check_step.csv`, from the rows every unit renders of
//! its checks ([`Describe`] gives a quantity's text).

use super::text::{num, sig};
use crate::reproduce::figures::curves::ENERGY_FLOOR;
use crate::reproduce::step_check::StepCheck;
use crate::reproduce::table::Table;
use std::fmt::Write;

/// A unit's compared quantity in the step-size check: what it is and the note beside its
/// value (the units implement it for their own quantities).
pub(crate) trait Describe {
    /// (quantity, note).
    fn describe(&self) -> (String, String);
}

/// One row of the step-size check: text, but the value.
pub(crate) struct CheckRow {
    run: String,
    method: &'static str,
    dt: f64,
    dt_fine: f64,
    quantity: String,
    value: f64,
    note: String,
}

/// The rows of the check `c`.
pub(crate) fn rows<Q: Describe>(c: &StepCheck<Q>) -> Vec<CheckRow> {
    c.rows
        .iter()
        .map(|(q, v)| {
            let (quantity, note) = q.describe();
            CheckRow {
                run: c.run.clone(),
                method: c.method,
                dt: c.dt,
                dt_fine: c.dt_fine,
                quantity,
                value: *v,
                note,
            }
        })
        .collect()
}

/// `## Step-size check`.
pub(super) fn section(rows: &[&CheckRow]) -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "## Step-size check (`--check-step`)\n");
    let _ = writeln!(
        w,
        "Each run again at an eighth of its step (`check_step.csv`); containers also with a chaos twin \
         (striker speed x (1 + 1e-12), same step). Relative differences of E_R count snapshots where the finer \
         run holds at least {:e} of the striker's energy.\n\n\
         Reading it: E_R(t) of a container agrees with the run at dt/8 within 1e-4 until the first snapshot \
         listed, a little after the incident wave has entered; from there the differences grow to the size \
         of the twin's, which a change of one part in 10^12 of the striker's speed causes. No step size can \
         hold the curve to 1e-4 beyond the twin's snapshot; gamma and alpha move with the step by about as \
         much as with the twin.\n",
        ENERGY_FLOOR
    );
    let _ = writeln!(w, "| run | method | dt | dt/8 | quantity | value | note |");
    let _ = writeln!(w, "|---|---|---|---|---|---|---|");
    for r in rows {
        let v = r.value;
        let value = if v.is_nan() {
            "never".to_string()
        } else if v.fract() == 0.0 && v.abs() < 1e7 {
            format!("{v}")
        } else {
            format!("{v:.2e}")
        };
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {value} | {} |",
            r.run,
            r.method,
            sig(r.dt),
            sig(r.dt_fine),
            r.quantity,
            r.note
        );
    }
    let _ = writeln!(w);
    s
}

/// `check_step.csv`.
pub(super) fn table(rows: &[CheckRow]) -> Table {
    let mut t = Table::new(
        "check_step.csv",
        &[
            "run", "method", "dt", "dt_fine", "quantity", "value", "note",
        ],
    );
    for r in rows {
        t.push(vec![
            r.run.as_str().into(),
            r.method.into(),
            num(r.dt),
            num(r.dt_fine),
            r.quantity.as_str().into(),
            num(r.value),
            r.note.as_str().into(),
        ]);
    }
    t
}
