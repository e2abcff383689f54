//! Number formatting shared by the report and the tables.

use crate::reproduce::table::Cell;

pub(super) fn num(x: f64) -> Cell {
    Cell::Num(x)
}

pub(super) fn opt(x: Option<f64>) -> Cell {
    x.map_or_else(|| Cell::Text("none".into()), Cell::Num)
}

pub(super) fn opt_k(x: Option<usize>) -> Cell {
    x.map_or_else(|| Cell::Text("none".into()), |k| Cell::Num(k as f64))
}

/// Local maxima of `e` over `a..=b`.
pub(super) fn local_maxima(e: &[f64], a: usize, b: usize) -> usize {
    (a..=b)
        .filter(|&i| {
            let l = if i > a { e[i - 1] } else { f64::NEG_INFINITY };
            let r = if i < b { e[i + 1] } else { f64::NEG_INFINITY };
            e[i] > l && e[i] >= r
        })
        .count()
}

pub(super) fn sig(x: f64) -> String {
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

pub(super) fn rel_diff(ours: f64, paper: f64) -> String {
    if paper == 0.0 || !ours.is_finite() {
        return "-".into();
    }
    format!("{:+.0} %", 100.0 * (ours - paper) / paper)
}
