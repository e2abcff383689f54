//! `grainchain units`: the SI value of the program units for steel grains of a diameter.

use super::Caller;
use crate::error::Error;
use grainchain_engine::units::{diameter_problem, SiScale, STAINLESS_STEEL};

/// The rule of a grain diameter in metres: the engine's one rule of a diameter
/// ([`diameter_problem`], the same message as a scene or design file's), else what is wrong.
pub fn diameter(x: f64) -> Result<f64, String> {
    match diameter_problem(x) {
        None => Ok(x),
        Some(problem) => Err(problem),
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
