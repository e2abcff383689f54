//! The load on one contact over every step: what a protector is judged by (the force on the
//! protected wall or target, its true peak, the impulse it transmits, how long it stays high),
//! which the state at output times misses.

use crate::chain::Chain;
use crate::state::State;

/// What [`LoadWatch`] found so far, in the scene's units (SI scenes: N, s, N s, J).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Load {
    /// The watched contact (`0..=n`; `n` is the right wall's).
    pub contact: usize,
    /// The largest force over every step (positions after each whole step); with contact
    /// events ([`crate::IntegrationParams::events`]) the maximum of the parabola through the
    /// three steps around each local maximum of the steps' forces, so that the peak's error is
    /// O(h^3) rather than the O(h^2) of sampling.
    pub peak: f64,
    /// The time of that step (of the parabola's maximum, with events).
    pub peak_time: f64,
    /// The force's integral over time (the trapezoid rule over the steps: for the splitting
    /// methods with a wall this is the momentum the wall took out, to rounding).
    pub impulse: f64,
    /// The fraction of the peak [`Load::duration`] counts above.
    pub fraction: f64,
    /// The time the force spent at or above `fraction * peak` (whole steps).
    pub duration: f64,
    /// The largest energy of the grain right of the contact when that grain is the target (the
    /// chain's last grain, its kinetic energy plus its spring's), else 0. Velocities are those
    /// after each step's closing kick, as [`crate::PeakSpeeds`] samples them.
    pub target_energy: f64,
    /// The steps watched.
    pub steps: u64,
}

/// The watched contact at one output: its force now, and its peak and impulse so far (the
/// columns `load`, `load_peak`, `load_impulse` of `energies.csv`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LoadSample {
    /// The force after the last whole step (the output's state).
    pub force: f64,
    /// The largest force over every step so far ([`Load::peak`]).
    pub peak: f64,
    /// The force's integral so far ([`Load::impulse`]).
    pub impulse: f64,
}

/// Watches the force of one contact after every step (switched on by
/// [`crate::Simulation::watch_load`]); off by default, when a step pays one branch.
#[derive(Clone, Debug, Default)]
pub struct LoadWatch {
    on: bool,
    load: Load,
    dt: f64,
    t0: f64,
    /// The force after the previous step (for the trapezoid rule).
    last: f64,
    /// The force the step before (for the located peak).
    before: f64,
    /// Whether the peak is located between steps (with contact events).
    located: bool,
    /// Whether the grain right of the contact is the chain's last (the target).
    target: bool,
    /// The steps at or above `fraction` of the peak.
    above: Above,
}

/// The forces at or above a fraction of the running peak, one per step: a superset of the steps
/// the final duration counts (the final peak is at least the running one). Pruned when it has
/// doubled since the last pruning, so its length stays near the steps above the threshold. The
/// duration's one rule, for [`LoadWatch`] and the protector's derivatives
/// (`protector::gradient`).
#[derive(Clone, Debug, Default)]
pub(crate) struct Above {
    kept: Vec<f64>,
    pruned_at: usize,
}

impl Above {
    /// Forget every step.
    pub fn clear(&mut self) {
        self.kept.clear();
        self.pruned_at = 0;
    }

    /// The force `f` after a step, the running peak's level `level` (`fraction * peak`).
    #[inline(always)]
    pub fn record(&mut self, f: f64, level: f64) {
        if f > 0.0 && f >= level {
            self.kept.push(f);
            if self.kept.len() >= 2 * self.pruned_at.max(64) {
                self.kept.retain(|&x| x >= level);
                self.pruned_at = self.kept.len();
            }
        }
    }

    /// The steps whose force is at or above `level` (the final peak's) and not zero.
    pub fn count(&self, level: f64) -> usize {
        self.kept.iter().filter(|&&f| f >= level && f > 0.0).count()
    }
}

/// The parabola through the forces `y0, y1, y2` of three consecutive steps, where it curves
/// down (`curvature = y0 - 2 y1 + y2 < 0`): its maximum `top`, at `offset` steps from the
/// middle one. The located peak's one rule, for [`LoadWatch`] and the protector's derivatives.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Parabola {
    pub top: f64,
    pub curvature: f64,
    pub offset: f64,
}

impl Parabola {
    /// `None` where the three forces do not curve down.
    #[inline(always)]
    pub fn through(y0: f64, y1: f64, y2: f64) -> Option<Parabola> {
        let curvature = y0 - 2.0 * y1 + y2;
        (curvature < 0.0).then(|| Parabola {
            top: y1 - (y0 - y2) * (y0 - y2) / (8.0 * curvature),
            curvature,
            offset: 0.5 * (y0 - y2) / curvature,
        })
    }
}

impl LoadWatch {
    /// Start watching contact `contact` of `chain` from `state` with steps of `dt`, counting
    /// the time at or above `fraction` of the peak; `target`: the grain right of the contact
    /// is the protected body (its energy is kept).
    pub(crate) fn start(
        &mut self,
        chain: &Chain,
        state: &State,
        dt: f64,
        contact: usize,
        fraction: f64,
        target: bool,
    ) {
        let f = contact_force(chain, state, contact);
        self.on = true;
        self.dt = dt;
        self.t0 = state.t;
        self.last = f;
        self.before = f;
        self.located = false;
        self.target = target;
        self.above.clear();
        self.load = Load {
            contact,
            peak: f,
            peak_time: state.t,
            fraction,
            ..Load::default()
        };
        if target {
            self.load.target_energy = target_energy(chain, state);
        }
    }

    /// Locate the peak between steps (with contact events): see [`Load::peak`].
    pub(crate) fn locate_peak(&mut self, on: bool) {
        self.located = on;
    }

    /// Whether the watch is on.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// The force now and the peak and impulse so far (cheap: for every output).
    pub fn sample(&self) -> LoadSample {
        LoadSample {
            force: self.last,
            peak: self.load.peak,
            impulse: self.load.impulse,
        }
    }

    /// What was found so far.
    pub fn load(&self) -> Load {
        let mut l = self.load;
        l.duration = self.above.count(l.fraction * l.peak) as f64 * self.dt;
        l
    }

    /// Fold in the state after a whole step.
    #[inline(always)]
    pub(crate) fn update(&mut self, chain: &Chain, state: &State) {
        if self.on {
            self.record(chain, state);
        }
    }

    #[inline(never)]
    fn record(&mut self, chain: &Chain, state: &State) {
        let f = contact_force(chain, state, self.load.contact);
        let l = &mut self.load;
        l.steps += 1;
        l.impulse += 0.5 * (self.last + f) * self.dt;
        if f > l.peak {
            l.peak = f;
            l.peak_time = self.t0 + l.steps as f64 * self.dt;
        }
        if self.located && self.last > self.before && self.last >= f && l.steps >= 2 {
            // The parabola through the forces at steps - 2, steps - 1 and steps: its maximum
            // lies within half a step of the middle one.
            if let Some(top) = Parabola::through(self.before, self.last, f) {
                if top.top > l.peak {
                    l.peak = top.top;
                    l.peak_time = self.t0 + ((l.steps - 1) as f64 + top.offset) * self.dt;
                }
            }
        }
        self.before = self.last;
        self.last = f;
        self.above.record(f, l.fraction * l.peak);
        if self.target {
            let e = target_energy(chain, state);
            if e > l.target_energy {
                l.target_energy = e;
            }
        }
    }
}

/// The force of contact `k` for the state: the law's force of the overlap, plus its dashpot's
/// `c delta^q d(delta)/dt` while closed (never tensile on a compression-only contact).
pub(crate) fn contact_force(chain: &Chain, state: &State, k: usize) -> f64 {
    let (Some(kernel), Some(delta)) = (chain.contact_kernel(k), chain.overlap(&state.u, k)) else {
        return 0.0;
    };
    let elastic = kernel.force_at(delta);
    let Some(law) = chain
        .contact_law(k)
        .filter(|l| l.damping.is_some_and(|d| d.c > 0.0))
    else {
        return elastic;
    };
    let d = law.damping.expect("filtered on it");
    if delta <= 0.0 && !law.tension {
        return 0.0;
    }
    let n = chain.len();
    let vl = if k == 0 { 0.0 } else { state.v[k - 1] };
    let vr = if k == n { 0.0 } else { state.v[k] };
    let q = d.model.exponent(law.p);
    let shape = if q == 0.0 {
        1.0
    } else {
        delta.max(0.0).powf(q)
    };
    let total = elastic + d.c * shape * (vl - vr);
    if law.tension {
        total
    } else {
        total.max(0.0)
    }
}

/// The energy of the chain's last grain: kinetic, plus the potential of the right wall's
/// contact (its spring to ground) if it has one.
fn target_energy(chain: &Chain, state: &State) -> f64 {
    let n = chain.len();
    let i = n - 1;
    0.5 * chain.mass()[i] * state.v[i] * state.v[i] + chain.contact_energy(&state.u, n)
}
