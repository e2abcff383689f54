//! The rows of `designs.csv`, `baselines.csv`, `robustness.csv` and `pareto.csv`: one struct
//! each, written through `csv` ([`crate::report::atomic::csv_rows`]), so that a column's header
//! is its field's name and cannot drift from its value. Numbers are written as every CSV of
//! grainchain writes them ([`crate::report::csv_number`]; an error that is not final is the
//! empty field).

use serde::Serialize;

/// `f64` fields as every CSV of grainchain writes them.
use crate::report::serialize_number as number;

/// An optional number: empty when `None` (an error that is not final), else as [`number`].
fn optional<S: serde::Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&crate::report::CsvNumber(x.unwrap_or(f64::NAN)))
}

/// A row of `designs.csv`: every design evaluated, ranked.
#[derive(Debug, Serialize)]
pub struct DesignRow {
    pub rank: usize,
    pub genes: String,
    pub design: String,
    #[serde(serialize_with = "number")]
    pub objective: f64,
    #[serde(serialize_with = "number")]
    pub peak_n: f64,
    #[serde(serialize_with = "optional")]
    pub peak_n_error: Option<f64>,
    pub bound: bool,
    #[serde(serialize_with = "number")]
    pub peak_ratio: f64,
    #[serde(serialize_with = "number")]
    pub impulse_ns: f64,
    #[serde(serialize_with = "optional")]
    pub impulse_ns_error: Option<f64>,
    #[serde(serialize_with = "number")]
    pub duration_s: f64,
    #[serde(serialize_with = "optional")]
    pub duration_s_error: Option<f64>,
    #[serde(serialize_with = "number")]
    pub mass_kg: f64,
    #[serde(serialize_with = "number")]
    pub length_m: f64,
    pub complete: bool,
    pub given_up: bool,
}

/// A row of `baselines.csv`: a known design at the file's load.
#[derive(Debug, Serialize)]
pub struct BaselineRow {
    pub baseline: String,
    pub design: String,
    #[serde(serialize_with = "number")]
    pub objective: f64,
    #[serde(serialize_with = "number")]
    pub peak_n: f64,
    #[serde(serialize_with = "optional")]
    pub peak_n_error: Option<f64>,
    pub bound: bool,
    #[serde(serialize_with = "number")]
    pub peak_ratio: f64,
    #[serde(serialize_with = "number")]
    pub impulse_ns: f64,
    #[serde(serialize_with = "optional")]
    pub impulse_ns_error: Option<f64>,
    #[serde(serialize_with = "number")]
    pub duration_s: f64,
    #[serde(serialize_with = "optional")]
    pub duration_s_error: Option<f64>,
    #[serde(serialize_with = "number")]
    pub mass_kg: f64,
    #[serde(serialize_with = "number")]
    pub length_m: f64,
    pub complete: bool,
}

/// A row of `robustness.csv`: the best design, the monodisperse column and the best baseline
/// under one condition (a speed, or restitution 0.95).
#[derive(Debug, Serialize)]
pub struct RobustnessRow {
    pub condition: String,
    #[serde(serialize_with = "number")]
    pub best_peak_n: f64,
    #[serde(serialize_with = "number")]
    pub monodisperse_peak_n: f64,
    pub best_baseline: String,
    #[serde(serialize_with = "number")]
    pub best_baseline_peak_n: f64,
    #[serde(serialize_with = "number")]
    pub best_ratio: f64,
    pub complete: bool,
    pub best_bound: bool,
    pub monodisperse_bound: bool,
    pub best_baseline_bound: bool,
}

/// A row of `pareto.csv`: a design no lighter design beats.
#[derive(Debug, Serialize)]
pub struct ParetoRow {
    #[serde(serialize_with = "number")]
    pub mass_kg: f64,
    #[serde(serialize_with = "number")]
    pub objective: f64,
    #[serde(serialize_with = "number")]
    pub peak_n: f64,
    pub bound: bool,
    pub genes: String,
    pub design: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header `csv` writes for a row struct.
    fn header<T: Serialize>(row: T) -> String {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(row).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        text.lines().next().unwrap().to_string()
    }

    /// The published headers (`DESIGNS_HEADER`, `BASELINES_HEADER`) are the structs'.
    #[test]
    fn the_headers_are_the_rows() {
        let d = DesignRow {
            rank: 1,
            genes: "0.1".into(),
            design: "a, b".into(),
            objective: 1.0,
            peak_n: 2.0,
            peak_n_error: None,
            bound: false,
            peak_ratio: 0.5,
            impulse_ns: 1e-3,
            impulse_ns_error: Some(1e-9),
            duration_s: 1e-5,
            duration_s_error: None,
            mass_kg: 0.1,
            length_m: 0.2,
            complete: true,
            given_up: false,
        };
        assert_eq!(header(&d), super::super::DESIGNS_HEADER);
        let b = BaselineRow {
            baseline: "monodisperse".into(),
            design: "x".into(),
            objective: 1.0,
            peak_n: 2.0,
            peak_n_error: Some(0.1),
            bound: false,
            peak_ratio: 1.0,
            impulse_ns: 1.0,
            impulse_ns_error: None,
            duration_s: 1.0,
            duration_s_error: None,
            mass_kg: 1.0,
            length_m: 1.0,
            complete: true,
        };
        assert_eq!(header(&b), super::super::BASELINES_HEADER);
        // A field with a comma is quoted; a missing error is empty; tiny numbers in exponent form.
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(&d).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(
            text.lines().nth(1).unwrap(),
            "1,0.1,\"a, b\",1,2,,false,0.5,0.001,1e-9,1e-5,,0.1,0.2,true,false"
        );
    }
}
