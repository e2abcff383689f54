//! The chain's work over the active window: which grains an island's evaluation covers, the
//! margin grains that join it, accelerations, and the damped sections' exact flow. Apart from
//! `mod.rs`, which defines the chain without knowing the window that integrates it.

use super::{Chain, Island, Window};

impl Chain {
    /// The grains whose accelerations an evaluation of island `isl` computes: the island plus a
    /// one-grain margin on each side (the whole chain when nothing is skipped).
    #[inline(always)]
    pub(crate) fn eval_range(&self, win: &Window, isl: Island) -> (usize, usize) {
        let n = self.len();
        if win.skip {
            (isl.lo.saturating_sub(1), (isl.hi + 1).min(n))
        } else {
            (0, n)
        }
    }

    /// Let a margin grain of island `j` whose acceleration is not exactly zero (is above the
    /// sleep rule's wake threshold) join the island. With `reset`, a margin grain that stays at
    /// rest gets its velocity back to zero (it was kicked by a force below the threshold, which a
    /// resting grain ignores; under the exact rule its acceleration was zero and nothing changes).
    /// Returns true when the island grew.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn grow(
        &self,
        win: &mut Window,
        j: usize,
        v: &mut [f64],
        a: &[f64],
        g0: usize,
        g1: usize,
        reset: bool,
    ) -> bool {
        if !win.skip {
            return false;
        }
        let mut isl = win.islands()[j];
        let wf = win.wake_force;
        // NaN wakes (the blow-up check must see it).
        let wakes = |g: usize| !(a[g].abs() <= wf * self.inv_mass[g]);
        let mut changed = false;
        // A grain beyond the causal horizon never joins (`Window::clip`): it stays where it was
        // dropped, and is reset to rest like a margin grain that does not wake.
        let (limit_lo, limit_hi) = win.limit();
        if g0 < isl.lo {
            if g0 >= limit_lo && wakes(g0) {
                isl.lo = g0;
                changed = true;
            } else if reset && v[g0] != 0.0 {
                v[g0] = 0.0;
            }
        }
        if g1 > isl.hi {
            if g1 <= limit_hi && wakes(g1 - 1) {
                isl.hi = g1;
                changed = true;
            } else if reset && v[g1 - 1] != 0.0 {
                v[g1 - 1] = 0.0;
            }
        }
        if changed {
            win.set_island(j, isl);
        }
        changed
    }

    /// Accelerations of every grain in the islands of `win` (plus a one-grain margin on each
    /// side, which joins its island when its acceleration is not exactly zero). `f` and `a` have
    /// lengths `n + 1` and `n`.
    #[inline(always)]
    pub fn accelerations(&self, u: &[f64], f: &mut [f64], a: &mut [f64], win: &mut Window) {
        let mut grew = false;
        for j in 0..win.islands().len() {
            let (g0, g1) = self.eval_range(win, win.islands()[j]);
            self.island_accelerations(u, f, a, g0, g1);
            grew |= self.grow(win, j, &mut [], a, g0, g1, false);
        }
        win.after_growth(grew);
    }

    /// The exact flow of `dv/dt = -rate v` over the damped grains in the islands: `v *= factor`.
    /// Adds the kinetic energy and the momentum taken out to `absorbed`. Grains at rest stay
    /// exactly at rest.
    #[inline]
    pub(crate) fn damp(
        &self,
        v: &mut [f64],
        factors: &[f64],
        win: &Window,
        absorbed: &mut (f64, f64),
    ) {
        for (&(first, end, _), &d) in self.damped.iter().zip(factors) {
            for isl in win.islands() {
                let (lo, hi) = (isl.lo.max(first), isl.hi.min(end));
                if lo >= hi {
                    continue;
                }
                for (vi, &m) in v[lo..hi].iter_mut().zip(&self.mass[lo..hi]) {
                    let v0 = *vi;
                    let v1 = v0 * d;
                    absorbed.0 += 0.5 * m * (v0 * v0 - v1 * v1);
                    absorbed.1 += m * (v0 - v1);
                    *vi = v1;
                }
            }
        }
    }
}
