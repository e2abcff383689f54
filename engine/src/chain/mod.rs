//! The chain: grains, their masses, the contacts between them and the ends.
//!
//! Grains are indexed `0..n` internally. Contact `k` (for `k in 0..=n`) joins grain `k - 1` and
//! grain `k`; contacts `0` and `n` are the left and right ends (a wall, or nothing for a free
//! end). Grain `i` feels `a_i = (f_i - f_{i+1}) / m_i`. Interior contacts `1..n` are grouped into
//! [`Segment`]s of equal law so the force loop dispatches once per segment.

mod active;
mod builder;
mod damping;
mod error;
mod fused;
pub mod law;
pub(crate) mod material;
mod window;

pub use builder::{ChainBuilder, End, InterfaceRule, Section, Striker, StrikerEnd};
pub(crate) use damping::DampWork;
pub use error::ChainError;
pub use law::{ContactDamping, ContactLaw, DampingModel, LawError};
pub use window::{Island, Window};

use law::Kernel;
use std::ops::RangeInclusive;

/// True when the AVX2 build of the hot loops can run here (checked once, cached by std).
#[inline]
pub(crate) fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// A run of consecutive interior contacts sharing one law (each contact's segment is
/// `Chain::contact_segment`), ending before contact `c1`.
#[derive(Clone, Debug)]
pub struct Segment {
    /// One past the last contact of the segment.
    pub c1: usize,
    /// The law shared by the segment's contacts.
    pub law: ContactLaw,
    pub(crate) kernel: Kernel,
}

/// The interior contacts as the fused sweeps (`chain::fused`) read them: runs of consecutive
/// contacts of one form of law (exponent kind, precompression, tension: what the compiled loop
/// depends on), and each contact's stiffness, precompression and cut, indexed by contact (the
/// ends' entries unused). Laws that differ only in their constants share a run.
#[derive(Clone, Debug, Default)]
pub(crate) struct Forms {
    /// `(c1, kernel)`: one past the run's last contact, and the kernel of its first contact
    /// (only its form is read).
    pub runs: Vec<(usize, Kernel)>,
    /// Contact index -> run index (interior contacts only).
    pub run_of: Vec<u32>,
    pub eta: Vec<f64>,
    pub delta0: Vec<f64>,
    pub cut: Vec<f64>,
}

impl Forms {
    /// The forms of the interior contacts `1..n` whose laws are `claw` (contact `k` is
    /// `claw[k - 1]`).
    pub(crate) fn of(claw: &[ContactLaw]) -> Forms {
        let same_form = |a: &Kernel, b: &Kernel| {
            a.power == b.power && a.precompressed == b.precompressed && a.tension == b.tension
        };
        let mut f = Forms {
            run_of: vec![0; claw.len() + 2],
            eta: vec![0.0; claw.len() + 2],
            delta0: vec![0.0; claw.len() + 2],
            cut: vec![0.0; claw.len() + 2],
            ..Forms::default()
        };
        for (j, law) in claw.iter().enumerate() {
            let (k, kern) = (j + 1, law.kernel());
            match f.runs.last_mut() {
                Some((c1, form)) if same_form(form, &kern) && *c1 == k => *c1 = k + 1,
                _ => f.runs.push((k + 1, kern)),
            }
            f.run_of[k] = (f.runs.len() - 1) as u32;
            (f.eta[k], f.delta0[k], f.cut[k]) = (kern.eta, kern.delta0, kern.cut);
        }
        f
    }
}

/// Where a section sits in the chain (internal grain indices).
#[derive(Clone, Debug, serde::Serialize)]
pub struct SectionSpan {
    /// The section's name (unique in the chain).
    pub name: String,
    /// Internal index of its first grain (0-based; a left striker is index 0, so the sections then
    /// start at 1).
    pub first: usize,
    /// Internal index of its last grain (inclusive).
    pub last: usize,
    /// Mass of each of its grains.
    pub mass: f64,
    /// Law of the contacts inside it (contacts at its edges follow the interface rule).
    pub law: ContactLaw,
    /// Viscous damping rate of its grains (0: none).
    pub damping: f64,
}

/// A built chain. Immutable during a run.
#[derive(Clone, Debug)]
pub struct Chain {
    pub(crate) mass: Vec<f64>,
    pub(crate) inv_mass: Vec<f64>,
    pub(crate) segments: Vec<Segment>,
    /// Contact index -> segment index (interior contacts only; walls use `left`/`right`).
    pub(crate) contact_segment: Vec<u32>,
    /// The interior contacts for the fused sweeps: runs of one form of law, each contact's
    /// constants.
    pub(crate) forms: Forms,
    pub(crate) left: Option<(ContactLaw, Kernel)>,
    pub(crate) right: Option<(ContactLaw, Kernel)>,
    /// Force of each contact `0..=n` with every grain at rest (u = 0).
    pub(crate) static_force: Vec<f64>,
    /// Grain number (as printed in files) of internal grain 0.
    pub(crate) number_offset: i64,
    pub(crate) sections: Vec<SectionSpan>,
    pub(crate) striker: Option<(usize, f64)>,
    /// Damped stretches of grains: `(first, end, rate)` (an absorbing layer; see [`Chain::damp`]).
    pub(crate) damped: Vec<(usize, usize, f64)>,
    /// Damped contacts in runs of equal damping (see `chain::damping`).
    pub(crate) damped_contacts: Vec<law::DampedRun>,
    /// The grains those contacts touch, as spans `first..end` that share no contact (see
    /// `chain::damping`).
    pub(crate) damped_grains: Vec<(usize, usize)>,
    /// The acceleration of gravity on every grain, positive towards the right end (0: none).
    pub(crate) gravity: f64,
}

impl Chain {
    /// Number of grains (including a striker).
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// Never true for a built chain; present for clippy.
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Mass of each grain, by internal index (a striker included).
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }

    /// Where each section sits, in chain order (a striker belongs to none).
    pub fn sections(&self) -> &[SectionSpan] {
        &self.sections
    }

    /// The section called `name`, if there is one (section names are unique in a built chain).
    pub fn section(&self, name: &str) -> Option<&SectionSpan> {
        self.sections.iter().find(|s| s.name == name)
    }

    /// The grains of section `name` (internal indices, inclusive); the error lists the known
    /// names.
    ///
    /// ```
    /// use grainchain_engine::{ChainBuilder, ContactLaw, Section};
    /// let law = ContactLaw::hertz(5657.0);
    /// let chain = ChainBuilder::new()
    ///     .section(Section::new("heavy", 10, 1.0, law))
    ///     .section(Section::new("light", 20, 0.1, law))
    ///     .build()?;
    /// assert_eq!(chain.grains_of("light")?, 10..=29);
    /// assert!(chain.grains_of("medium").unwrap_err().to_string().contains("heavy, light"));
    /// # Ok::<(), grainchain_engine::ChainError>(())
    /// ```
    pub fn grains_of(&self, name: &str) -> Result<RangeInclusive<usize>, ChainError> {
        self.grains_between(name, name)
    }

    /// The grains from the first of section `from` to the last of section `to` (internal
    /// indices, inclusive): a region spanning consecutive sections, e.g. a container from its
    /// left wall to its right wall.
    pub fn grains_between(
        &self,
        from: &str,
        to: &str,
    ) -> Result<RangeInclusive<usize>, ChainError> {
        let find = |name: &str| {
            self.section(name)
                .ok_or_else(|| ChainError::UnknownSection {
                    name: name.to_string(),
                    known: self
                        .sections
                        .iter()
                        .map(|s| s.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                })
        };
        let (a, b) = (find(from)?, find(to)?);
        if a.first > b.last {
            return Err(ChainError::SectionsReversed {
                from: from.to_string(),
                to: to.to_string(),
            });
        }
        Ok(a.first..=b.last)
    }

    /// The acceleration of gravity on every grain, positive towards the right end (0: none;
    /// [`ChainBuilder::gravity`]).
    pub fn gravity(&self) -> f64 {
        self.gravity
    }

    /// The potential energy of gravity, `-g sum m_i u_i` (relative to every grain at `u = 0`,
    /// the built static state), summed in grain order; 0 without gravity.
    pub fn gravity_energy(&self, u: &[f64]) -> f64 {
        if self.gravity == 0.0 {
            return 0.0;
        }
        let mut mu = 0.0;
        for (m, u) in self.mass.iter().zip(u) {
            mu += m * u;
        }
        -self.gravity * mu
    }

    /// The elastic energy of the static state, the sum over contacts of `V(delta0)` (0 without
    /// static overlaps): the scale of the rounding of [`Chain::contact_energy`], which subtracts
    /// it contact by contact.
    pub(crate) fn static_energy(&self) -> f64 {
        (0..=self.len())
            .filter_map(|k| self.contact_kernel(k))
            .filter(|k| k.precompressed)
            .map(|k| k.potential_at(k.delta0))
            .sum()
    }

    /// Internal index and velocity of the striker, if the chain was built with one.
    pub fn striker(&self) -> Option<(usize, f64)> {
        self.striker
    }

    /// The grain number printed in output files for internal index `i`: chain grains are
    /// numbered 1..=N from the left; a left striker is grain 0, a right striker N + 1.
    pub fn grain_number(&self, i: usize) -> i64 {
        i as i64 + self.number_offset
    }

    /// Internal index of a printed grain number, if it exists.
    pub fn index_of(&self, number: i64) -> Option<usize> {
        let i = number - self.number_offset;
        (i >= 0 && (i as usize) < self.len()).then_some(i as usize)
    }

    /// The law of contact `k` (`0..=n`), if there is a contact there.
    pub fn contact_law(&self, k: usize) -> Option<ContactLaw> {
        let n = self.len();
        if k == 0 {
            self.left.map(|l| l.0)
        } else if k == n {
            self.right.map(|l| l.0)
        } else if k < n {
            Some(self.segments[self.contact_segment[k] as usize].law)
        } else {
            None
        }
    }

    /// Total overlap of contact `k` for displacements `u` (None where there is no contact).
    pub fn overlap(&self, u: &[f64], k: usize) -> Option<f64> {
        let law = self.contact_law(k)?;
        Some(law.delta0 + compression(u, k))
    }

    /// The compiled kernel of contact `k` (`0..=n`), if there is a contact there.
    #[inline]
    pub(crate) fn contact_kernel(&self, k: usize) -> Option<&Kernel> {
        let n = self.len();
        if k == 0 {
            self.left.as_ref().map(|l| &l.1)
        } else if k == n {
            self.right.as_ref().map(|l| &l.1)
        } else if k < n {
            Some(&self.segments[self.contact_segment[k] as usize].kernel)
        } else {
            None
        }
    }

    /// Calls `each` with [`Chain::contact_energy`] of every contact `k0..=k1` (`k1 <= n`), in
    /// order, the same bits, one dispatch per segment of equal law.
    fn for_each_contact_energy(&self, u: &[f64], k0: usize, k1: usize, mut each: impl FnMut(f64)) {
        let n = self.len();
        let mut k = k0;
        if k > k1 {
            return;
        }
        if k == 0 {
            each(self.contact_energy(u, 0));
            k = 1;
        }
        let last_inner = k1.min(n.saturating_sub(1));
        while k <= last_inner && k < n {
            let seg = &self.segments[self.contact_segment[k] as usize];
            let stop = seg.c1.min(last_inner + 1);
            seg.kernel.for_each_potential(&u[k - 1..stop], &mut each);
            k = stop;
        }
        if k1 == n && n > 0 && k <= n {
            each(self.contact_energy(u, n));
        }
    }

    /// The sum of [`Chain::contact_energy`] over contacts `k0..=k1` (`k1 <= n`), added in
    /// order (the same bits as the plain loop), one dispatch per segment.
    pub fn potential_energy(&self, u: &[f64], k0: usize, k1: usize) -> f64 {
        let mut pe = 0.0;
        self.for_each_contact_energy(u, k0, k1, |e| pe += e);
        pe
    }

    /// [`Chain::contact_energy`] of contacts `k0..=k1` (`k1 <= n`) into `out` (cleared first), the
    /// same bits, one dispatch per segment.
    pub fn contact_energies(&self, u: &[f64], k0: usize, k1: usize, out: &mut Vec<f64>) {
        out.clear();
        self.for_each_contact_energy(u, k0, k1, |e| out.push(e));
    }

    /// Potential energy of contact `k` relative to its static value, for displacements `u`.
    pub fn contact_energy(&self, u: &[f64], k: usize) -> f64 {
        let Some(kern) = self.contact_kernel(k) else {
            return 0.0;
        };
        let x = kern.delta0 + compression(u, k);
        if kern.precompressed {
            kern.potential_at(x) - kern.potential_at(kern.delta0)
        } else {
            kern.potential_at(x)
        }
    }

    /// Compute contact forces `f[k]` for contacts `k0..=k1` (clamped to `0..=n`).
    #[inline(always)]
    pub(crate) fn contact_forces(&self, u: &[f64], f: &mut [f64], k0: usize, k1: usize) {
        let n = self.len();
        let mut k = k0;
        let k1 = k1.min(n);
        if k0 > k1 {
            return;
        }
        if k == 0 {
            f[0] = match &self.left {
                Some((_, kern)) => kern.force_at(kern.delta0 - u[0]),
                None => 0.0,
            };
            k = 1;
        }
        let end = k1.min(n - 1); // last interior contact to compute
        while k <= end && k < n {
            let seg = &self.segments[self.contact_segment[k] as usize];
            let stop = seg.c1.min(end + 1);
            // contacts k..stop use u[k-1..stop]
            seg.kernel.forces(&u[k - 1..stop], &mut f[k..stop]);
            k = stop;
        }
        if k1 == n {
            f[n] = match &self.right {
                Some((_, kern)) => kern.force_at(kern.delta0 + u[n - 1]),
                None => 0.0,
            };
        }
    }

    /// Damping factors `exp(-rate h)` of the damped stretches for a time `h`, in order.
    pub(crate) fn damping_factors(&self, h: f64) -> Vec<f64> {
        self.damped
            .iter()
            .map(|&(_, _, c)| (-c * h).exp())
            .collect()
    }

    /// [`Chain::damping_factors`] into `out`, which keeps its allocation.
    pub(crate) fn damping_factors_into(&self, h: f64, out: &mut Vec<f64>) {
        out.clear();
        out.extend(self.damped.iter().map(|&(_, _, c)| (-c * h).exp()));
    }

    /// Accelerations of grains `g0..g1` (forces of contacts `g0..=g1`).
    #[inline(always)]
    fn island_accelerations(&self, u: &[f64], f: &mut [f64], a: &mut [f64], g0: usize, g1: usize) {
        self.contact_forces(u, f, g0, g1);
        let fa = &f[g0..g1];
        let fb = &f[g0 + 1..g1 + 1];
        let im = &self.inv_mass[g0..g1];
        for (((ai, fa), fb), im) in a[g0..g1].iter_mut().zip(fa).zip(fb).zip(im) {
            *ai = (fa - fb) * im;
        }
    }

    /// Net force on grain `i` for displacements `u`, by the arithmetic of the force kernels.
    pub fn net_force(&self, u: &[f64], i: usize) -> f64 {
        self.contact_force_at(u, i) - self.contact_force_at(u, i + 1)
    }

    /// Index of the first grain whose net force is not zero with every grain at rest, and of the
    /// last (None if the chain is in static equilibrium everywhere).
    pub(crate) fn static_imbalance(&self) -> Option<(usize, usize)> {
        let n = self.len();
        let bad: Vec<usize> = (0..n)
            .filter(|&i| self.static_force[i] - self.static_force[i + 1] != 0.0)
            .collect();
        Some((*bad.first()?, *bad.last()?))
    }
}

/// How much displacements `u` close contact `k` (`0..=n` for `n = u.len()`): `u_(k-1) - u_k`,
/// the left wall's `-u_0`, the right wall's `u_(n-1)`; a contact's overlap is its `delta0` plus
/// this. The one place the ends are told apart (`Chain::overlap`, `Chain::contact_energy`, the
/// runs with derivatives).
#[inline(always)]
pub(crate) fn compression(u: &[f64], k: usize) -> f64 {
    let n = u.len();
    if k == 0 {
        -u[0]
    } else if k == n {
        u[n - 1]
    } else {
        u[k - 1] - u[k]
    }
}
