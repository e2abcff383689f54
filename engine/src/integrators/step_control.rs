//! Step-size control shared by the adaptive methods.
//!
//! A PI controller (Gustafsson; Hairer & Wanner, Solving ODEs II, IV.2) on the max-norm of the
//! scaled error. The max norm matters here: it does not change with the number of grains, so
//! the accepted steps are the same whether or not untouched grains are skipped, and a long chain
//! gets the same accuracy per grain as a short one.
//!
//! Contacts open and close during a run, and the Hertz force is only C^1 there (the linear law
//! only C^0). The local error of a step that straddles such an event is larger than the smooth
//! theory predicts; the controller copes by (1) rejecting and shrinking (never growing) after a
//! rejection, (2) limiting growth after an accept to `FAC_MAX`, and (3) damping with the PI term so
//! the step does not oscillate between accept and reject around contact events.

/// Safety factor on the predicted optimal step.
pub const SAFETY: f64 = 0.9;
/// Largest growth of the step after an accepted step.
pub const FAC_MAX: f64 = 5.0;
/// Largest shrink of the step after a rejected step.
pub const FAC_MIN: f64 = 0.2;
/// PI controller: integral exponent is `1/(q+1) - 0.75 BETA`, proportional exponent `BETA`.
pub const BETA: f64 = 0.04;

/// Controller state.
#[derive(Clone, Copy, Debug)]
pub struct PiController {
    order: f64,
    err_old: f64,
    last_rejected: bool,
}

/// The verdict on one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Verdict {
    /// Accept the step; try `next_h` next.
    Accept {
        /// The next step size.
        next_h: f64,
    },
    /// Reject the step; retry it with `retry_h`.
    Reject {
        /// The smaller step to retry with.
        retry_h: f64,
    },
}

impl PiController {
    /// `order` is the order of the lower-order embedded solution plus one (5 for DOPRI5(4)).
    pub fn new(order: f64) -> Self {
        PiController {
            order,
            err_old: 1e-4,
            last_rejected: false,
        }
    }

    /// Judge a step of size `h` with scaled error `err` (accept when `err <= 1`).
    pub fn judge(&mut self, h: f64, err: f64) -> Verdict {
        let expo = 1.0 / self.order - 0.75 * BETA;
        if err <= 1.0 {
            let err = err.max(1e-10);
            let mut fac = SAFETY * err.powf(-expo) * self.err_old.powf(BETA);
            fac = fac.clamp(FAC_MIN, FAC_MAX);
            if self.last_rejected {
                fac = fac.min(1.0);
            }
            self.err_old = err.max(1e-4);
            self.last_rejected = false;
            Verdict::Accept { next_h: h * fac }
        } else {
            let fac = if err.is_finite() {
                (SAFETY * err.powf(-expo)).max(FAC_MIN)
            } else {
                FAC_MIN
            };
            self.last_rejected = true;
            Verdict::Reject {
                retry_h: h * fac.min(1.0),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_error_grows_large_error_shrinks() {
        let mut c = PiController::new(5.0);
        match c.judge(1.0, 1e-6) {
            Verdict::Accept { next_h } => assert!(next_h > 1.0 && next_h <= FAC_MAX),
            v => panic!("{v:?}"),
        }
        match c.judge(1.0, 100.0) {
            Verdict::Reject { retry_h } => assert!((FAC_MIN..1.0).contains(&retry_h)),
            v => panic!("{v:?}"),
        }
        // No growth right after a rejection.
        match c.judge(1.0, 1e-6) {
            Verdict::Accept { next_h } => assert!(next_h <= 1.0),
            v => panic!("{v:?}"),
        }
        match c.judge(1.0, f64::NAN) {
            Verdict::Reject { retry_h } => assert_eq!(retry_h, FAC_MIN),
            v => panic!("{v:?}"),
        }
    }
}
