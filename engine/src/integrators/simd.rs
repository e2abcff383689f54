//! Runtime selection of the instruction set for the hot loops.
//!
//! The stepping loops are written once, `#[inline(always)]`, and compiled twice: for the
//! baseline x86-64 (SSE2) and for AVX2, picked once per `advance_to` call by CPU detection. The
//! results are bit-for-bit identical: every operation in the loops (add, sub, mul, div, sqrt,
//! compare-select, and the libm `pow` of the general law) is correctly rounded or the same
//! function call in both, and Rust never contracts a*b+c into a fused multiply-add, so golden
//! data do not depend on the machine.

/// True when the AVX2 build of the loops can run here.
#[inline]
pub(crate) fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Define `$name` that runs the `#[inline(always)]` method `$imp` of `$ty` with AVX2 enabled
/// when available, and with the baseline instruction set otherwise.
macro_rules! dispatch_simd {
    ($ty:ty, $name:ident, $imp:ident, ($($arg:ident : $t:ty),*) -> $ret:ty) => {
        impl $ty {
            fn $name(&mut self, $($arg: $t),*) -> $ret {
                #[cfg(target_arch = "x86_64")]
                {
                    #[target_feature(enable = "avx2")]
                    fn avx2(this: &mut $ty, $($arg: $t),*) -> $ret {
                        this.$imp($($arg),*)
                    }
                    if $crate::integrators::simd::has_avx2() {
                        // SAFETY: the CPU supports AVX2 (checked just above).
                        return unsafe { avx2(self, $($arg),*) };
                    }
                }
                self.$imp($($arg),*)
            }
        }
    };
}
pub(crate) use dispatch_simd;
