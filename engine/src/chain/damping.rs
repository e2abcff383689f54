//! Contact damping: the dashpot `c delta^q d(delta)/dt` in parallel with a contact
//! ([`super::law::ContactDamping`]), as a flow of its own in the splitting methods.
//!
//! With the displacements held, the damping force depends only on the velocities, so the
//! splitting methods compose it with their elastic step symmetrically (Strang: half a damping
//! step, the elastic step, half a damping step; second order overall). The damping flow over a
//! time `tau` is one explicit midpoint (second-order Runge-Kutta) step. The total contact force is
//! never tensile: while a compression-only contact opens faster than its elastic force can hold,
//! the damping force is clipped at minus the elastic force (the grains separate with no force). A
//! two-sided (tension) contact's damping is `c d(delta)/dt` at every overlap, unclipped: only the
//! forms with q = 0 are defined there (viscous, and scale-respecting on its linear law;
//! `ContactLaw::validate` refuses kuwabara-kono on it). The
//! kinetic energy each grain loses to the flow is counted, per grain and in total: the energy
//! budget's dissipated energy.

use super::law::{contact_force, with_power, DampedRun, Power, QPower};
use super::Chain;
use crate::chain::Window;

/// Scratch space of the damping flow: contact damping forces and midpoint velocities.
#[derive(Clone, Debug, Default)]
pub(crate) struct DampWork {
    fd: Vec<f64>,
    vmid: Vec<f64>,
    /// Damping accelerations of the grains beside the islands (whether they join).
    acc: Vec<f64>,
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

    /// Whether any contact is damped.
    pub fn has_contact_damping(&self) -> bool {
        !self.damped_contacts.is_empty()
    }

    /// Damping forces of contacts `k0..=k1` for displacements `u` and velocities `v`, into
    /// `fd[k]` (zero where a contact is undamped or open): one dispatch per run on the forms of
    /// `delta^q` and `delta^p`, none per contact.
    fn damping_forces(&self, u: &[f64], v: &[f64], fd: &mut [f64], k0: usize, k1: usize) {
        fd[k0..=k1].fill(0.0);
        for run in &self.damped_contacts {
            let (a, b) = (run.k0.max(k0), run.k1.min(k1 + 1));
            if a >= b {
                continue;
            }
            let kern = run.kernel;
            match run.q {
                QPower::Zero => with_power!(kern, |pw, TENSION| {
                    self.run_forces::<_, TENSION>(run, pw, u, v, fd, a..b, |_| 1.0)
                }),
                QPower::Half => with_power!(kern, |pw, TENSION| {
                    self.run_forces::<_, TENSION>(run, pw, u, v, fd, a..b, f64::sqrt)
                }),
                QPower::Quarter => with_power!(kern, |pw, TENSION| {
                    self.run_forces::<_, TENSION>(run, pw, u, v, fd, a..b, |x| x.sqrt().sqrt())
                }),
                QPower::General(q) => with_power!(kern, |pw, TENSION| {
                    self.run_forces::<_, TENSION>(run, pw, u, v, fd, a..b, |x| x.powf(q))
                }),
            }
        }
    }

    /// [`Chain::damping_forces`] of contacts `ks` of one run, compiled per form of `delta^p`
    /// (`pw`, `TENSION`) and of `delta^q` (`g`).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn run_forces<P: Power, const TENSION: bool>(
        &self,
        run: &DampedRun,
        pw: P,
        u: &[f64],
        v: &[f64],
        fd: &mut [f64],
        ks: std::ops::Range<usize>,
        g: impl Fn(f64) -> f64,
    ) {
        let n = self.len();
        let k = &run.kernel;
        let force = |x: f64, rate: f64| {
            // A two-sided contact is never open and its total force may pull, so its dashpot
            // acts at every overlap and is not clipped. Its form has q = 0, `c d(delta)/dt`:
            // `ContactLaw::validate` refuses a q != 0 on a tension contact (kuwabara-kono's
            // delta^(1/2) has no value at the negative overlaps it reaches), and
            // scale-respecting's q = (p - 1)/2 is 0 on its linear law (`damped_runs` asserts it).
            if TENSION {
                return run.c * rate;
            }
            let fe = contact_force::<P, false, TENSION>(pw, k.eta, 0.0, k.cut, x);
            if fe == 0.0 {
                0.0
            } else {
                (run.c * g(x) * rate).max(-fe)
            }
        };
        // Contact j joins grains j - 1 and j; a wall's other side is at rest.
        for j in ks {
            let (ul, vl) = if j == 0 {
                (0.0, 0.0)
            } else {
                (u[j - 1], v[j - 1])
            };
            let (ur, vr) = if j == n { (0.0, 0.0) } else { (u[j], v[j]) };
            fd[j] = force(k.delta0 + ul - ur, vl - vr);
        }
    }

    /// The damping flow over a time `tau` (displacements held) on every island of `win`: one
    /// explicit midpoint step. A grain beside an island that the damping force would move joins
    /// it first (as one whose elastic force is not zero does in a force evaluation). Adds the
    /// kinetic energy each grain lost to `dissipated[i]` and returns the total.
    // The loops read contact `i` and `i + 1` beside grain `i`: an index reads plainest.
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn contact_damping_flow(
        &self,
        u: &[f64],
        v: &mut [f64],
        tau: f64,
        win: &mut Window,
        work: &mut DampWork,
        dissipated: &mut [f64],
    ) -> f64 {
        let n = self.len();
        work.fd.resize(n + 1, 0.0);
        work.vmid.resize(n, 0.0);
        work.acc.resize(n, 0.0);
        let mut grew = false;
        for j in 0..win.islands().len() {
            let (g0, g1) = self.eval_range(win, win.islands()[j]);
            let isl = win.islands()[j];
            // Only the island's two edge contacts can push a grain beside it.
            self.damping_forces(u, v, &mut work.fd, isl.lo, isl.lo);
            self.damping_forces(u, v, &mut work.fd, isl.hi, isl.hi);
            // The grains beside the island are at rest, as are their other neighbours: only the
            // contact with the island pushes them.
            if g0 < isl.lo {
                work.acc[g0] = -work.fd[isl.lo] * self.inv_mass[g0];
            }
            if g1 > isl.hi {
                work.acc[isl.hi] = work.fd[isl.hi] * self.inv_mass[isl.hi];
            }
            grew |= self.grow(win, j, &mut [], &work.acc, g0, g1, false);
        }
        win.after_growth(grew);
        let mut total = 0.0;
        for isl in win.islands() {
            let (lo, hi) = (isl.lo, isl.hi);
            if lo >= hi {
                continue;
            }
            // Contacts lo..=hi act on the island's grains; grains outside it keep their
            // velocities (at rest, or beyond the causal horizon: held).
            self.damping_forces(u, v, &mut work.fd, lo, hi);
            // The grains beside the island keep their velocities in the midpoint stage.
            let (a, b) = (lo.saturating_sub(1), (hi + 1).min(n));
            work.vmid[a..b].copy_from_slice(&v[a..b]);
            for i in lo..hi {
                work.vmid[i] = v[i] + 0.5 * tau * (work.fd[i] - work.fd[i + 1]) * self.inv_mass[i];
            }
            self.damping_forces(u, &work.vmid, &mut work.fd, lo, hi);
            for i in lo..hi {
                let v0 = v[i];
                let v1 = v0 + tau * (work.fd[i] - work.fd[i + 1]) * self.inv_mass[i];
                let de = 0.5 * self.mass[i] * (v0 * v0 - v1 * v1);
                dissipated[i] += de;
                total += de;
                v[i] = v1;
            }
        }
        total
    }
}
