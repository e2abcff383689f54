//! Comparisons of two `E_R` curves (step-size check, variants, chaos twin).

/// Comparison of two `E_R` curves over their common snapshots.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CurveDiff {
    /// Largest `|E - E_ref| / E_ref` over snapshots with `E_ref >= floor * E0`.
    pub max_rel: f64,
    /// Output index of `max_rel` (0 when no difference above the floor was found).
    pub at: usize,
    /// First snapshot whose bits differ.
    pub first_bit_difference: Option<usize>,
    /// First snapshot at which the relative difference exceeds `level` (1e-4).
    pub first_above_level: Option<usize>,
    /// Snapshots compared: the shorter curve's length (t = 0 included).
    pub snapshots: usize,
}

/// Relative differences are taken where the reference holds at least this fraction of the
/// striker's energy: below it only the super-exponentially small precursor of the incident wave
/// has entered, whose relative value means nothing.
pub const ENERGY_FLOOR: f64 = 1e-3;

/// The accuracy level of the issue (requirement 6).
pub const LEVEL: f64 = 1e-4;

/// Compare the curve `e` with `reference` over their common output indices; `e0` is the
/// striker's energy E0 (the floor is [`ENERGY_FLOOR`] `* e0`, the level [`LEVEL`]).
pub fn curve_diff(e: &[f64], reference: &[f64], e0: f64) -> CurveDiff {
    let m = e.len().min(reference.len());
    let mut d = CurveDiff {
        max_rel: 0.0,
        at: 0,
        first_bit_difference: None,
        first_above_level: None,
        snapshots: m,
    };
    for k in 0..m {
        if d.first_bit_difference.is_none() && e[k].to_bits() != reference[k].to_bits() {
            d.first_bit_difference = Some(k);
        }
        if reference[k] >= ENERGY_FLOOR * e0 {
            let r = (e[k] - reference[k]).abs() / reference[k];
            if r > d.max_rel {
                d.max_rel = r;
                d.at = k;
            }
            if r > LEVEL && d.first_above_level.is_none() {
                d.first_above_level = Some(k);
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_diff_finds_first_difference_and_ignores_the_floor() {
        let r = vec![0.0, 1e-9, 100.0, 100.0, 100.0];
        let e = vec![0.0, 2e-9, 100.0, 100.02, 100.0];
        let d = curve_diff(&e, &r, 100.0);
        assert_eq!(d.first_bit_difference, Some(1));
        assert_eq!(d.first_above_level, Some(3));
        assert_eq!(d.at, 3);
        assert!((d.max_rel - 2e-4).abs() < 1e-12);
    }
}
