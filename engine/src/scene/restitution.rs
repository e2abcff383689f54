//! Contact damping from a coefficient of restitution: the head-on collision of two grains run
//! to its end, and the damping coefficient that gives a restitution by bisection. Here, below
//! the problem catalogue, so that scenes (`restitution = 0.95`) and
//! `problems::TwoGrainCollision` (which delegates to it, bit for bit the arithmetic it had) share
//! one implementation.

use crate::chain::{ChainBuilder, ContactLaw, DampingModel, Striker, StrikerEnd};
use crate::integrators::{IntegrationParams, Method};
use crate::run::{RunError, SimulationBuilder};
use std::ops::ControlFlow;

/// A head-on collision: a striker of mass `striker_mass` at `speed` hits a grain of mass
/// `grain_mass` at rest through `F = eta delta^p` (plus a dashpot), `contact_time` the elastic
/// contact's duration (it sets the step, contact_time / 4096, and the run, 8 contact times).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Collision {
    pub p: f64,
    pub eta: f64,
    pub striker_mass: f64,
    pub grain_mass: f64,
    pub speed: f64,
    pub contact_time: f64,
}

impl Collision {
    /// The coefficient of restitution `(v_grain - v_striker) / speed` after the contact, with the
    /// contact damped by `model` with coefficient `c`: the two grains run (blanes-moan4) until
    /// they part, 8 elastic contact times at most. Error: a run error, or grains still in contact then (a damping so
    /// strong that the contact lasts longer; restitution near 0).
    pub(crate) fn restitution(&self, model: DampingModel, c: f64) -> Result<f64, RunError> {
        let law = ContactLaw::new(self.p, self.eta).with_damping(model, c);
        let chain = ChainBuilder::new()
            .grains(1, self.grain_mass, law)
            .striker(Striker {
                end: StrikerEnd::Left,
                mass: self.striker_mass,
                speed: self.speed,
                law: None,
            })
            .build()
            .map_err(|e| RunError::Settings(e.to_string()))?;
        let tc = self.contact_time;
        let mut sim = SimulationBuilder::new(chain)
            .params(IntegrationParams {
                method: Method::BlanesMoan4,
                dt: tc / 4096.0,
                ..Default::default()
            })
            .schedule(8.0 * tc, tc)
            .build()?;
        // Once the contact is open and the grains part (`v0 <= v1`), no force acts again and
        // every velocity keeps its bits (each kick adds an exact zero): the run stops at the
        // first output time after that, with the restitution it would have at 8 contact times.
        sim.run_until(|fr| {
            let (u, v) = (&fr.state.u, &fr.state.v);
            if u[0] < u[1] && v[0] <= v[1] {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })?;
        let st = sim.state();
        if st.u[0] >= st.u[1] {
            return Err(RunError::Settings(format!(
                "restitution: the grains are still in contact after 8 elastic contact times \
                 (damping c = {c} too strong)"
            )));
        }
        Ok((st.v[1] - st.v[0]) / self.speed)
    }

    /// The coefficient `c` of `model` for which this collision's restitution is `e`
    /// (0.05 <= e < 1): bisection on `c` (the restitution falls as `c` grows) to 1e-12 of it.
    /// For the scale-respecting model the answer holds at every impact speed; it depends on the
    /// masses only through `c / sqrt(eta m_eff)`.
    pub(crate) fn damping_for_restitution(
        &self,
        model: DampingModel,
        e: f64,
    ) -> Result<f64, RunError> {
        if !(0.05..1.0).contains(&e) {
            return Err(RunError::Settings(format!(
                "restitution must be in [0.05, 1), got {e}"
            )));
        }
        let reduced = self.striker_mass * self.grain_mass / (self.striker_mass + self.grain_mass);
        let scale = (self.eta * reduced).sqrt();
        let (mut lo, mut hi) = (0.0, 1e-3 * scale);
        while self.restitution(model, hi)? > e {
            lo = hi;
            hi *= 2.0;
        }
        while hi - lo > 1e-12 * hi {
            let mid = 0.5 * (lo + hi);
            if self.restitution(model, mid)? > e {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(0.5 * (lo + hi))
    }
}

/// `I_{3/2} = B(2/5, 1/2) / (5/2)`, the contact integral of a Hertz collision (physics.md 4;
/// `problems::contact_integral(1.5)`, which the catalogue's tests compare with it): the scene
/// needs the elastic contact time of a Hertz pair and sits below the analysis that computes it.
pub(crate) const HERTZ_CONTACT_INTEGRAL: f64 = 1.471_637_592_162_352_3;
