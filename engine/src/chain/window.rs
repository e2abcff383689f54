//! The active window: the grains that are integrated, as a set of islands.
//!
//! Every grain outside the islands is at rest: zero velocity and a net force that evaluates to
//! exactly zero (or, with an approximate [`crate::integrators::Sleep`] rule, a net force below its
//! threshold, which a resting grain ignores). Integrating a grain at rest would only add exact
//! zeros, so skipping it changes no bit of the result. After every force evaluation the one grain
//! on each side of each island (its margin) is checked and joins the island when its acceleration
//! is not exactly zero (above the sleep threshold); a disturbance can cross at most one contact
//! per force evaluation, so the islands always cover it.
//!
//! Islands are kept at least [`MIN_GAP`] resting grains apart, so that no grain is the margin of
//! two islands and no contact is computed by two sweeps: sweeping the islands one after another
//! then does exactly the arithmetic of one sweep over the whole envelope. Islands that grow closer
//! merge. They split (at output times, see [`crate::run::Simulation`]) where a stretch of grains
//! inside an island has come to rest.

use super::Chain;

/// Shortest stretch of resting grains inside an island that splits it in two. Each island costs
/// a fixed overhead per sweep (its two edge contacts, a scalar first grain, the margin test:
/// measured in BENCHMARKS.md, "Islands"), so splitting off a shorter stretch would cost more than
/// it saves.
pub const MIN_SPLIT: usize = 64;

/// Fewest resting grains between two islands: each island's margin is one grain, and the grain
/// between the two margins is read (for the margins' outer contacts) but written by neither sweep.
pub const MIN_GAP: usize = 3;

/// One interval of integrated grains, `[lo, hi)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Island {
    /// First grain of the island (internal index).
    pub lo: usize,
    /// One past the last grain of the island.
    pub hi: usize,
}

impl Island {
    /// Number of grains in the island.
    pub fn len(&self) -> usize {
        self.hi - self.lo
    }
    /// True when the island holds no grain.
    pub fn is_empty(&self) -> bool {
        self.hi <= self.lo
    }
    /// The island's grains as a range of internal indices, `lo..hi`.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.lo..self.hi
    }
}

/// The integrated grains: islands, their envelope `[lo, hi)`, and every grain ever integrated.
#[derive(Clone, Debug, PartialEq)]
pub struct Window {
    /// Envelope of the islands: the first integrated grain.
    pub lo: usize,
    /// Envelope of the islands: one past the last integrated grain.
    pub hi: usize,
    /// False: the window is always the whole chain.
    pub skip: bool,
    /// Every grain ever in the window lies in `[ever_lo, ever_hi)` (resting grains keep their
    /// displacement and may store contact energy, so observables sum over this range).
    pub ever_lo: usize,
    /// One past the last grain ever in the window (see `ever_lo`).
    pub ever_hi: usize,
    /// Sorted, disjoint, at least [`MIN_GAP`] apart; empty when nothing is integrated.
    islands: Vec<Island>,
    spare: Vec<Island>,
    /// Acceleration below which a resting margin grain stays at rest, as a force (0: exact rule,
    /// any nonzero acceleration wakes it).
    pub(crate) wake_force: f64,
    /// The causal horizon: no grain outside `[limit_lo, limit_hi)` joins an island (grains
    /// beyond it were dropped from the integration, see [`Window::clip`]). `(0, usize::MAX)`
    /// when no horizon is set.
    limit_lo: usize,
    limit_hi: usize,
}

impl Window {
    /// The whole chain, nothing skipped.
    pub fn full(n: usize) -> Self {
        let mut w = Window {
            lo: 0,
            hi: n,
            skip: false,
            ever_lo: 0,
            ever_hi: n,
            islands: Vec::with_capacity(16),
            spare: Vec::new(),
            wake_force: 0.0,
            limit_lo: 0,
            limit_hi: usize::MAX,
        };
        if n > 0 {
            w.islands.push(Island { lo: 0, hi: n });
        }
        w
    }

    /// The islands that hold every grain with a nonzero displacement or velocity, or a nonzero
    /// net force at rest. With `split == false` one interval from the first such grain to the
    /// last (what integrators that do not sweep islands need); with `skip == false`, the whole
    /// chain.
    pub fn seed(chain: &Chain, u: &[f64], v: &[f64], skip: bool, split: bool) -> Self {
        let n = chain.len();
        if !skip {
            return Self::full(n);
        }
        let mut w = Window {
            lo: 0,
            hi: 0,
            skip,
            ever_lo: 0,
            ever_hi: 0,
            islands: Vec::with_capacity(16),
            spare: Vec::new(),
            wake_force: 0.0,
            limit_lo: 0,
            limit_hi: usize::MAX,
        };
        for i in (0..n).filter(|&i| u[i] != 0.0 || v[i] != 0.0) {
            w.push_grains(i, i + 1);
        }
        if let Some((a, b)) = chain.static_imbalance() {
            // Precompressed chains are balanced everywhere or rejected by the builder, so this
            // is the whole imbalanced stretch as one island, merged with what overlaps it.
            w.insert(Island { lo: a, hi: b + 1 });
        }
        if !split && !w.islands.is_empty() {
            let (lo, hi) = (w.islands[0].lo, w.islands[w.islands.len() - 1].hi);
            w.islands.clear();
            w.islands.push(Island { lo, hi });
        }
        w.update_envelope();
        w.ever_lo = w.lo;
        w.ever_hi = w.hi;
        w
    }

    /// Append grains `[lo, hi)` (to the right of every island), merging when closer than
    /// [`MIN_GAP`].
    fn push_grains(&mut self, lo: usize, hi: usize) {
        match self.islands.last_mut() {
            Some(last) if lo < last.hi + MIN_GAP => last.hi = last.hi.max(hi),
            _ => self.islands.push(Island { lo, hi }),
        }
    }

    /// Insert an island anywhere, merging what comes within [`MIN_GAP`] of it.
    fn insert(&mut self, isl: Island) {
        let pos = self.islands.partition_point(|x| x.lo < isl.lo);
        self.islands.insert(pos, isl);
        self.merge_close();
    }

    /// Net force below which a resting margin grain stays at rest (0: the exact rule).
    pub fn set_wake_force(&mut self, force: f64) {
        self.wake_force = force;
    }

    fn update_envelope(&mut self) {
        match (self.islands.first(), self.islands.last()) {
            (Some(f), Some(l)) => {
                self.lo = f.lo;
                self.hi = l.hi;
            }
            _ => {
                // Nothing integrated: an empty envelope where the last one began.
                self.hi = self.lo;
            }
        }
    }

    /// Merge islands that have grown closer than [`MIN_GAP`] (the grains between them are at
    /// rest, and integrating them adds nothing).
    pub(crate) fn merge_close(&mut self) {
        let mut k = 0;
        for j in 1..self.islands.len() {
            if self.islands[j].lo < self.islands[k].hi + MIN_GAP {
                self.islands[k].hi = self.islands[k].hi.max(self.islands[j].hi);
            } else {
                k += 1;
                self.islands[k] = self.islands[j];
            }
        }
        if !self.islands.is_empty() {
            self.islands.truncate(k + 1);
        }
        self.update_envelope();
    }

    /// Island `j` grew to `isl` (by its margins): keeps the envelope and the ever-touched range.
    #[inline(always)]
    pub(crate) fn set_island(&mut self, j: usize, isl: Island) {
        self.islands[j] = isl;
        self.lo = self.lo.min(isl.lo);
        self.hi = self.hi.max(isl.hi);
        self.ever_lo = self.ever_lo.min(isl.lo);
        self.ever_hi = self.ever_hi.max(isl.hi);
    }

    /// Make the window the one island `isl` (a method that integrates one interval and needs it
    /// to hold a given region, see [`crate::integrators::multirate`]).
    pub(crate) fn reset_to(&mut self, isl: Island) {
        self.islands.clear();
        self.islands.push(isl);
        self.update_envelope();
        self.ever_lo = self.ever_lo.min(isl.lo);
        self.ever_hi = self.ever_hi.max(isl.hi);
    }

    /// After a sweep in which some island grew: merge islands that came closer than
    /// [`MIN_GAP`] (nothing to do with one island).
    #[inline(always)]
    pub(crate) fn after_growth(&mut self, grew: bool) {
        if grew && self.islands.len() > 1 {
            self.merge_close();
        }
    }

    /// Take every stretch of grains for which `rest(i)` holds out of the islands: stretches at
    /// an island's ends of any length, stretches inside an island of at least [`MIN_SPLIT`]
    /// grains.
    /// `on_rest` is called with every grain taken out. Returns the number of grains taken out.
    pub(crate) fn split_at_rest(
        &mut self,
        mut rest: impl FnMut(usize) -> bool,
        mut on_rest: impl FnMut(usize),
    ) -> usize {
        if !self.skip {
            return 0;
        }
        // The old islands go to the spare buffer (no allocation once both have grown).
        let mut old = std::mem::take(&mut self.spare);
        old.clear();
        old.extend_from_slice(&self.islands);
        self.islands.clear();
        let mut taken = 0;
        for isl in &old {
            let mut i = isl.lo;
            // Start of the current run of active grains.
            let mut start: Option<usize> = None;
            while i < isl.hi {
                if rest(i) {
                    let r0 = i;
                    while i < isl.hi && rest(i) {
                        i += 1;
                    }
                    let at_end = r0 == isl.lo || i == isl.hi;
                    if at_end || i - r0 >= MIN_SPLIT {
                        if let Some(s) = start.take() {
                            self.islands.push(Island { lo: s, hi: r0 });
                        }
                        for g in r0..i {
                            on_rest(g);
                        }
                        taken += i - r0;
                    } else if start.is_none() {
                        start = Some(r0);
                    }
                } else {
                    if start.is_none() {
                        start = Some(i);
                    }
                    i += 1;
                }
            }
            if let Some(s) = start {
                self.islands.push(Island { lo: s, hi: isl.hi });
            }
        }
        self.spare = old;
        self.update_envelope();
        taken
    }

    /// Drop every grain outside `[lo, hi)` from the integration, for good: the islands are cut
    /// to it and no grain outside it joins an island again (the limit only ever narrows).
    /// `on_drop` is called with every grain taken out of an island. Returns their number. The
    /// caller decides what a dropped grain is (the run sets its velocity to zero, so it stays
    /// where it is: a fixed wall for its neighbour inside).
    pub(crate) fn clip(&mut self, lo: usize, hi: usize, mut on_drop: impl FnMut(usize)) -> usize {
        self.limit_lo = self.limit_lo.max(lo);
        self.limit_hi = self.limit_hi.min(hi);
        let (lo, hi) = (self.limit_lo, self.limit_hi);
        let mut dropped = 0;
        for isl in &mut self.islands {
            let a = isl.lo.max(lo).min(isl.hi);
            let b = isl.hi.min(hi).max(a);
            for g in (isl.lo..a).chain(b..isl.hi) {
                on_drop(g);
                dropped += 1;
            }
            *isl = Island { lo: a, hi: b };
        }
        self.islands.retain(|i| !i.is_empty());
        self.update_envelope();
        dropped
    }

    /// The grains that may still be integrated, `[lo, hi)` (the whole chain and beyond when no
    /// horizon has cut it, see `Window::clip` and [`crate::Simulation::drop_outside`]).
    pub fn limit(&self) -> (usize, usize) {
        (self.limit_lo, self.limit_hi)
    }

    /// The islands.
    pub fn islands(&self) -> &[Island] {
        &self.islands
    }

    /// Number of integrated grains (the sum over islands).
    #[inline]
    pub fn len(&self) -> usize {
        match self.islands.as_slice() {
            [] => 0,
            [one] => one.len(),
            many => many.iter().map(Island::len).sum(),
        }
    }

    /// True when no grain is integrated (every grain at rest).
    pub fn is_empty(&self) -> bool {
        self.islands.is_empty()
    }

    /// The envelope of the islands.
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

#[cfg(test)]
mod tests {
    use super::*;

    fn win(islands: &[(usize, usize)]) -> Window {
        let mut w = Window::full(0);
        w.skip = true;
        for &(lo, hi) in islands {
            w.islands.push(Island { lo, hi });
        }
        w.update_envelope();
        w
    }

    fn pairs(w: &Window) -> Vec<(usize, usize)> {
        w.islands().iter().map(|i| (i.lo, i.hi)).collect()
    }

    #[test]
    fn clip_cuts_islands_and_narrows_the_limit_for_good() {
        let mut w = win(&[(0, 5), (10, 20), (30, 40)]);
        let mut dropped = vec![];
        let n = w.clip(12, 35, |g| dropped.push(g));
        assert_eq!(pairs(&w), vec![(12, 20), (30, 35)]);
        let expect: Vec<usize> = (0..5).chain(10..12).chain(35..40).collect();
        assert_eq!(dropped, expect);
        assert_eq!(n, expect.len());
        assert_eq!((w.lo, w.hi), (12, 35));
        // A wider clip later does not widen the limit.
        assert_eq!(w.clip(0, 100, |_| {}), 0);
        assert_eq!(w.limit(), (12, 35));
        // Everything outside: no islands left.
        w.clip(21, 29, |_| {});
        assert!(w.is_empty());
    }

    #[test]
    fn merge_keeps_min_gap() {
        let mut w = win(&[(0, 5), (7, 9), (12, 20), (30, 31)]);
        w.merge_close();
        // 5 -> 7 is a gap of 2 (< 3): merged; 9 -> 12 is 3: kept apart.
        assert_eq!(pairs(&w), vec![(0, 9), (12, 20), (30, 31)]);
        assert_eq!((w.lo, w.hi), (0, 31));
        assert_eq!(w.len(), 9 + 8 + 1);
    }

    #[test]
    fn split_takes_ends_and_long_interior_runs_only() {
        let m = MIN_SPLIT;
        let mut w = win(&[(0, 2 * m + 20)]);
        // At rest: 0..2 (end run), 5..7 (interior, shorter than MIN_SPLIT: stays), 10..10+m
        // (interior, MIN_SPLIT long: splits), the last 2 (end run).
        let end = 2 * m + 20;
        let rest =
            |i: usize| i < 2 || (5..7).contains(&i) || (10..10 + m).contains(&i) || i >= end - 2;
        let mut taken = vec![];
        let n = w.split_at_rest(rest, |g| taken.push(g));
        assert_eq!(pairs(&w), vec![(2, 10), (10 + m, end - 2)]);
        let expect: Vec<usize> = (0..2).chain(10..10 + m).chain(end - 2..end).collect();
        assert_eq!(taken, expect);
        assert_eq!(n, m + 4);
        // Everything at rest: no islands left, an empty envelope.
        let rest_len = w.len();
        let n = w.split_at_rest(|_| true, |_| {});
        assert_eq!(n, rest_len);
        assert!(w.is_empty() && w.range().is_empty());
    }
}
