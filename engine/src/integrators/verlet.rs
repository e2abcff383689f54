//! Velocity Verlet: second order, symplectic, time-reversible.
//!
//! Kick-drift-kick, one force evaluation per step. In a scene's run ([`super::Split`]) the
//! closing half kick of one step is fused with the opening half kick of the next (`v += dt a`),
//! so a step is one fused sweep over the window ([`crate::chain::Chain`]'s
//! `drift_forces_kick`: drift, force, acceleration and kick grain by grain). Velocities are
//! synchronized (the closing half kick) at the end of every `advance_to`, i.e. at every output
//! time.

use super::splitting::{Scheme, Split, Splitting};

/// Kick 1/2, drift 1, kick 1/2; a damped stretch's flow after the step.
pub(crate) const KDK: Splitting = Splitting {
    kicks: &[0.5, 0.5],
    drifts: &[1.0],
    central: 0,
};

/// Velocity Verlet's weights ([`KDK`]) as a type.
pub struct Kdk;

impl Scheme for Kdk {
    const SPLITTING: Splitting = KDK;
}

/// Velocity Verlet (kick-drift-kick) with fused sweeps: second order, symplectic,
/// time-reversible, one force evaluation per step ([`super::Method::Verlet`]).
pub type Verlet = Split<Kdk>;
