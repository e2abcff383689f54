//! Number formatting shared by the units' reports and tables.

use crate::reproduce::table::Cell;

pub(crate) fn num(x: f64) -> Cell {
    Cell::Num(x)
}

pub(crate) fn opt(x: Option<f64>) -> Cell {
    // A missing value is an empty field (CONTRIBUTING.md, "CSV conventions").
    x.map_or_else(|| Cell::Text(String::new()), Cell::Num)
}

pub(crate) fn opt_k(x: Option<usize>) -> Cell {
    x.map_or_else(|| Cell::Text(String::new()), |k| Cell::Num(k as f64))
}

pub(crate) fn sig(x: f64) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let d = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.d$}")
    } else {
        format!("{x:.3e}")
    }
}

pub(crate) fn rel_diff(ours: f64, paper: f64) -> String {
    if paper == 0.0 || !ours.is_finite() {
        return "-".into();
    }
    format!("{:+.0} %", 100.0 * (ours - paper) / paper)
}
