//! Observables, computed on demand at output times only.
//!
//! Energies follow the paper: the energy of a grain is its kinetic energy plus half the potential
//! of each of its two contacts (a wall contact's whole potential goes to its one grain, so grain
//! energies add up to the total). Potentials are counted relative to their static value, so a
//! precompressed chain at rest has zero energy.

mod pulses;
pub mod tracking;

pub use pulses::{detect_pulses, Pulse, PulseRule};
pub use tracking::{Track, TrackPoint, TrackRule, Tracker};

/// Which outputs (by index) a snapshot or a pulse detection is taken at.
#[derive(Clone, Debug, PartialEq)]
pub enum Schedule {
    /// Every output whose index is a multiple of this (at least 1).
    Every(u64),
    /// Exactly these output indices.
    At(Vec<u64>),
}

impl Schedule {
    /// Whether output `index` is on the schedule.
    pub fn wants(&self, index: u64) -> bool {
        match self {
            Schedule::Every(k) => index.is_multiple_of((*k).max(1)),
            Schedule::At(at) => at.contains(&index),
        }
    }

    /// The last output index up to `end` on the schedule, if any.
    pub fn last(&self, end: u64) -> Option<u64> {
        match self {
            Schedule::Every(k) => Some(end / (*k).max(1) * (*k).max(1)),
            Schedule::At(at) => at.iter().copied().filter(|&i| i <= end).max(),
        }
    }
}

use crate::chain::{Chain, Window};
use crate::state::State;
use serde::{Deserialize, Serialize};

/// Totals over the chain.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Totals {
    /// Kinetic energy, the sum of `m v^2 / 2`.
    pub kinetic: f64,
    /// Potential energy of the contacts (walls included), relative to their static values, plus
    /// under gravity its potential `-g sum m u` ([`Chain::gravity_energy`]).
    pub potential: f64,
    /// `kinetic + potential`.
    pub total: f64,
    /// Momentum, the sum of `m v`.
    pub momentum: f64,
}

/// Kinetic, potential and total energy and momentum. Sums over the grains ever touched (every
/// other grain is at rest with static contacts and contributes exactly zero).
pub fn totals(chain: &Chain, state: &State, win: &Window) -> Totals {
    let n = chain.len();
    let r = win.ever();
    let (ke, mom) = kinetic_and_momentum(chain, state, r.clone());
    let pe = if r.is_empty() {
        0.0
    } else {
        chain.potential_energy(&state.u, r.start, r.end.min(n))
    };
    // Gravity's potential (`-g m u`; none without gravity, where the sum is not formed).
    let pe = if chain.gravity() != 0.0 {
        pe + chain.gravity_energy(&state.u)
    } else {
        pe
    };
    Totals {
        kinetic: ke,
        potential: pe,
        total: ke + pe,
        momentum: mom,
    }
}

/// Kinetic energy and momentum of grains `range`, summed in order.
fn kinetic_and_momentum(chain: &Chain, state: &State, range: std::ops::Range<usize>) -> (f64, f64) {
    let (mut ke, mut mom) = (0.0, 0.0);
    for i in range {
        let mv = chain.mass[i] * state.v[i];
        ke += 0.5 * mv * state.v[i];
        mom += mv;
    }
    (ke, mom)
}

/// [`totals`] for a run that calls it at every output: the potential energy of the contacts
/// between grains at rest outside the window's envelope (split off, put to sleep or dropped by
/// the causal horizon: their displacements cannot change while they stay outside) is kept
/// between calls and only extended when the envelope shrinks, so a call costs the envelope, not
/// every grain ever touched. Kinetic energy and momentum are summed over the envelope, which
/// gives the bits of [`totals`] (every grain outside has `v = 0` exactly and adds `+0.0`); the
/// potential energy is the same sum in another order (left rest, envelope, right rest).
#[derive(Clone, Debug, Default)]
pub struct TotalsCache {
    /// `(ever_lo, lo, pe)`: the contacts `ever_lo..lo` (both grains left of the envelope).
    left: Option<(usize, usize, f64)>,
    /// `(hi, ever_hi, pe)`: the contacts `hi + 1..=min(ever_hi, n)`.
    right: Option<(usize, usize, f64)>,
}

impl TotalsCache {
    /// The totals of the chain's state, as [`totals`].
    pub fn totals(&mut self, chain: &Chain, state: &State, win: &Window) -> Totals {
        let n = chain.len();
        let (elo, ehi) = (win.ever_lo, win.ever_hi);
        if elo >= ehi {
            return totals(chain, state, win);
        }
        let (lo, hi) = (
            win.lo.clamp(elo, ehi),
            win.hi.clamp(elo, ehi).max(win.lo.clamp(elo, ehi)),
        );
        let u = &state.u;
        // Left rest: contacts elo..lo (contact k joins grains k - 1 and k, both below lo).
        let left = match self.left {
            Some((e, l, pe)) if e == elo && l == lo => pe,
            Some((e, l, pe)) if e == elo && l < lo => {
                let add = chain.potential_energy(u, l, lo - 1);
                pe + add
            }
            _ if lo > elo => chain.potential_energy(u, elo, lo - 1),
            _ => 0.0,
        };
        self.left = Some((elo, lo, left));
        // Right rest: contacts hi + 1..=min(ehi, n).
        let last = ehi.min(n);
        let right = match self.right {
            Some((h, e, pe)) if e == ehi && h == hi => pe,
            Some((h, e, pe)) if e == ehi && hi < h => pe + chain.potential_energy(u, hi + 1, h),
            _ if hi < last => chain.potential_energy(u, hi + 1, last),
            _ => 0.0,
        };
        self.right = Some((hi, ehi, right));
        let (ke, mom) = kinetic_and_momentum(chain, state, lo..hi);
        let mid = chain.potential_energy(u, lo, hi.min(n));
        let pe = left + mid + right;
        let pe = if chain.gravity() != 0.0 {
            pe + chain.gravity_energy(u)
        } else {
            pe
        };
        Totals {
            kinetic: ke,
            potential: pe,
            total: ke + pe,
            momentum: mom,
        }
    }
}

/// Energy of grain `i` (kinetic plus half of each contact's potential; a wall's whole).
pub fn grain_energy(chain: &Chain, state: &State, i: usize) -> f64 {
    let n = chain.len();
    let ke = 0.5 * chain.mass[i] * state.v[i] * state.v[i];
    let left = chain.contact_energy(&state.u, i) * if i == 0 { 1.0 } else { 0.5 };
    let right = chain.contact_energy(&state.u, i + 1) * if i + 1 == n { 1.0 } else { 0.5 };
    ke + left + right
}

/// Energies of grains `range` into `out` (cleared first).
pub fn grain_energies(
    chain: &Chain,
    state: &State,
    range: std::ops::Range<usize>,
    out: &mut Vec<f64>,
) {
    out.clear();
    out.extend(range.map(|i| grain_energy(chain, state, i)));
}

/// Energy of the grains `first..=last` (internal indices). Only grains ever touched are visited.
pub fn region_energy(chain: &Chain, state: &State, win: &Window, first: usize, last: usize) -> f64 {
    let lo = first.max(win.ever_lo);
    let hi = (last + 1).min(win.ever_hi);
    // Start from +0.0 so an untouched region reads 0, not -0 (the empty f64 sum).
    (lo..hi).fold(0.0, |acc, i| acc + grain_energy(chain, state, i))
}

/// [`region_energy`], the same bits, with each contact's energy computed once (not once per
/// grain beside it) and one dispatch per segment of contacts; `buf` is scratch space, reused
/// between calls (the recorder's regions at every output; an outer section of 50,000 grains
/// cost as much as integrating it).
pub fn region_energy_with(
    chain: &Chain,
    state: &State,
    win: &Window,
    (first, last): (usize, usize),
    buf: &mut Vec<f64>,
) -> f64 {
    let n = chain.len();
    let lo = first.max(win.ever_lo);
    let hi = (last + 1).min(win.ever_hi);
    if lo >= hi {
        return 0.0;
    }
    // Contacts lo..=hi: grain i has contact i on its left and i + 1 on its right.
    chain.contact_energies(&state.u, lo, hi, buf);
    let mut acc = 0.0;
    for i in lo..hi {
        let ke = 0.5 * chain.mass[i] * state.v[i] * state.v[i];
        let left = buf[i - lo] * if i == 0 { 1.0 } else { 0.5 };
        let right = buf[i + 1 - lo] * if i + 1 == n { 1.0 } else { 0.5 };
        acc += ke + left + right;
    }
    acc
}

/// Momentum of the grains `first..=last` (internal indices). Only grains ever touched are
/// visited.
pub fn region_momentum(
    chain: &Chain,
    state: &State,
    win: &Window,
    first: usize,
    last: usize,
) -> f64 {
    let lo = first.max(win.ever_lo);
    let hi = (last + 1).min(win.ever_hi);
    (lo..hi).fold(0.0, |acc, i| acc + chain.mass[i] * state.v[i])
}

/// Per-grain quantities a snapshot can record.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "kebab-case")]
pub enum Field {
    /// Velocity `v = du/dt`.
    Velocity,
    /// Displacement `u` from the grain's position at rest.
    Displacement,
    /// Force of the contact between this grain and the next one on the right (0 at a free end).
    Force,
    /// Overlap (compression, precompression included) of the contact between this grain and the
    /// next one on the right; negative where they are apart (0 at a free end).
    Overlap,
    /// The grain's energy: kinetic plus half of each contact's potential (a wall contact's
    /// whole), as in the module docs.
    Energy,
    /// The grain's mass (so momentum and wave amplitude need no lookup of the sections).
    Mass,
}

impl Field {
    /// The field's name in scene files and CSV headers (kebab-case, as serde spells it).
    pub fn name(self) -> &'static str {
        match self {
            Field::Velocity => "velocity",
            Field::Displacement => "displacement",
            Field::Force => "force",
            Field::Overlap => "overlap",
            Field::Energy => "energy",
            Field::Mass => "mass",
        }
    }

    /// The value of this field for grain `i`.
    pub fn value(self, chain: &Chain, state: &State, i: usize) -> f64 {
        match self {
            Field::Velocity => state.v[i],
            Field::Displacement => state.u[i],
            Field::Force => match (chain.contact_law(i + 1), chain.overlap(&state.u, i + 1)) {
                (Some(l), Some(x)) => l.force(x),
                _ => 0.0,
            },
            Field::Overlap => chain.overlap(&state.u, i + 1).unwrap_or(0.0),
            Field::Energy => grain_energy(chain, state, i),
            Field::Mass => chain.mass[i],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::{ChainBuilder, ContactLaw, End};

    /// `region_energy_with` (each contact once, per segment) gives the bits of
    /// `region_energy` (per grain, each contact twice) for every region of a chain of mixed
    /// laws between walls, and `TotalsCache` the bits of `totals` for kinetic energy and
    /// momentum.
    #[test]
    fn fast_region_energy_and_totals_match_the_plain_sums() {
        let chain = ChainBuilder::new()
            .grains(7, 1.0, ContactLaw::hertz(5657.0))
            .grains(5, 2.0, ContactLaw::new(1.0, 5657.0))
            .grains(6, 0.5, ContactLaw::new(2.0, 300.0))
            .grains(5, 0.1, ContactLaw::new(2.5, 300.0))
            .left(End::Wall(ContactLaw::hertz(5657.0)))
            .right(End::Wall(ContactLaw::new(1.0, 5657.0)))
            .build()
            .unwrap();
        let n = chain.len();
        let mut st = State::at_rest(n);
        for i in 0..n {
            st.u[i] = 0.02 * ((i * 7919 % 61) as f64 / 61.0 - 0.5);
            st.v[i] = (i * 104729 % 53) as f64 / 53.0 - 0.5;
        }
        let win = Window::full(n);
        let mut buf = Vec::new();
        for a in 0..n {
            for b in a..n {
                let plain = region_energy(&chain, &st, &win, a, b);
                let fast = region_energy_with(&chain, &st, &win, (a, b), &mut buf);
                assert_eq!(plain.to_bits(), fast.to_bits(), "grains {a}..={b}");
            }
        }
        let (p, c) = (
            totals(&chain, &st, &win),
            TotalsCache::default().totals(&chain, &st, &win),
        );
        assert_eq!(p.kinetic.to_bits(), c.kinetic.to_bits());
        assert_eq!(p.momentum.to_bits(), c.momentum.to_bits());
        assert!((p.potential - c.potential).abs() <= 1e-12 * p.potential.abs());
    }

    #[test]
    fn grain_energies_add_up_to_total() {
        let law = ContactLaw::new(1.5, 3.0);
        let chain = ChainBuilder::new()
            .grains(4, 2.0, law)
            .grains(3, 1.0, ContactLaw::new(2.0, 3.0))
            .left(End::Wall(law))
            .build()
            .unwrap();
        let mut s = State::at_rest(7);
        s.u = vec![-0.1, 0.2, 0.1, 0.3, -0.2, 0.0, 0.05];
        s.v = vec![1.0, -0.5, 0.2, 0.0, 0.3, 0.1, -0.4];
        let win = Window::full(7);
        let t = totals(&chain, &s, &win);
        let sum: f64 = (0..7).map(|i| grain_energy(&chain, &s, i)).sum();
        approx::assert_relative_eq!(t.total, sum, max_relative = 1e-14);
        approx::assert_relative_eq!(
            region_energy(&chain, &s, &win, 0, 6),
            sum,
            max_relative = 1e-14
        );
        // momentum and kinetic energy by hand
        let p: f64 = s.v.iter().zip(chain.mass()).map(|(v, m)| v * m).sum();
        assert_eq!(t.momentum, p);
        // grains 2..=4: 2.0 * 0.2 + 2.0 * 0.0 + 1.0 * 0.3
        approx::assert_relative_eq!(
            region_momentum(&chain, &s, &win, 2, 4),
            0.7,
            max_relative = 1e-15
        );
        // overlap of the contact right of grain 1: u1 - u2 = 0.2 - 0.1; mass of grain 5: 1.0
        approx::assert_relative_eq!(
            Field::Overlap.value(&chain, &s, 1),
            0.1,
            max_relative = 1e-14
        );
        assert_eq!(Field::Mass.value(&chain, &s, 5), 1.0);
        // the last grain has a free end on the right: no contact, overlap 0
        assert_eq!(Field::Overlap.value(&chain, &s, 6), 0.0);
        // wall contact overlap 0.1 -> 3 * 0.1^2.5 / 2.5
        approx::assert_relative_eq!(
            chain.contact_energy(&s.u, 0),
            3.0 * 0.1f64.powf(2.5) / 2.5,
            max_relative = 1e-14
        );
    }
}
