//! The dynamical state, as structure-of-arrays.

/// Displacements and velocities of every grain at time `t`.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Time, in the scene's units.
    pub t: f64,
    /// Displacement of each grain from its rest position.
    pub u: Vec<f64>,
    /// Velocity of each grain.
    pub v: Vec<f64>,
    /// Energy each grain has lost to contact damping so far (the kinetic energy the damping
    /// flow took from it; empty for a chain without damped contacts).
    pub dissipated: Vec<f64>,
}

impl State {
    /// Every grain at rest at t = 0.
    pub fn at_rest(n: usize) -> Self {
        State {
            t: 0.0,
            u: vec![0.0; n],
            v: vec![0.0; n],
            dissipated: Vec::new(),
        }
    }

    /// Number of grains (a striker included).
    pub fn len(&self) -> usize {
        self.u.len()
    }

    /// True for a state of no grains.
    pub fn is_empty(&self) -> bool {
        self.u.is_empty()
    }

    /// First grain in `range` whose displacement or velocity is not finite.
    pub fn first_non_finite(&self, range: std::ops::Range<usize>) -> Option<usize> {
        range
            .into_iter()
            .find(|&i| !(self.u[i].is_finite() && self.v[i].is_finite()))
    }
}
