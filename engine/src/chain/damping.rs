//! Contact damping: the dashpot `c delta^q d(delta)/dt` in parallel with a contact
//! ([`super::law::ContactDamping`]), folded into the splitting methods' drifts.
//!
//! The dashpot's force is a time derivative: `c delta^q delta' = d/dt G(delta)` with
//! `G(delta) = c delta^(q+1) / (q + 1)`. Over any stretch of time the momentum it moves through a
//! closed contact is `G(delta_end) - G(delta_start)`, whatever happens between, and it depends on
//! the displacements only. So the splitting methods' drifts carry it (the damped drift,
//! [`Chain::damped_drift`]): the displacements move under the velocities and the dashpots
//! together, integrated by one explicit midpoint (second-order Runge-Kutta) step whose velocity
//! change is that exact difference of `G` at the step's ends; the kicks stay elastic. The
//! damping force `c delta^q delta'` is not smooth in time where a contact closes (a jump for
//! q = 0, `t^q` after it), and a flow in time at held displacements converged at order q + 1
//! there; `G` is a function of the displacements, continuous with its first derivative's jump
//! only for q = 0, so the damped drift keeps the method's order 2 (the restitution rows of
//! `work-precision`).
//!
//! The total contact force is never tensile: once a compression-only contact opens faster than
//! its elastic force can hold (`eta delta^p + c delta^q delta' < 0`, the clamp), the dashpot's
//! force is minus the elastic force (the grains separate with no force), and the drift's
//! impulse for that contact is minus the elastic force at the midpoint over the drift, taking
//! back what the kicks around it give. Whether a contact is clamped is read at the drift's
//! midpoint. The total force is continuous where the clamp engages, so a step that holds that
//! instant has an error of order 2, with a constant that depends on where in the step it falls;
//! with `integrator.events` the instant is a contact event (`integrators::events`) and no step
//! holds it. A two-sided (tension) contact's damping is `c d(delta)/dt`
//! at every overlap (`G = c delta`), unclipped: only the forms with q = 0 are defined there
//! (viscous, and scale-respecting on its linear law; `ContactLaw::validate` refuses
//! kuwabara-kono on it). The kinetic energy each grain loses in the damped drifts is counted,
//! per grain and in total: the energy budget's dissipated energy.
//!
//! A grain that no damped contact touches drifts by the midpoint step's arithmetic with exact
//! zero impulses, written as such (`u + tau (v + 0.0)`), and loses no energy: the midpoint step
//! runs on the spans of grains the damped contacts touch (`Chain::damped_spans`), so a chain
//! damped in a layer (the `dashpot` outer medium) pays for the layer, not for the chain.

use super::law::{contact_force, with_power, DampedRun, Power, QPower};
use super::Chain;
use crate::chain::Window;

/// A damped contact at one set of displacements: what the damped drift reads of it.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Terms {
    /// `G(delta) = c delta^(q+1) / (q + 1)` (`c delta` on a two-sided contact); zero where the
    /// contact is open or undamped.
    g: f64,
    /// The elastic force (zero open, and on a two-sided contact, which is never clamped).
    fe: f64,
    /// `c delta^q`, the dashpot's force per unit rate of compression (zero open or undamped).
    cq: f64,
}

impl Terms {
    /// Whether the total force at rate of compression `w` would be tensile, so the contact is
    /// clamped (the grains separate with no force).
    #[inline(always)]
    fn clamped(&self, w: f64) -> bool {
        self.fe > 0.0 && self.fe + self.cq * w < 0.0
    }
}

/// Scratch space of the damped drift: each contact's terms at the drift's start, midpoint and
/// end, the impulses, the midpoint displacements and velocities.
#[derive(Clone, Debug, Default)]
pub(crate) struct DampWork {
    t0: Vec<Terms>,
    tm: Vec<Terms>,
    t1: Vec<Terms>,
    impulse: Vec<f64>,
    um: Vec<f64>,
    vm: Vec<f64>,
    u1: Vec<f64>,
    /// Damping accelerations of the grains beside the islands (whether they join).
    acc: Vec<f64>,
    /// The islands whose contacts' terms `t1` holds at the displacements the last damped drift
    /// left (the kicks between two drifts do not move them): the next drift's start, not
    /// computed again. Emptied by [`DampWork::forget`].
    ended: Vec<(usize, usize)>,
}

impl DampWork {
    /// Forget the terms the last drift ended with (the displacements may have been set since:
    /// a new advance, a piece of a step cut at an event).
    pub(crate) fn forget(&mut self) {
        self.ended.clear();
    }
}

impl Chain {
    /// The damped contacts in runs of equal damping (empty: an elastic chain).
    pub(crate) fn damped_runs(&self) -> Vec<DampedRun> {
        let n = self.len();
        let mut runs: Vec<DampedRun> = Vec::new();
        for k in 0..=n {
            let Some(law) = self.contact_law(k) else {
                continue;
            };
            let Some(d) = law.damping.filter(|d| d.c > 0.0) else {
                continue;
            };
            let q = QPower::of(d.model.exponent(law.p));
            debug_assert!(
                !law.tension || q == QPower::Zero,
                "a two-sided contact's damping must have q = 0 (ContactLaw::validate)"
            );
            let kernel = law.kernel();
            match runs.last_mut() {
                // Walls (contacts 0 and n) are runs of their own.
                Some(r) if r.k1 == k && k != n && r.k0 != 0 && r.kernel == kernel && r.c == d.c => {
                    r.k1 = k + 1
                }
                _ => runs.push(DampedRun {
                    k0: k,
                    k1: k + 1,
                    c: d.c,
                    q,
                    kernel,
                }),
            }
        }
        runs
    }

    /// The grains the damped contacts touch, as spans of grains that share no contact: a
    /// run's contacts `k0..k1` join grains `k0 - 1..k1`; runs whose grains overlap merge.
    pub(crate) fn damped_spans(&self) -> Vec<(usize, usize)> {
        let n = self.len();
        let mut spans: Vec<(usize, usize)> = Vec::new();
        for run in &self.damped_contacts {
            let (a, b) = (run.k0.saturating_sub(1), run.k1.min(n));
            match spans.last_mut() {
                Some(last) if a < last.1 => last.1 = last.1.max(b),
                _ => spans.push((a, b)),
            }
        }
        spans
    }

    /// [`Chain::damped_spans`] within grains `lo..hi`.
    fn damped_spans_in(&self, lo: usize, hi: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.damped_grains
            .iter()
            .map(move |&(a, b)| (a.max(lo), b.min(hi)))
            .filter(|(a, b)| a < b)
    }

    /// Whether any contact is damped.
    pub fn has_contact_damping(&self) -> bool {
        !self.damped_contacts.is_empty()
    }

    /// The terms of contacts `k0..=k1` at displacements `u`, into `t[k]` (zeros where a contact
    /// is undamped or open): one dispatch per run on the forms of `delta^q` and `delta^p`, none
    /// per contact.
    fn damping_terms(&self, u: &[f64], t: &mut [Terms], k0: usize, k1: usize) {
        t[k0..=k1].fill(Terms::default());
        for run in &self.damped_contacts {
            let (a, b) = (run.k0.max(k0), run.k1.min(k1 + 1));
            if a >= b {
                continue;
            }
            let kern = run.kernel;
            match run.q {
                QPower::Zero => with_power!(kern, |pw, TENSION| {
                    self.run_terms::<_, TENSION>(run, pw, u, t, a..b, 0.0, |_| 1.0)
                }),
                QPower::Half => with_power!(kern, |pw, TENSION| {
                    self.run_terms::<_, TENSION>(run, pw, u, t, a..b, 0.5, f64::sqrt)
                }),
                QPower::Quarter => with_power!(kern, |pw, TENSION| {
                    self.run_terms::<_, TENSION>(run, pw, u, t, a..b, 0.25, |x| x.sqrt().sqrt())
                }),
                QPower::General(q) => with_power!(kern, |pw, TENSION| {
                    self.run_terms::<_, TENSION>(run, pw, u, t, a..b, q, |x| x.powf(q))
                }),
            }
        }
    }

    /// [`Chain::damping_terms`] of contacts `ks` of one run, compiled per form of `delta^p`
    /// (`pw`, `TENSION`) and of `delta^q` (`g`, the exponent `q`).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn run_terms<P: Power, const TENSION: bool>(
        &self,
        run: &DampedRun,
        pw: P,
        u: &[f64],
        t: &mut [Terms],
        ks: std::ops::Range<usize>,
        q: f64,
        g: impl Fn(f64) -> f64,
    ) {
        let n = self.len();
        let k = &run.kernel;
        let over = 1.0 / (q + 1.0);
        // Contact j joins grains j - 1 and j; a wall's other side is at rest.
        for j in ks {
            let ul = if j == 0 { 0.0 } else { u[j - 1] };
            let ur = if j == n { 0.0 } else { u[j] };
            let x = k.delta0 + ul - ur;
            t[j] = if TENSION {
                // A two-sided contact is never open and its total force may pull, so its
                // dashpot acts at every overlap and is not clipped. Its form has q = 0,
                // `c d(delta)/dt` (`damped_runs` asserts it): `G = c delta`.
                Terms {
                    g: run.c * x,
                    fe: 0.0,
                    cq: run.c,
                }
            } else if x <= k.cut {
                // Open: no power to evaluate (`contact_force` would give zero).
                Terms::default()
            } else {
                let fe = contact_force::<P, false, TENSION>(pw, k.eta, 0.0, k.cut, x);
                if fe == 0.0 {
                    Terms::default()
                } else {
                    let cq = run.c * g(x);
                    Terms {
                        g: cq * x * over,
                        fe,
                        cq,
                    }
                }
            };
        }
    }

    /// The dashpots' accelerations at `(u, v)` (a clamped contact's: minus its elastic force)
    /// added to `a` on the islands' grains: what the contact events' prediction adds to the
    /// elastic accelerations (`integrators::events`).
    // The loop reads contact `i` and `i + 1` beside grain `i`: an index reads plainest.
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn add_damping_accelerations(
        &self,
        u: &[f64],
        v: &[f64],
        a: &mut [f64],
        win: &Window,
        work: &mut DampWork,
    ) {
        let n = self.len();
        work.t0.resize(n + 1, Terms::default());
        work.impulse.resize(n + 1, 0.0);
        for isl in win.islands() {
            let (lo, hi) = (isl.lo, isl.hi);
            if lo >= hi {
                continue;
            }
            self.damping_terms(u, &mut work.t0, lo, hi);
            for k in lo..=hi {
                let t = work.t0[k];
                let vl = if k == 0 { 0.0 } else { v[k - 1] };
                let vr = if k == n { 0.0 } else { v[k] };
                let w = vl - vr;
                work.impulse[k] = if t.clamped(w) { -t.fe } else { t.cq * w };
            }
            for i in lo..hi {
                a[i] += (work.impulse[i] - work.impulse[i + 1]) * self.inv_mass[i];
            }
        }
    }

    /// The damped drift over a time `tau` on every island of `win`: the displacements and
    /// velocities under the dashpots alone (no elastic force), one explicit midpoint step whose
    /// velocity change is the exact `G(delta_end) - G(delta_start)` of each unclamped contact
    /// (module docs). A grain beside an island that a dashpot pushes over the drift joins it (as
    /// one whose elastic force is not zero does in a force evaluation): first as the plain
    /// drift predicts, then, if the drift's own path pushes one more, the drift is taken again
    /// with it, so that skipping grains at rest changes no bit. Adds the kinetic energy each
    /// grain lost to `dissipated[i]` and returns the total.
    // The loops read contact `i` and `i + 1` beside grain `i`: an index reads plainest.
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn damped_drift(
        &self,
        u: &mut [f64],
        v: &mut [f64],
        tau: f64,
        win: &mut Window,
        work: &mut DampWork,
        dissipated: &mut [f64],
    ) -> f64 {
        let n = self.len();
        for t in [&mut work.t0, &mut work.tm, &mut work.t1] {
            t.resize(n + 1, Terms::default());
        }
        work.impulse.resize(n + 1, 0.0);
        work.um.resize(n, 0.0);
        work.vm.resize(n, 0.0);
        work.u1.resize(n, 0.0);
        work.acc.resize(n, 0.0);
        let mut grew = false;
        for j in 0..win.islands().len() {
            let isl = win.islands()[j];
            let (g0, g1) = self.eval_range(win, isl);
            // The grains beside the island are at rest: only the island's edge contact can push
            // one, by the change of its `G` as the island's edge grain drifts.
            for (margin, k, edge, sign) in [(g0, isl.lo, isl.lo, -1.0), (g1, isl.hi, isl.hi, 1.0)] {
                let beside = if sign < 0.0 {
                    margin < isl.lo
                } else {
                    margin > isl.hi
                };
                if !beside || isl.lo >= isl.hi {
                    continue;
                }
                // The edge grain: `lo` on the left, `hi - 1` on the right.
                let e = if sign < 0.0 { edge } else { edge - 1 };
                let g = if sign < 0.0 { margin } else { margin - 1 };
                self.damping_terms(u, &mut work.tm, k, k);
                let before = work.tm[k].g;
                let held = u[e];
                u[e] += tau * v[e];
                self.damping_terms(u, &mut work.tm, k, k);
                u[e] = held;
                work.acc[g] = sign * (work.tm[k].g - before) / tau * self.inv_mass[g];
            }
            grew |= self.grow(win, j, &mut [], &work.acc, g0, g1, false);
        }
        win.after_growth(grew);
        // The drift of every island is computed first and committed once no island's edge
        // contact pushes a grain beside it. The prediction above used the plain drift; a grain
        // it missed joins here and the drift is computed again. A grain at rest that no dashpot
        // pushes moves by exact zeros, so these are the bits of a run that skips nothing.
        let mut ended = std::mem::take(&mut work.ended);
        loop {
            let mut missed = false;
            for j in 0..win.islands().len() {
                let isl = win.islands()[j];
                if isl.lo >= isl.hi {
                    continue;
                }
                let cached = ended.contains(&(isl.lo, isl.hi));
                self.island_drift(u, v, tau, (isl.lo, isl.hi), cached, work);
                if win.skip {
                    let (limit_lo, limit_hi) = win.limit();
                    let mut grown = isl;
                    if isl.lo > limit_lo && work.impulse[isl.lo] != 0.0 {
                        grown.lo = isl.lo - 1;
                    }
                    if isl.hi < n && isl.hi < limit_hi && work.impulse[isl.hi] != 0.0 {
                        grown.hi = isl.hi + 1;
                    }
                    if (grown.lo, grown.hi) != (isl.lo, isl.hi) {
                        win.set_island(j, grown);
                        missed = true;
                    }
                }
            }
            if !missed {
                break;
            }
            // `t1` now holds this pass's ends, not the last drift's: the next pass computes its
            // start afresh.
            ended.clear();
            win.after_growth(true);
        }
        // Every grain's new place and velocity, and the kinetic energy each grain lost, summed
        // in grain order over the grains a dashpot touched: every other grain's is an exact
        // zero (`v + 0.0` against `v`), whose sum would change no bit.
        let mut total = 0.0;
        for isl in win.islands() {
            let mut from = isl.lo;
            for (a, b) in self.damped_spans_in(isl.lo, isl.hi) {
                self.commit::<false>(u, v, work, dissipated, &mut total, (from, a));
                self.commit::<true>(u, v, work, dissipated, &mut total, (a, b));
                from = b;
            }
            self.commit::<false>(u, v, work, dissipated, &mut total, (from, isl.hi));
        }
        ended.clear();
        ended.extend(win.islands().iter().map(|isl| (isl.lo, isl.hi)));
        work.ended = ended;
        total
    }

    /// Grains `a..b` take the drift's places and velocities; with `LOST` (the grains a dashpot
    /// touched) the kinetic energy each lost is added to `dissipated[i]` and `total`.
    // The loop reads contact `i` and `i + 1` beside grain `i`: an index reads plainest.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn commit<const LOST: bool>(
        &self,
        u: &mut [f64],
        v: &mut [f64],
        work: &DampWork,
        dissipated: &mut [f64],
        total: &mut f64,
        (a, b): (usize, usize),
    ) {
        let im = &self.inv_mass;
        for i in a..b {
            u[i] = work.u1[i];
            let v0 = v[i];
            let v1 = v0 + (work.impulse[i] - work.impulse[i + 1]) * im[i];
            if LOST {
                let de = 0.5 * self.mass[i] * (v0 * v0 - v1 * v1);
                dissipated[i] += de;
                *total += de;
            }
            v[i] = v1;
        }
    }

    /// The damped drift of island `lo..hi` over `tau`, not committed: the displacements at its
    /// end into `work.u1`, each contact's impulse (`lo..=hi`) into `work.impulse`. `cached`:
    /// `work.t1` holds the contacts' terms at `u` (the last drift's end).
    ///
    /// A grain no damped contact touches drifts plainly, `u + tau (v + 0.0)`: the arithmetic
    /// of the midpoint step where every impulse is an exact zero (`v + 0.0` is the midpoint
    /// velocity, `-0.0` made `+0.0` as there), so a chain damped in a layer pays the midpoint
    /// step on the layer only ([`Chain::damped_span`]); an undamped contact's impulse stays the
    /// zero it always is.
    fn island_drift(
        &self,
        u: &[f64],
        v: &[f64],
        tau: f64,
        (lo, hi): (usize, usize),
        cached: bool,
        work: &mut DampWork,
    ) {
        let plain = |work: &mut DampWork, a: usize, b: usize| {
            for ((u1, u), v) in work.u1[a..b].iter_mut().zip(&u[a..b]).zip(&v[a..b]) {
                *u1 = u + tau * (v + 0.0);
            }
        };
        let mut from = lo;
        for span in self.damped_spans_in(lo, hi) {
            plain(work, from, span.0);
            self.damped_span(u, v, tau, span, (lo, hi), cached, work);
            from = span.1;
        }
        plain(work, from, hi);
    }

    /// The damped drift of grains `lo..hi`, a span of island `isl` that holds every grain its
    /// damped contacts touch ([`Chain::island_drift`]): the explicit midpoint step of the module
    /// docs on its contacts `lo..=hi`. A grain beside the span inside the island enters only
    /// an undamped contact, whose terms are zero whatever its place; one beside the island is
    /// held (at rest, or beyond the causal horizon).
    // The loops read contact `i` and `i + 1` beside grain `i`: an index reads plainest.
    #[allow(clippy::needless_range_loop, clippy::too_many_arguments)]
    fn damped_span(
        &self,
        u: &[f64],
        v: &[f64],
        tau: f64,
        (lo, hi): (usize, usize),
        isl: (usize, usize),
        cached: bool,
        work: &mut DampWork,
    ) {
        let n = self.len();
        let im = &self.inv_mass;
        let rate = |v: &[f64], k: usize| {
            let vl = if k == 0 { 0.0 } else { v[k - 1] };
            let vr = if k == n { 0.0 } else { v[k] };
            vl - vr
        };
        // Contacts lo..=hi act on the span's grains; a grain beside the island keeps its place
        // and velocity (at rest, or beyond the causal horizon: held).
        let beside = [
            (lo == isl.0 && lo > 0).then(|| lo - 1),
            (hi == isl.1 && hi < n).then_some(hi),
        ];
        let held = |to: &mut [f64], from: &[f64]| {
            for i in beside.into_iter().flatten() {
                to[i] = from[i];
            }
        };
        if cached {
            work.t0[lo..=hi].copy_from_slice(&work.t1[lo..=hi]);
        } else {
            self.damping_terms(u, &mut work.t0, lo, hi);
        }
        // To the midpoint: the displacements at the start's velocities, the velocities by
        // the dashpots' impulses over the first half.
        held(&mut work.um, u);
        for i in lo..hi {
            work.um[i] = u[i] + 0.5 * tau * v[i];
        }
        self.damping_terms(&work.um, &mut work.tm, lo, hi);
        for k in lo..=hi {
            let t0 = work.t0[k];
            work.impulse[k] = if t0.clamped(rate(v, k)) {
                -0.5 * tau * t0.fe
            } else {
                work.tm[k].g - t0.g
            };
        }
        held(&mut work.vm, v);
        for i in lo..hi {
            work.vm[i] = v[i] + (work.impulse[i] - work.impulse[i + 1]) * im[i];
        }
        // The whole drift at the midpoint's velocities; each unclamped contact's impulse is
        // the exact difference of its `G`, a clamped one's minus its elastic force at the
        // midpoint.
        held(&mut work.u1, u);
        for i in lo..hi {
            work.u1[i] = u[i] + tau * work.vm[i];
        }
        self.damping_terms(&work.u1, &mut work.t1, lo, hi);
        for k in lo..=hi {
            let (t0, tm) = (work.t0[k], work.tm[k]);
            work.impulse[k] = if tm.clamped(rate(&work.vm, k)) {
                -tau * tm.fe
            } else if tm.fe == 0.0 && t0.clamped(rate(v, k)) {
                // Clamped at the start and open by the midpoint: no force all along (the
                // kicks around gave at most `eta delta^p` over the bit it was closed, a
                // delta of order tau). `G1 - G0` would pull: `-G0`, of order tau^(q+1).
                0.0
            } else {
                work.t1[k].g - t0.g
            };
        }
    }
}
