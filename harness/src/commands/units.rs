//! `grainchain units`: the SI value of the program units for steel grains of a diameter.

use super::Caller;
use crate::error::Error;
use grainchain_engine::format::Num;
use grainchain_engine::units::{SiScale, DIAMETER_RANGE_M, STAINLESS_STEEL};

/// The rule of a grain diameter in metres: a finite number within [`DIAMETER_RANGE_M`] (a steel
/// sphere from a micrometre to a metre), else what is wrong.
pub fn diameter(x: f64) -> Result<f64, String> {
    let (lo, hi) = DIAMETER_RANGE_M;
    if (lo..=hi).contains(&x) {
        Ok(x)
    } else {
        Err(format!(
            "a grain diameter must be between {} m and {} m (a steel sphere from a micrometre to \
             a metre), got {}",
            Num(lo),
            Num(hi),
            Num(x)
        ))
    }
}

/// `grainchain units --diameter D`: the scale of stainless steel grains of diameter `d` metres
/// with the paper's eta, as JSON on stdout. A diameter outside [`diameter`]'s rule is
/// [`Error::Usage`].
pub fn units(d: f64, caller: &Caller) -> Result<SiScale, Error> {
    let d = diameter(d).map_err(|problem| Error::Usage {
        name: "diameter",
        problem,
    })?;
    let s = SiScale::hertz(d, STAINLESS_STEEL, grainchain_engine::paper::ETA);
    caller.out(format_args!("{}", serde_json::to_string_pretty(&s)?));
    Ok(s)
}
