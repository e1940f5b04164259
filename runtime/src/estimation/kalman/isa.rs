//! The instruction set a Kalman step runs on, chosen once when the filter is built.
//!
//! The products of a step (`products`) are sums of columns scaled by scalars. On the default x86-64 target
//! (SSE2) a column of `NX` entries takes `⌈NX/2⌉` multiplications and as many additions per scalar; with AVX2
//! and FMA (Intel since Haswell, AMD since Zen 1) it takes `⌈NX/4⌉` fused multiply-adds, about a third of the
//! instructions. The filter asks the processor once, when it is built, and then runs its step through a copy
//! of the code compiled for those instructions; every other processor and architecture runs the portable
//! copy. A fused multiply-add rounds once where a multiplication and an addition round twice, so the two
//! copies agree to rounding, not bit for bit, and each rounding bound of `definite` (which counts every
//! multiplication and addition as rounded) holds for both.

/// How the products form `a b + c`.
pub(super) trait MulAdd {
    fn mul_add(a: f64, b: f64, c: f64) -> f64;
}

/// A multiplication and an addition, each rounded: the portable code.
pub(super) struct Separate;

impl MulAdd for Separate {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}

/// One fused multiply-add. Compiled into a function without the `fma` feature it becomes a call into the
/// math library (correct, and slow), so it is used only in code reached through [`Isa::Avx2Fma`].
#[cfg(target_arch = "x86_64")]
pub(super) struct Fused;

#[cfg(target_arch = "x86_64")]
impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

/// The instruction set of a filter's step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Isa {
    /// The default target's instructions.
    Portable,
    /// AVX2 and FMA, which [`Isa::detect`] found on this processor: the only way to make this value, so that
    /// holding it is the proof the `unsafe` calls of the step need.
    #[cfg(target_arch = "x86_64")]
    Avx2Fma,
}

impl Isa {
    /// The fastest instruction set this processor has for the step.
    pub(super) fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            return Isa::Avx2Fma;
        }
        Isa::Portable
    }
}
