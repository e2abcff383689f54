//! When a run may stop: a bound on every force the protected contact can still feel.
//!
//! **The rule.** Grains `0..k` (the striker is grain 0, the left end is free) have *escaped* when
//! every contact among them and the contact `k` to grain `k` are open, their velocities do not
//! decrease from left to right (`v_0 <= v_1 <= ... <= v_{k-1}`), and `v_{k-1}` is below
//! `-sqrt(2 E_R (1 + MARGIN) / m_k)`, where `E_R` is the energy of the rest (grains `k..n`,
//! their kinetic energy and every contact right of contact `k`, walls and springs included).
//! Then the force the protected contact `c` can still feel is at most
//! - 0 if `c <= k` (it lies among the escaped grains or at their edge), else
//! - the force at the overlap whose potential energy is `E_R (1 + MARGIN)`, plus for a damped
//!   contact its dashpot at that overlap and at the largest closing speed `E_R` allows.
//!
//! A run that needs the peak stops when this bound is below the peak found; one that needs the
//! time above a fraction of the peak, when it is below that fraction of the peak; one that
//! needs the impulse, when it is 0.
//!
//! **The rest's own motion.** The rest's momentum `P_R` (its mass `M_R`) tightens the bound
//! where it cannot grow back: with a fixed wall at the right end and `P_R <= 0` (the rest moves
//! away from the wall), or a free right end (a target on no spring). Then every contact of the
//! rest holds at most `E_R (1 + MARGIN) - P_R^2 / (2 M_R)` of potential energy, and the bound
//! is the force there. When no prefix has escaped and the whole chain's momentum counts, the
//! whole chain is the rest (`k = 0`, the striker's velocity not final), with that bound. A column that has left the wall as a
//! slowly spreading clump (what dissipation makes of it) is then proven long before its last
//! grains have sorted themselves out.
//!
//! **Proof.** (1) No force acts on an escaped grain: its contacts are open. So each keeps its
//! velocity, and since each moves left no slower than its right neighbour, no gap among them
//! closes: they never touch again. (2) Grain `k` belongs to the rest, which exchanges nothing
//! with the escaped grains while contact `k` is open and has no energy source (the right end is
//! a fixed wall, a spring to ground or free; dashpots only take energy out). So its energy stays
//! at most `E_R`, and grain `k`'s kinetic energy with it: `v_k >= -sqrt(2 E_R / m_k) > v_{k-1}`.
//! Contact `k`'s gap therefore only widens, and (1) and (2) hold for all later time. (3) Every
//! potential energy is non-negative, so a contact of the rest holds at most `E_R`: its overlap
//! is at most the one whose potential is `E_R`, its force (increasing in the overlap) at most
//! the force there, and each grain's speed at most `sqrt(2 E_R / m)`. (4) A contact among the
//! escaped grains or at their edge stays open: force 0. (5) The rest's momentum changes only by
//! the right end's force (contact `k` is open for good, nothing else acts): a wall only pushes
//! it left, so `P_R <= 0` stays so and `P_R^2` only grows; with a free end it is constant. A
//! kinetic energy is at least its momentum's `P_R^2 / (2 M_R)` (Cauchy-Schwarz), so the
//! potential of any contact of the rest, at most `E_R` less the kinetic energy, is at most
//! `E_R - P_R^2 / (2 M_R)` for good; and so is the kinetic energy of the motion relative to the
//! centre of mass, which bounds each grain's speed relative to it, hence a contact's closing
//! speed (relative speeds are the same in that frame; towards the wall the centre of mass only
//! subtracts), as (3) with `E_R` replaced.
//!
//! **Why the margin.** The proof is for the exact dynamics. Velocity Verlet conserves a nearby
//! energy, not `E_R` itself; the energy it shows oscillates by a relative amount of order
//! `(dt / t_c)^2`, below 1e-4 at 160 steps per contact time (`Settings::default`). `MARGIN =
//! 1e-2` covers that a hundred times over; `validation/protector.rs` checks on random designs
//! that a stopped run's peak is the peak of the run to its end, bit for bit.
//!
//! The rule needs a free left end, no precompression and no damped sections (an absorbing layer
//! slows escaped grains, which could then be caught): without them the bound is infinite and
//! the run goes to its time cap. The rest's momentum counts only without gravity and with a
//! compression-only wall or a free right end (a spring to ground pushes both ways).

use crate::chain::Chain;
use crate::state::State;

/// The relative energy margin of the rule (see the module doc).
pub const MARGIN: f64 = 1e-2;

/// What the rule says about a state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// The largest force the protected contact can still feel (infinite when the rule does
    /// not apply).
    pub force: f64,
    /// The energy of the rest, `E_R` (infinite when the rule does not apply).
    pub energy: f64,
    /// Whether the striker (grain 0) has escaped, so its velocity is final.
    pub striker_free: bool,
}

const NONE: Bound = Bound {
    force: f64::INFINITY,
    energy: f64::INFINITY,
    striker_free: false,
};

/// Whether contact `k` is open and stays open while nothing pushes it (a two-sided spring
/// never is).
fn open(chain: &Chain, u: &[f64], k: usize) -> bool {
    match (chain.contact_law(k), chain.overlap(u, k)) {
        (Some(law), Some(x)) => !law.tension && x <= 0.0,
        _ => true, // no contact there (a free end)
    }
}

/// The bound for `state` on the force of contact `contact` (see the module doc).
pub fn bound(chain: &Chain, state: &State, contact: usize) -> Bound {
    let n = chain.len();
    let (u, v, m) = (&state.u, &state.v, chain.mass());
    let precompressed = chain.static_force.iter().any(|&f| f != 0.0);
    if chain.left.is_some() || precompressed || !chain.damped.is_empty() || n == 0 {
        return NONE;
    }
    // The largest prefix whose inner contacts are open and velocities sorted.
    let mut k_max = 1;
    while k_max < n && open(chain, u, k_max) && v[k_max - 1] <= v[k_max] {
        k_max += 1;
    }
    // From the right: E_R(k) = E_R(k + 1) + grain k's kinetic energy + contact k + 1's energy,
    // and the rest's momentum and mass.
    let (mut e_rest, mut p_rest, mut m_rest) = (0.0, 0.0, 0.0);
    for k in (1..=n).rev() {
        if k < n {
            e_rest += 0.5 * m[k] * v[k] * v[k] + chain.contact_energy(u, k + 1);
            p_rest += m[k] * v[k];
            m_rest += m[k];
        }
        if k > k_max || !open(chain, u, k) {
            continue;
        }
        let e = e_rest * (1.0 + MARGIN);
        let escapes = if k == n {
            // Nothing right of the prefix: a wall or spring must be left behind for good.
            chain.contact_law(n).is_none() || v[n - 1] < 0.0
        } else {
            v[k - 1] < -(2.0 * e / m[k]).sqrt()
        };
        if escapes {
            let force = if contact <= k {
                0.0
            } else {
                force_bound(chain, contact, e - bulk(chain, p_rest, m_rest))
            };
            return Bound {
                force,
                energy: e,
                striker_free: true,
            };
        }
    }
    // No prefix has escaped: the whole chain is the rest, where its momentum counts.
    let e = (e_rest + 0.5 * m[0] * v[0] * v[0] + chain.contact_energy(u, 1)) * (1.0 + MARGIN);
    let b = bulk(chain, p_rest + m[0] * v[0], m_rest + m[0]);
    if b > 0.0 && contact > 0 {
        return Bound {
            force: force_bound(chain, contact, e - b),
            energy: e,
            striker_free: false,
        };
    }
    NONE
}

/// The kinetic energy of the rest's centre of mass that it keeps for good (its momentum `p`,
/// its mass `m`; module doc, (5)): `p^2 / (2 m)` where the momentum cannot shrink (no gravity;
/// a free right end, or a compression-only wall the rest moves away from, `p <= 0`), else 0.
fn bulk(chain: &Chain, p: f64, m: f64) -> f64 {
    let kept = chain.gravity() == 0.0
        && match chain.contact_law(chain.len()) {
            None => true,
            Some(law) => !law.tension && p <= 0.0,
        };
    if kept && m > 0.0 {
        p * p / (2.0 * m)
    } else {
        0.0
    }
}

/// The largest force contact `c` can feel with energy `e` in its part of the chain.
fn force_bound(chain: &Chain, c: usize, e: f64) -> f64 {
    let Some(law) = chain.contact_law(c) else {
        return 0.0;
    };
    let p = law.p;
    let x = ((p + 1.0) * e / law.eta).powf(1.0 / (p + 1.0));
    let elastic = law.eta * x.powf(p);
    let Some(d) = law.damping.filter(|d| d.c > 0.0) else {
        return elastic;
    };
    let n = chain.len();
    let m = chain.mass();
    let speed = |i: usize| (2.0 * e / m[i]).sqrt();
    let closing = if c > 0 { speed(c - 1) } else { 0.0 } + if c < n { speed(c) } else { 0.0 };
    elastic + d.c * x.powf(d.model.exponent(p)) * closing
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::{ChainBuilder, ContactLaw, End};

    /// Four unit Hertz grains moving as one block at speed `v`, compressed by `overlap` at each
    /// inner contact and just touching the right end's `law`.
    fn block(v: f64, overlap: f64, right: ContactLaw) -> (Chain, State) {
        let chain = ChainBuilder::new()
            .grains(4, 1.0, ContactLaw::hertz(1.0))
            .right(End::Wall(right))
            .build()
            .unwrap();
        let mut state = State::at_rest(4);
        for i in 0..4 {
            state.u[i] = overlap * (3 - i) as f64;
            state.v[i] = v;
        }
        (chain, state)
    }

    /// The rest's momentum counts only where it cannot shrink. A block moving towards a wall
    /// will give the wall all it has: with no grain escaped and no momentum to count, the rule
    /// does not apply (an infinite bound). The same block moving away from the wall keeps its
    /// centre of mass's energy for good: the bound is the force at the overlap holding the rest,
    /// its compression and the margin. On a spring to ground, which can pull it back, the rule
    /// does not apply either.
    #[test]
    fn the_momentum_counts_only_where_it_cannot_shrink() {
        let wall = ContactLaw::hertz(1.0);
        let at = |chain: &Chain, e: f64| force_bound(chain, 4, e);
        let (chain, towards) = block(1.0, 0.0, wall);
        assert_eq!(bound(&chain, &towards, 4).force, f64::INFINITY);
        let (chain, away) = block(-1.0, 0.1, wall);
        let compression: f64 = (1..4).map(|k| chain.contact_energy(&away.u, k)).sum();
        let got = bound(&chain, &away, 4);
        let kept = (2.0 + compression) * (1.0 + MARGIN) - 2.0;
        // The rule sums the same energies from the right: equal to rounding.
        assert!(
            (got.force / at(&chain, kept) - 1.0).abs() < 1e-12,
            "{got:?} against {}",
            at(&chain, kept)
        );
        assert!(got.force < 0.2 * at(&chain, 2.0), "{got:?}");
        assert!(!got.striker_free);
        let (chain, sprung) = block(-1.0, 0.1, ContactLaw::linear_spring(1.0));
        assert_eq!(bound(&chain, &sprung, 4).force, f64::INFINITY);
    }
}
