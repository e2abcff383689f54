//! The active window: the grains that are integrated.
//!
//! Grains outside `[lo, hi)` are exactly at rest: zero displacement and velocity, and a net force
//! that evaluates to exactly zero. Integrating them would only add exact zeros, so skipping them
//! changes no bit of the result. After every force evaluation the one grain on each side of the
//! window is checked (see [`Chain::accelerations`]) and joins the window when its acceleration is
//! not exactly zero; a disturbance can cross at most one contact per force evaluation, so the
//! window always covers it.

use super::Chain;

/// The integrated range of grains, `[lo, hi)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub lo: usize,
    pub hi: usize,
    /// False: the window is always the whole chain.
    pub skip: bool,
    /// Every grain ever in the window lies in `[ever_lo, ever_hi)` (sleeping grains keep their
    /// displacement and may store contact energy, so observables sum over this range).
    pub ever_lo: usize,
    pub ever_hi: usize,
}

impl Window {
    /// The whole chain, nothing skipped.
    pub fn full(n: usize) -> Self {
        Window {
            lo: 0,
            hi: n,
            skip: false,
            ever_lo: 0,
            ever_hi: n,
        }
    }

    /// The smallest window that holds every grain with a nonzero displacement or velocity, or a
    /// nonzero net force at rest. With `skip == false`, the whole chain.
    pub fn seed(chain: &Chain, u: &[f64], v: &[f64], skip: bool) -> Self {
        let n = chain.len();
        if !skip {
            return Self::full(n);
        }
        let moving = |i: usize| u[i] != 0.0 || v[i] != 0.0;
        let first = (0..n).find(|&i| moving(i));
        let last = (0..n).rev().find(|&i| moving(i));
        let mut lo = first.unwrap_or(n);
        let mut hi = last.map_or(0, |l| l + 1);
        if let Some((a, b)) = chain.static_imbalance() {
            lo = lo.min(a);
            hi = hi.max(b + 1);
        }
        if lo >= hi {
            // Nothing moves: an empty window at the left end; it grows if anything ever moves.
            return Window {
                lo: 0,
                hi: 0,
                skip,
                ever_lo: 0,
                ever_hi: 0,
            };
        }
        Window {
            lo,
            hi,
            skip,
            ever_lo: lo,
            ever_hi: hi,
        }
    }

    /// Number of grains in the window.
    pub fn len(&self) -> usize {
        self.hi - self.lo
    }

    pub fn is_empty(&self) -> bool {
        self.hi <= self.lo
    }

    pub fn range(&self) -> std::ops::Range<usize> {
        self.lo..self.hi
    }

    /// Every grain that has ever been in the window.
    pub fn ever(&self) -> std::ops::Range<usize> {
        self.ever_lo..self.ever_hi
    }

    /// Grains never touched so far.
    pub fn untouched(&self, n: usize) -> usize {
        n - (self.ever_hi - self.ever_lo)
    }
}
