//! The settings check themselves: [`IntegrationParams::validate`] is the one place the rules
//! live, used by the scene check (which puts the error under the scene's file) and by
//! [`crate::run::SimulationBuilder::build`]; [`IntegrationParams::fitted_step`] is the one place
//! a fixed step is fitted to the output interval.

use super::{IntegrationParams, Method, Sleep};

/// The most steps of a fixed-step method per output interval.
pub const MAX_STEPS_PER_OUTPUT: f64 = 1e12;

/// Settings that cannot work: the scene key of the setting at fault (`integrator.dt`,
/// `integrator.sleep`, `integrator.multirate.ratio`, ...) and what is wrong with it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key}: {message}")]
pub struct ParamsError {
    /// The setting at fault, as its scene key.
    pub key: &'static str,
    /// What is wrong, without naming the setting.
    pub message: String,
}

fn fail(key: &'static str, message: String) -> Result<(), ParamsError> {
    Err(ParamsError { key, message })
}

fn positive(key: &'static str, x: f64) -> Result<(), ParamsError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        fail(key, format!("must be a finite number > 0, got {x}"))
    }
}

fn non_negative(key: &'static str, x: f64) -> Result<(), ParamsError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        fail(key, format!("must be a finite number >= 0, got {x}"))
    }
}

impl IntegrationParams {
    /// Check the settings for a run with outputs every `interval`, on a chain of `grains` grains
    /// when known (the multirate fast region must lie inside it). In order: the values
    /// ([`IntegrationParams::validate_values`]), the steps per output interval
    /// ([`IntegrationParams::validate_steps`]), the multirate settings
    /// ([`IntegrationParams::validate_multirate`]); the first problem is returned.
    pub fn validate(&self, interval: f64, grains: Option<usize>) -> Result<(), ParamsError> {
        self.validate_values()?;
        self.validate_steps(interval)?;
        self.validate_multirate(interval, grains)
    }

    /// The values on their own and against the method: `dt` (and, for the adaptive method,
    /// `rtol` and `atol`) finite and > 0, `max_energy_error` > 0, sleep thresholds finite and
    /// >= 0, and a sleep rule only for a method that takes one ([`super::MethodInfo::sleep`]).
    pub fn validate_values(&self) -> Result<(), ParamsError> {
        let info = self.method.information();
        positive("integrator.dt", self.dt)?;
        if info.adaptive {
            positive("integrator.rtol", self.rtol)?;
            positive("integrator.atol", self.atol)?;
        }
        // Infinity switches the energy check off.
        if !(self.max_energy_error > 0.0) {
            return fail(
                "integrator.max_energy_error",
                format!("must be > 0, got {}", self.max_energy_error),
            );
        }
        if self.events && !info.events {
            return fail(
                "integrator.events",
                format!(
                    "contact events need {}, not {}",
                    Method::names_with(|i| i.events, "or"),
                    info.name
                ),
            );
        }
        if let Some(Sleep { velocity, force }) = self.sleep {
            non_negative("integrator.sleep.velocity", velocity)?;
            non_negative("integrator.sleep.force", force)?;
            if !info.sleep {
                return fail(
                    "integrator.sleep",
                    format!(
                        "the sleep rule needs a splitting method ({}), not {}",
                        Method::names_with(|i| i.sleep, "or"),
                        info.name
                    ),
                );
            }
        }
        Ok(())
    }

    /// At most [`MAX_STEPS_PER_OUTPUT`] steps of a fixed-step method per output interval.
    pub fn validate_steps(&self, interval: f64) -> Result<(), ParamsError> {
        if !self.method.is_adaptive() && interval / self.dt > MAX_STEPS_PER_OUTPUT {
            return fail(
                "integrator.dt",
                format!(
                    "dt = {:e} needs more than 1e12 steps per output interval ({interval})",
                    self.dt
                ),
            );
        }
        Ok(())
    }

    /// For [`Method::Multirate`] with settings: the ratio divides the steps per output interval
    /// ([`IntegrationParams::validate_ratio`]) and the fast region lies inside the chain of
    /// `grains` grains (when known).
    pub fn validate_multirate(
        &self,
        interval: f64,
        grains: Option<usize>,
    ) -> Result<(), ParamsError> {
        let (Method::Multirate, Some(m)) = (self.method, self.multirate) else {
            return Ok(());
        };
        self.validate_ratio(m.ratio, interval)?;
        if let Some(n) = grains {
            if m.first > m.last || m.last >= n {
                return fail(
                    "integrator.multirate.fast",
                    format!(
                        "the fast region {}..={} is not inside the chain of {n} grains",
                        m.first, m.last
                    ),
                );
            }
        }
        Ok(())
    }

    /// A multirate `ratio` must divide the steps of the fitted `dt` per output interval.
    pub fn validate_ratio(&self, ratio: u64, interval: f64) -> Result<(), ParamsError> {
        let steps = self.steps_per_output(interval);
        if ratio == 0 || !steps.is_multiple_of(ratio) {
            return fail(
                "integrator.multirate.ratio",
                format!("must divide the {steps} steps of dt per output interval, got {ratio}"),
            );
        }
        Ok(())
    }

    /// The step a run with outputs every `interval` takes: for a fixed-step method `dt`
    /// shortened so that a whole number of steps fits each output interval (so output `k`
    /// falls exactly at `k * interval`); for the adaptive method `dt`, its initial step. The one
    /// place the step is fitted.
    pub fn fitted_step(&self, interval: f64) -> f64 {
        if self.method.is_adaptive() {
            self.dt
        } else {
            interval / (interval / self.dt).ceil().max(1.0)
        }
    }

    /// Steps of the fitted step per output interval (for the adaptive method, of its initial
    /// step).
    pub fn steps_per_output(&self, interval: f64) -> u64 {
        (interval / self.fitted_step(interval)).round() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_scene_key() {
        let p = IntegrationParams {
            method: Method::Gear5,
            sleep: Some(Sleep {
                velocity: 0.0,
                force: 0.0,
            }),
            ..Default::default()
        };
        let e = p.validate(1.0, None).unwrap_err();
        assert_eq!(e.key, "integrator.sleep");
        assert_eq!(
            e.message,
            "the sleep rule needs a splitting method (verlet or blanes-moan4), not gear5"
        );
        let p = IntegrationParams {
            dt: 1e-14,
            ..Default::default()
        };
        assert_eq!(
            p.validate(0.5, None).unwrap_err().to_string(),
            "integrator.dt: dt = 1e-14 needs more than 1e12 steps per output interval (0.5)"
        );
    }

    #[test]
    fn multirate_settings_are_checked() {
        let p = IntegrationParams {
            method: Method::Multirate,
            dt: 0.01,
            multirate: Some(super::super::MultirateParams {
                ratio: 3,
                first: 2,
                last: 5,
            }),
            ..Default::default()
        };
        assert_eq!(p.validate(0.3, Some(10)), Ok(()));
        assert_eq!(
            p.validate(0.2, Some(10)).unwrap_err().key,
            "integrator.multirate.ratio"
        );
        assert_eq!(
            p.validate(0.3, Some(5)).unwrap_err().key,
            "integrator.multirate.fast"
        );
    }

    #[test]
    fn fitted_step_divides_the_interval() {
        let p = IntegrationParams {
            dt: 0.3,
            ..Default::default()
        };
        assert_eq!(p.fitted_step(1.0), 0.25);
        assert_eq!(p.steps_per_output(1.0), 4);
        let a = IntegrationParams {
            method: Method::Dopri5,
            dt: 0.3,
            ..Default::default()
        };
        assert_eq!(a.fitted_step(1.0), 0.3);
    }
}
