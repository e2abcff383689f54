//! Would a kernel that steps several designs in SIMD lanes pay on this CPU? A probe, not the
//! engine: velocity Verlet's fused sweep on 41-grain Hertz chains against a wall (64 designs
//! with random constants, 20,000 steps), one design at a time in scalar code as the engine's
//! sweep takes it, against 4 designs per AVX2 vector and 8 per AVX-512 vector (intrinsics,
//! branch-free). Prints nanoseconds per design-grain-step, five rounds. With `--ftz`, subnormal
//! numbers are flushed to zero (the probe has no window, so a wave's precursor underflows in
//! it; the engine's runs do not, and are as fast with the flag as without).
//! Run: `cargo run --release --example lanes_probe [-- --ftz]` (x86-64 only).

#[cfg(target_arch = "x86_64")]
mod probe {
    use std::arch::x86_64::*;
    use std::time::Instant;

    /// Grains per chain (a striker and 40 beads).
    const N: usize = 41;
    const DESIGNS: usize = 64;
    const STEPS: usize = 20_000;
    const H: f64 = 2e-3;

    /// One chain: Hertz constants of its contacts (contact `i + 1` right of grain `i`, the last
    /// one the wall's) and inverse masses.
    struct Chain {
        eta: [f64; N + 1],
        inv_m: [f64; N],
    }

    #[target_feature(enable = "avx2")]
    fn scalar(c: &Chain) -> f64 {
        let (mut u, mut v, mut a) = ([0.0; N], [0.0; N], [0.0; N]);
        v[0] = 1.0;
        let hh = 0.5 * H;
        for _ in 0..STEPS {
            for i in 0..N {
                v[i] += hh * a[i];
                u[i] += H * v[i];
            }
            let mut left = 0.0;
            for i in 0..N {
                let d = if i + 1 < N { u[i] - u[i + 1] } else { u[i] };
                let right = if d > 0.0 {
                    c.eta[i + 1] * d * d.sqrt()
                } else {
                    0.0
                };
                a[i] = (left - right) * c.inv_m[i];
                v[i] += hh * a[i];
                left = right;
            }
        }
        v[0]
    }

    /// One sweep for `L` designs per vector of type `$v` (the same operations as
    /// [`scalar`]'s, branch-free), and the sum of the striker's velocities over every group of
    /// `L` designs of `chains`.
    macro_rules! lanes {
        ($name:ident, $feature:literal, $l:literal, $v:ty, $zero:ident, $set1:ident, $load:ident,
         $add:ident, $sub:ident, $mul:ident, $max:ident, $sqrt:ident, $sum:expr) => {
            #[target_feature(enable = $feature)]
            fn $name(chains: &[Chain]) -> f64 {
                let mut total = 0.0;
                for g in 0..chains.len() / $l {
                    let group = &chains[$l * g..$l * (g + 1)];
                    let gather = |pick: &dyn Fn(&Chain) -> f64| -> $v {
                        let x: [f64; $l] = std::array::from_fn(|l| pick(&group[l]));
                        // SAFETY: `x` holds `$l` doubles, one vector.
                        unsafe { $load(x.as_ptr()) }
                    };
                    let eta: [$v; N + 1] = std::array::from_fn(|k| gather(&|c| c.eta[k]));
                    let inv_m: [$v; N] = std::array::from_fn(|k| gather(&|c| c.inv_m[k]));
                    let z = $zero();
                    let (mut u, mut v, mut a) = ([z; N], [z; N], [z; N]);
                    v[0] = $set1(1.0);
                    let (h, hh) = ($set1(H), $set1(0.5 * H));
                    for _ in 0..STEPS {
                        for i in 0..N {
                            v[i] = $add(v[i], $mul(hh, a[i]));
                            u[i] = $add(u[i], $mul(h, v[i]));
                        }
                        let mut left = z;
                        for i in 0..N {
                            let d = if i + 1 < N {
                                $sub(u[i], u[i + 1])
                            } else {
                                u[i]
                            };
                            let d = $max(d, z);
                            let right = $mul($mul(eta[i + 1], d), $sqrt(d));
                            a[i] = $mul($sub(left, right), inv_m[i]);
                            v[i] = $add(v[i], $mul(hh, a[i]));
                            left = right;
                        }
                    }
                    total += $sum(v[0]);
                }
                total
            }
        };
    }

    lanes!(
        lanes4,
        "avx2",
        4,
        __m256d,
        _mm256_setzero_pd,
        _mm256_set1_pd,
        _mm256_loadu_pd,
        _mm256_add_pd,
        _mm256_sub_pd,
        _mm256_mul_pd,
        _mm256_max_pd,
        _mm256_sqrt_pd,
        |x: __m256d| {
            let mut out = [0.0; 4];
            // SAFETY: `out` holds 4 doubles.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), x) };
            out.iter().sum::<f64>()
        }
    );
    lanes!(
        lanes8,
        "avx512f",
        8,
        __m512d,
        _mm512_setzero_pd,
        _mm512_set1_pd,
        _mm512_loadu_pd,
        _mm512_add_pd,
        _mm512_sub_pd,
        _mm512_mul_pd,
        _mm512_max_pd,
        _mm512_sqrt_pd,
        _mm512_reduce_add_pd
    );

    pub fn run() {
        if !is_x86_feature_detected!("avx2") {
            println!("this CPU has no AVX2: nothing to compare");
            return;
        }
        let avx512 = is_x86_feature_detected!("avx512f");
        if std::env::args().any(|a| a == "--ftz") {
            // SAFETY: sets the flush-to-zero and denormals-are-zero bits of this thread's MXCSR.
            #[allow(deprecated)]
            unsafe {
                _mm_setcsr(_mm_getcsr() | 0x8040)
            };
        }
        // A xorshift of fixed seed: the constants need no quality, only variety.
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let chains: Vec<Chain> = (0..DESIGNS)
            .map(|_| Chain {
                eta: std::array::from_fn(|_| 0.5 + next()),
                inv_m: std::array::from_fn(|_| 0.3 + next()),
            })
            .collect();
        let per = (DESIGNS * STEPS * N) as f64;
        for round in 0..5 {
            let t0 = Instant::now();
            // SAFETY: AVX2 is present (checked above).
            let check: f64 = chains.iter().map(|c| unsafe { scalar(c) }).sum();
            let t_scalar = t0.elapsed().as_secs_f64() / per * 1e9;
            let t0 = Instant::now();
            // SAFETY: AVX2 is present (checked above).
            let check4 = unsafe { lanes4(&chains) };
            let t_4 = t0.elapsed().as_secs_f64() / per * 1e9;
            let mut line = format!(
                "round {round}: ns per design-grain-step: scalar {t_scalar:.3}, 4 lanes {t_4:.3}"
            );
            if avx512 {
                let t0 = Instant::now();
                // SAFETY: AVX-512F is present (checked above).
                let check8 = unsafe { lanes8(&chains) };
                let t_8 = t0.elapsed().as_secs_f64() / per * 1e9;
                line += &format!(", 8 lanes {t_8:.3} (sums {check:.9} {check4:.9} {check8:.9})");
            } else {
                line += &format!(" (sums {check:.9} {check4:.9}; no AVX-512 here)");
            }
            println!("{line}");
        }
    }
}

fn main() {
    #[cfg(target_arch = "x86_64")]
    probe::run();
    #[cfg(not(target_arch = "x86_64"))]
    println!("the lanes probe is written for x86-64");
}
