//! The fused stepping pass of the splitting methods (Verlet, Blanes-Moan): drift, contact force,
//! acceleration and kick in one sweep over the window.
//!
//! For grain `i` in order: `u_i += cd v_i`; then the force of contact `i` (grains `i-1`, `i`, both
//! drifted) is known, and with it the acceleration of grain `i-1`, which is kicked:
//! `v_{i-1} += ck a_{i-1}`. Each grain sees exactly the arithmetic of the unfused sequence (drift
//! everything, compute every force, kick everything), so the result does not depend on how the
//! sweep is split. The AVX2 path carries the previous vectors of `u`, `F` and `v` in registers and
//! shifts them by one lane, so a 4-grain step touches memory only for `u`, `v`, `1/m` (and `a`
//! when asked); it computes the same IEEE operations per element as the scalar path.

use super::law::{contact_force, with_power, Kernel, Power};
use super::{Chain, Window};

/// Each interior contact's constants, indexed by contact: the sweeps of a run of one form of
/// law (exponent kind, precompression, tension) read them per contact, so a column whose
/// contacts differ only in their stiffness (beads of other diameters or materials) is one run,
/// swept four contacts at a time, instead of a run per contact.
#[derive(Clone, Copy)]
pub(crate) struct Laws<'a> {
    pub eta: &'a [f64],
    pub delta0: &'a [f64],
    pub cut: &'a [f64],
}

/// Scalar sweep over contacts `i0..i1` of one form of law. Returns the force of contact `i1 - 1`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn sweep_scalar<P: Power, const PRE: bool, const TENSION: bool>(
    pw: P,
    k: Laws<'_>,
    u: &mut [f64],
    v: &mut [f64],
    a: &mut [f64],
    im: &[f64],
    cd: f64,
    ck: f64,
    i0: usize,
    i1: usize,
    mut f_left: f64,
    store_a: bool,
) -> f64 {
    for i in i0..i1 {
        u[i] += cd * v[i];
        let f =
            contact_force::<P, PRE, TENSION>(pw, k.eta[i], k.delta0[i], k.cut[i], u[i - 1] - u[i]);
        let acc = (f_left - f) * im[i - 1];
        v[i - 1] += ck * acc;
        if store_a {
            a[i - 1] = acc;
        }
        f_left = f;
    }
    f_left
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use crate::chain::law::{General, Hertz, Linear, Quadratic};
    use std::arch::x86_64::*;

    /// `x^p` on four lanes, the same IEEE operations as [`Power::pow`]: the one thing an
    /// exponent kind declares outside `chain::law` (every kind of `with_power!` needs it).
    pub(super) trait PowerX4: Power {
        unsafe fn pow4(self, x: __m256d) -> __m256d;
    }
    impl PowerX4 for Linear {
        #[inline(always)]
        unsafe fn pow4(self, x: __m256d) -> __m256d {
            x
        }
    }
    impl PowerX4 for Hertz {
        #[inline(always)]
        unsafe fn pow4(self, x: __m256d) -> __m256d {
            _mm256_mul_pd(x, _mm256_sqrt_pd(x))
        }
    }
    impl PowerX4 for Quadratic {
        #[inline(always)]
        unsafe fn pow4(self, x: __m256d) -> __m256d {
            _mm256_mul_pd(x, x)
        }
    }
    impl PowerX4 for General {
        #[inline(always)]
        unsafe fn pow4(self, x: __m256d) -> __m256d {
            let mut l = [0.0; 4];
            _mm256_storeu_pd(l.as_mut_ptr(), x);
            for z in &mut l {
                *z = z.powf(self.0);
            }
            _mm256_loadu_pd(l.as_ptr())
        }
    }

    /// `[prev[3], cur[0], cur[1], cur[2]]`: the vector shifted right by one lane.
    #[inline(always)]
    unsafe fn shift(prev: __m256d, cur: __m256d) -> __m256d {
        let t = _mm256_permute2f128_pd::<0x21>(prev, cur); // [prev2, prev3, cur0, cur1]
        _mm256_shuffle_pd::<0b0101>(t, cur) // [prev3, cur0, cur1, cur2]
    }

    /// The AVX2 sweep; same contract and same per-element arithmetic as `sweep_scalar`.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn sweep<P: PowerX4, const PRE: bool, const TENSION: bool>(
        pw: P,
        k: Laws<'_>,
        u: &mut [f64],
        v: &mut [f64],
        a: &mut [f64],
        im: &[f64],
        cd: f64,
        ck: f64,
        i0: usize,
        i1: usize,
        f_left: f64,
        store_a: bool,
    ) -> f64 {
        assert!(i0 >= 1 && i1 <= u.len() && i1 <= v.len() && i1 <= im.len() && i1 <= a.len());
        assert!(i1 <= k.eta.len() && i1 <= k.delta0.len() && i1 <= k.cut.len());
        let chunks = (i1 - i0) / 4;
        let (up, vp, ap, mp) = (u.as_mut_ptr(), v.as_mut_ptr(), a.as_mut_ptr(), im.as_ptr());
        let cdv = _mm256_set1_pd(cd);
        let ckv = _mm256_set1_pd(ck);
        let (etap, d0p, cutp) = (k.eta.as_ptr(), k.delta0.as_ptr(), k.cut.as_ptr());
        let sign = _mm256_set1_pd(-0.0);
        let mut fc = _mm256_set1_pd(f_left);
        // The drifted u of the previous chunk, stored one chunk late so that this chunk can still
        // read the old u[i-1] and redo its drift in the shifted lane (the same two operations),
        // instead of shuffling: loads are cheap, shuffles all queue on one port.
        let mut pending: Option<(usize, __m256d)> = None;
        let mut i = i0;
        // Grain i0 - 1 is already drifted: the shifted lane of the first chunk must not drift it
        // again, so the first chunk starts from its stored value with no drift (cd = 0 lane).
        let first_shift_cd = _mm256_set_pd(cd, cd, cd, 0.0);
        for c in 0..chunks {
            // SAFETY: i - 1 >= 0 and i + 4 <= i1 <= every slice length (asserted above).
            let vv = _mm256_loadu_pd(vp.add(i));
            let vs = _mm256_loadu_pd(vp.add(i - 1));
            let us_old = _mm256_loadu_pd(up.add(i - 1));
            let uu = _mm256_add_pd(_mm256_loadu_pd(up.add(i)), _mm256_mul_pd(cdv, vv));
            let cds = if c == 0 { first_shift_cd } else { cdv };
            let us = _mm256_add_pd(us_old, _mm256_mul_pd(cds, vs));
            if let Some((j, prev)) = pending {
                _mm256_storeu_pd(up.add(j), prev);
            }
            pending = Some((i, uu));
            let mut x = _mm256_sub_pd(us, uu);
            if PRE {
                x = _mm256_add_pd(_mm256_loadu_pd(d0p.add(i)), x);
            }
            let cut = _mm256_loadu_pd(cutp.add(i));
            let eta = _mm256_loadu_pd(etap.add(i));
            let open = if TENSION {
                _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_andnot_pd(sign, x), cut)
            } else {
                _mm256_cmp_pd::<_CMP_GT_OQ>(x, cut)
            };
            let f = _mm256_mul_pd(eta, pw.pow4(_mm256_and_pd(open, x)));
            let acc = _mm256_mul_pd(
                _mm256_sub_pd(shift(fc, f), f),
                _mm256_loadu_pd(mp.add(i - 1)),
            );
            let vk = _mm256_add_pd(vs, _mm256_mul_pd(ckv, acc));
            _mm256_storeu_pd(vp.add(i - 1), vk);
            if store_a {
                _mm256_storeu_pd(ap.add(i - 1), acc);
            }
            fc = f;
            i += 4;
        }
        if let Some((j, prev)) = pending {
            _mm256_storeu_pd(up.add(j), prev);
        }
        let mut l = [0.0; 4];
        _mm256_storeu_pd(l.as_mut_ptr(), fc);
        let f_left = if chunks > 0 { l[3] } else { f_left };
        sweep_scalar::<P, PRE, TENSION>(pw, k, u, v, a, im, cd, ck, i, i1, f_left, store_a)
    }
}

/// One sweep of contacts `i0..i1` (all of the form of law `form`, their constants in `laws`),
/// picking the compiled variant.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn sweep(
    form: &Kernel,
    laws: Laws<'_>,
    simd: bool,
    u: &mut [f64],
    v: &mut [f64],
    a: &mut [f64],
    im: &[f64],
    cd: f64,
    ck: f64,
    i0: usize,
    i1: usize,
    f_left: f64,
    store_a: bool,
) -> f64 {
    macro_rules! go {
        ($pw:expr, $pre:tt, $t:tt) => {{
            #[cfg(target_arch = "x86_64")]
            if simd {
                // SAFETY: `simd` is true only when the CPU has AVX2.
                return unsafe {
                    avx2::sweep::<_, $pre, $t>(
                        $pw, laws, u, v, a, im, cd, ck, i0, i1, f_left, store_a,
                    )
                };
            }
            let _ = simd;
            sweep_scalar::<_, $pre, $t>($pw, laws, u, v, a, im, cd, ck, i0, i1, f_left, store_a)
        }};
    }
    with_power!(form, |pw, TENSION| if form.precompressed {
        go!(pw, true, TENSION)
    } else {
        go!(pw, false, TENSION)
    })
}

impl Chain {
    /// Force of contact `k` (0..=n) for the current `u`, by the same arithmetic as the sweeps.
    #[inline]
    pub(crate) fn contact_force_at(&self, u: &[f64], k: usize) -> f64 {
        let n = self.len();
        if k == 0 {
            match &self.left {
                Some((_, kern)) => kern.force_at(kern.delta0 - u[0]),
                None => 0.0,
            }
        } else if k == n {
            match &self.right {
                Some((_, kern)) => kern.force_at(kern.delta0 + u[n - 1]),
                None => 0.0,
            }
        } else {
            let kern = &self.segments[self.contact_segment[k] as usize].kernel;
            let mut f = [0.0];
            kern.forces(&u[k - 1..k + 1], &mut f);
            f[0]
        }
    }

    /// One fused pass: `u += cd v`, forces, `a`, `v += ck a` over every island of the window and
    /// its margins (a margin grain gets `v += ck * 0` and stays at rest unless it joins). `a` is
    /// written for every grain when `store_a`, and always for the edge grains of each island (the
    /// window test needs them). Islands are at least `MIN_GAP` apart, so the sweeps of two
    /// islands never write the same grain or compute the same contact, and sweeping them one after
    /// another is the arithmetic of one sweep over the envelope.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn drift_forces_kick(
        &self,
        u: &mut [f64],
        v: &mut [f64],
        a: &mut [f64],
        cd: f64,
        ck: f64,
        store_a: bool,
        win: &mut Window,
    ) {
        let mut grew = false;
        for j in 0..win.islands().len() {
            let (g0, g1) = self.eval_range(win, win.islands()[j]);
            self.sweep_range(u, v, a, cd, ck, store_a, g0, g1);
            grew |= self.grow(win, j, v, a, g0, g1, true);
        }
        win.after_growth(grew);
    }

    /// The fused pass over grains `g0..g1` taken as a chain of their own: their two end
    /// contacts (`g0` and `g1`) carry no force. The multirate method's fast region, whose end
    /// contacts are slow forces ([`crate::integrators::multirate`]). The same arithmetic per
    /// grain as drift all, forces of the contacts inside, accelerations, kick all.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn drift_forces_kick_free(
        &self,
        u: &mut [f64],
        v: &mut [f64],
        a: &mut [f64],
        cd: f64,
        ck: f64,
        store_a: bool,
        g0: usize,
        g1: usize,
    ) {
        if g0 >= g1 {
            return;
        }
        u[g0] += cd * v[g0];
        let f_left = self.sweep_segments(u, v, a, cd, ck, store_a, g0 + 1, g1, 0.0);
        let im = &self.inv_mass[..];
        let acc = (f_left - 0.0) * im[g1 - 1];
        v[g1 - 1] += ck * acc;
        if store_a {
            a[g1 - 1] = acc;
        }
    }

    /// Each interior contact's constants, for the sweeps.
    #[inline(always)]
    fn laws(&self) -> Laws<'_> {
        Laws {
            eta: &self.forms.eta,
            delta0: &self.forms.delta0,
            cut: &self.forms.cut,
        }
    }

    /// The fused pass over contacts `i0..i1` (drift of grain `i`, force of contact `i`, kick of
    /// grain `i - 1`), run by run of one form of law; `f_left` is the force of contact
    /// `i0 - 1`. Returns the force of contact `i1 - 1`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn sweep_segments(
        &self,
        u: &mut [f64],
        v: &mut [f64],
        a: &mut [f64],
        cd: f64,
        ck: f64,
        store_a: bool,
        i0: usize,
        i1: usize,
        mut f_left: f64,
    ) -> f64 {
        let simd = super::simd_available();
        let im = &self.inv_mass[..];
        let mut i = i0;
        while i < i1 {
            let (c1, form) = &self.forms.runs[self.forms.run_of[i] as usize];
            let end = (*c1).min(i1);
            f_left = sweep(
                form,
                self.laws(),
                simd,
                u,
                v,
                a,
                im,
                cd,
                ck,
                i,
                end,
                f_left,
                store_a,
            );
            i = end;
        }
        f_left
    }

    /// The fused pass over grains `g0..g1`: contacts `g0..=g1`, kicks of grains `g0..g1`; the
    /// accelerations of the first and last grain are always stored (the window test needs
    /// them), the others when `store_a`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn sweep_range(
        &self,
        u: &mut [f64],
        v: &mut [f64],
        a: &mut [f64],
        cd: f64,
        ck: f64,
        store_a: bool,
        g0: usize,
        g1: usize,
    ) {
        if g0 >= g1 {
            return;
        }
        let im = &self.inv_mass[..];
        u[g0] += cd * v[g0];
        let mut f_left = self.contact_force_at(u, g0);
        let mut i = g0 + 1;
        // The first grain's acceleration is always stored (window test).
        if i < g1 {
            let form = &self.forms.runs[self.forms.run_of[i] as usize].1;
            f_left = sweep(
                form,
                self.laws(),
                false,
                u,
                v,
                a,
                im,
                cd,
                ck,
                i,
                i + 1,
                f_left,
                true,
            );
            i += 1;
        }
        f_left = self.sweep_segments(u, v, a, cd, ck, store_a, i, g1, f_left);
        let f_right = self.contact_force_at(u, g1);
        let acc = (f_left - f_right) * im[g1 - 1];
        v[g1 - 1] += ck * acc;
        a[g1 - 1] = acc;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::ContactLaw;

    /// The AVX2 sweep and the scalar sweep give the same bits for every law variant, over ranges
    /// of every length mod 4 (so the vector body and the scalar tail are both exercised).
    #[test]
    fn simd_sweep_equals_scalar_sweep_bit_for_bit() {
        if !crate::chain::simd_available() {
            return; // nothing to compare on this CPU; the scalar path is the only one that runs
        }
        let laws = [
            ContactLaw::new(1.0, 3.0),
            ContactLaw::linear_spring(3.0),
            ContactLaw::linear_spring(3.0).with_precompression(0.01),
            ContactLaw::hertz(5657.0),
            ContactLaw::hertz(5657.0).with_precompression(0.02),
            ContactLaw::new(2.0, 7.0),
            ContactLaw::new(2.5, 7.0),
        ];
        let n = 64;
        // A deterministic, irregular state with open and closed contacts.
        let u0: Vec<f64> = (0..n)
            .map(|i| 0.05 * ((i * 7919 % 61) as f64 / 61.0 - 0.5))
            .collect();
        let v0: Vec<f64> = (0..n)
            .map(|i| (i * 104729 % 53) as f64 / 53.0 - 0.5)
            .collect();
        let im: Vec<f64> = (0..n).map(|i| 1.0 / (1.0 + (i % 5) as f64)).collect();
        for law in laws {
            let k = law.kernel();
            // Each contact its own stiffness (the law's times 1 to 2), as in a column of beads
            // of several sizes: the lanes read theirs.
            let eta: Vec<f64> = (0..n)
                .map(|i| k.eta * (1.0 + (i * 37 % 17) as f64 / 17.0))
                .collect();
            let (delta0, cut) = (vec![k.delta0; n], vec![k.cut; n]);
            let laws = Laws {
                eta: &eta,
                delta0: &delta0,
                cut: &cut,
            };
            for len in 1..12 {
                let (i0, i1) = (3, 3 + len);
                let run = |simd: bool| {
                    let (mut u, mut v, mut a) = (u0.clone(), v0.clone(), vec![0.0; n]);
                    let f = sweep(
                        &k, laws, simd, &mut u, &mut v, &mut a, &im, 1e-3, 2e-3, i0, i1, 0.7, true,
                    );
                    (u, v, a, f)
                };
                let (s, x) = (run(false), run(true));
                let bits = |w: &[f64]| w.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&s.0), bits(&x.0), "{law:?} len {len}: u");
                assert_eq!(bits(&s.1), bits(&x.1), "{law:?} len {len}: v");
                assert_eq!(bits(&s.2), bits(&x.2), "{law:?} len {len}: a");
                assert_eq!(s.3.to_bits(), x.3.to_bits(), "{law:?} len {len}: f");
            }
        }
    }
}
