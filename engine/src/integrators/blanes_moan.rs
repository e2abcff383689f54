//! The optimized fourth-order symmetric symplectic Runge-Kutta-Nystrom method of Blanes & Moan,
//! J. Comput. Appl. Math. 142, 313 (2002), "SRKN_6^b": six force evaluations per step (in a
//! scene's run the last kick of one step and the first of the next are fused into one), error
//! constants far smaller than those of the Forest-Ruth / Yoshida triple jump.

use super::splitting::{Scheme, Split, Splitting};

const A1: f64 = 0.245298957184271;
const A2: f64 = 0.604872665711080;
const A3: f64 = 0.5 - (A1 + A2);
const B1: f64 = 0.0829844064174052;
const B2: f64 = 0.396309801498368;
const B3: f64 = -0.0390563049223486;
const B4: f64 = 1.0 - 2.0 * (B1 + B2 + B3);

/// Kick B1, drift A1, kick B2, ... kick B1 (seven kicks, six drifts); a damped stretch's flow
/// after the central kick (B4, stage 2).
pub(crate) const SRKN6B: Splitting = Splitting {
    kicks: &[B1, B2, B3, B4, B3, B2, B1],
    drifts: &[A1, A2, A3, A3, A2, A1],
    central: 2,
};

/// Blanes & Moan's weights ([`SRKN6B`]) as a type.
pub struct Srkn6b;

impl Scheme for Srkn6b {
    const SPLITTING: Splitting = SRKN6B;
}

/// Blanes & Moan (2002) SRKN_6^b: fourth order, symplectic, time-reversible, six force
/// evaluations per step ([`super::Method::BlanesMoan4`]).
pub type BlanesMoan4 = Split<Srkn6b>;
