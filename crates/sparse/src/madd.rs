//! The multiply–add of the sparse products, fused where the processor has FMA.
//!
//! A product's inner step s ← s + a x is one fused multiply–add (`f64::mul_add`, one
//! rounding) on a processor with FMA (x86-64 with AVX2 and FMA, detected at run time), and a
//! product then a sum (two roundings) elsewhere. The fused form is faster (measured in the
//! deform bench: the product with A in ~12 % less time at 309k and 1M nodes) because the
//! product's loop is bound by the number of instructions it issues, not by memory.
//!
//! The kernels that use it (`Kernel`) are compiled twice: once for the processor's
//! features, run through [`pulp`]'s dispatch (which keeps every `unsafe` inside pulp), and
//! once for the baseline. The results are then the same for any thread count, as
//! everywhere in the solvers, and the same on every processor of one kind (with or without
//! FMA); they differ between the two kinds by round-off.

/// One multiply–add s + a x, with the rounding of [`Fused`] or [`Separate`].
pub(crate) trait MulAdd {
    /// s + a x.
    fn mul_add(a: f64, x: f64, s: f64) -> f64;
}

/// One rounding: `a.mul_add(x, s)`, only used where the processor has FMA.
pub(crate) struct Fused;

/// Two roundings: s + (a x).
pub(crate) struct Separate;

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, x: f64, s: f64) -> f64 {
        a.mul_add(x, s)
    }
}

impl MulAdd for Separate {
    #[inline(always)]
    fn mul_add(a: f64, x: f64, s: f64) -> f64 {
        s + a * x
    }
}

/// s ← s + a x for the three components of x and s.
#[inline(always)]
pub(crate) fn mul_add3<M: MulAdd>(a: f64, x: [f64; 3], s: &mut [f64; 3]) {
    s[0] = M::mul_add(a, x[0], s[0]);
    s[1] = M::mul_add(a, x[1], s[1]);
    s[2] = M::mul_add(a, x[2], s[2]);
}

/// A computation generic over the multiply–add ([`run`] picks it for the processor).
pub(crate) trait Kernel {
    /// What the computation returns.
    type Output;
    /// Runs the computation with the multiply–add `M`.
    fn run<M: MulAdd>(self) -> Self::Output;
}

/// Runs `k` with [`Fused`] multiply–adds, compiled for AVX2 and FMA, on a processor that has
/// them, and with [`Separate`] ones otherwise.
#[inline]
pub(crate) fn run<K: Kernel>(k: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    {
        struct WithFma<K>(K);
        impl<K: Kernel> pulp::WithSimd for WithFma<K> {
            type Output = K::Output;
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) -> K::Output {
                self.0.run::<Fused>()
            }
        }
        match pulp::Arch::new() {
            pulp::Arch::Scalar => k.run::<Separate>(),
            arch => arch.dispatch(WithFma(k)),
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    k.run::<Separate>()
}

/// True when the products (`run`) use fused multiply–adds on this processor.
pub fn fused() -> bool {
    struct Probe;
    impl Kernel for Probe {
        type Output = bool;
        fn run<M: MulAdd>(self) -> bool {
            // (1 + 2⁻³⁰)(1 − 2⁻³⁰) − 1 = −2⁻⁶⁰ exactly; rounded first, the product is 1.
            let e = (-30f64).exp2();
            M::mul_add(1.0 + e, 1.0 - e, -1.0) != 0.0
        }
    }
    run(Probe)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fused_and_separate_round_as_documented() {
        let e = (-30f64).exp2();
        assert_eq!(Fused::mul_add(1.0 + e, 1.0 - e, -1.0), -(e * e));
        assert_eq!(Separate::mul_add(1.0 + e, 1.0 - e, -1.0), 0.0);
        // Whatever the processor, `run` uses one of the two.
        let _ = fused();
    }
}
