//! Four lanes of one precision as one vector value, written out where the compiler's own
//! vectorizer does badly: the per-point bodies of the scatters hold one lane per node of a
//! tetrahedron, and left to the compiler they were mostly shuffles and stack traffic
//! (docs/design.md §9). Each operation is the lane-wise IEEE operation (no fused
//! multiply-add), so code written with [`Four`] gives the bits of the same code written lane by
//! lane.
//!
//! On x86-64, f64 takes one 256-bit AVX register ([`F64x4`]) and f32 one 128-bit SSE register
//! ([`F32x4`]); elsewhere both take a plain array ([`Lanes4`]), which the compiler vectorizes
//! as it can. An [`F64x4`] is made only
//! from an [`Avx`] token, which exists only where the processor runs AVX2, so its operations
//! are safe to call; they compile to single instructions only where inlined into code compiled
//! with AVX (the passes' AVX2 copies, [`crate::parallel::avx2`]). Each precision names its type
//! as [`crate::real::Real::Four`]; this file imports nothing of the crate, so that the
//! precision, on the ground floor, needs nothing above it.

use std::ops::{Add, Mul, Sub};

/// Four lanes of `R` as one value.
pub trait Four<R: Copy>:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// What proves that the processor runs this type's instructions.
    type Token: Copy + Send + Sync;
    /// The token, where the processor runs this type's instructions.
    fn token() -> Option<Self::Token>;
    /// All four lanes `v`.
    fn splat(t: Self::Token, v: R) -> Self;
    /// The lanes of `a`.
    fn load(t: Self::Token, a: &[R; 4]) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> [R; 4];
    /// Whether some lane is less than the same lane of `o` (an ordered comparison: false
    /// where either is NaN, as `<` on the scalars).
    fn any_lt(self, o: Self) -> bool;
    /// The four vectors' lanes transposed: lane k of vector q of the result is lane q of
    /// vector k (values moved, not computed).
    #[inline(always)]
    fn transpose(t: Self::Token, v: [Self; 4]) -> [Self; 4] {
        let a: [[R; 4]; 4] = std::array::from_fn(|q| v[q].to_array());
        std::array::from_fn(|q| Self::load(t, &std::array::from_fn(|k| a[k][q])))
    }
}

/// Four lanes as a plain array (f32, and f64 off x86-64): each operation lane by lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lanes4<R>([R; 4]);

macro_rules! lanes4_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<R: Copy + std::ops::$tr<Output = R>> $tr for Lanes4<R> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Lanes4(std::array::from_fn(|k| self.0[k] $op o.0[k]))
            }
        }
    };
}
lanes4_op!(Add, add, +);
lanes4_op!(Sub, sub, -);
lanes4_op!(Mul, mul, *);

impl<R> Four<R> for Lanes4<R>
where
    R: Copy + Add<Output = R> + Sub<Output = R> + Mul<Output = R> + PartialOrd,
{
    type Token = ();
    #[inline(always)]
    fn token() -> Option<()> {
        Some(())
    }
    #[inline(always)]
    fn splat(_: (), v: R) -> Self {
        Lanes4([v; 4])
    }
    #[inline(always)]
    fn load(_: (), a: &[R; 4]) -> Self {
        Lanes4(*a)
    }
    #[inline(always)]
    fn to_array(self) -> [R; 4] {
        self.0
    }
    #[inline(always)]
    fn any_lt(self, o: Self) -> bool {
        (0..4).any(|k| self.0[k] < o.0[k])
    }
}

#[cfg(target_arch = "x86_64")]
pub use x86::{Avx, F32x4, F64x4, Sse};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::Four;
    use std::arch::x86_64::{
        __m128, __m256d, _mm256_add_pd, _mm256_cmp_pd, _mm256_loadu_pd, _mm256_movemask_pd,
        _mm256_mul_pd, _mm256_permute2f128_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd,
        _mm256_unpackhi_pd, _mm256_unpacklo_pd, _mm_add_ps, _mm_cmplt_ps, _mm_loadu_ps,
        _mm_movehl_ps, _mm_movelh_ps, _mm_movemask_ps, _mm_mul_ps, _mm_set1_ps, _mm_storeu_ps,
        _mm_sub_ps, _mm_unpackhi_ps, _mm_unpacklo_ps, _CMP_LT_OQ,
    };
    use std::ops::{Add, Mul, Sub};

    /// Proof that the processor runs AVX2 (and so AVX): made only by [`Four::token`] after
    /// asking the processor.
    #[derive(Debug, Clone, Copy)]
    pub struct Avx(());

    /// Four f64 lanes in one 256-bit AVX register; exists only where the processor runs AVX2
    /// (made from an [`Avx`]).
    #[derive(Debug, Clone, Copy)]
    pub struct F64x4(__m256d);

    /// Proof that the processor runs SSE: every x86-64 processor does (a token, so that
    /// [`F32x4`] has the shape of [`F64x4`]).
    #[derive(Debug, Clone, Copy)]
    pub struct Sse(());

    /// Four f32 lanes in one 128-bit SSE register (SSE is part of x86-64).
    #[derive(Debug, Clone, Copy)]
    pub struct F32x4(__m128);

    macro_rules! vector_op {
        ($ty:ident, $tr:ident, $f:ident, $intr:ident) => {
            impl $tr for $ty {
                type Output = Self;
                #[inline(always)]
                fn $f(self, o: Self) -> Self {
                    // SAFETY: an F64x4 exists only where the processor runs AVX (made from an
                    // `Avx` token, which `token` makes only after asking it); an F32x4 needs
                    // SSE, which every x86-64 processor runs.
                    $ty(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    vector_op!(F64x4, Add, add, _mm256_add_pd);
    vector_op!(F64x4, Sub, sub, _mm256_sub_pd);
    vector_op!(F64x4, Mul, mul, _mm256_mul_pd);
    vector_op!(F32x4, Add, add, _mm_add_ps);
    vector_op!(F32x4, Sub, sub, _mm_sub_ps);
    vector_op!(F32x4, Mul, mul, _mm_mul_ps);

    impl Four<f32> for F32x4 {
        type Token = Sse;
        #[inline(always)]
        fn token() -> Option<Sse> {
            Some(Sse(()))
        }
        #[inline(always)]
        fn splat(_: Sse, v: f32) -> Self {
            // SAFETY: SSE is part of x86-64.
            F32x4(unsafe { _mm_set1_ps(v) })
        }
        #[inline(always)]
        fn load(_: Sse, a: &[f32; 4]) -> Self {
            // SAFETY: SSE is part of x86-64; `a` holds four f32 (an unaligned load).
            F32x4(unsafe { _mm_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        fn to_array(self) -> [f32; 4] {
            let mut a = [0.0; 4];
            // SAFETY: SSE is part of x86-64; `a` has room for four f32 (an unaligned store).
            unsafe { _mm_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn any_lt(self, o: Self) -> bool {
            // SAFETY: SSE is part of x86-64. (`cmplt` is ordered: false with a NaN.)
            unsafe { _mm_movemask_ps(_mm_cmplt_ps(self.0, o.0)) != 0 }
        }
        #[inline(always)]
        fn transpose(_: Sse, v: [Self; 4]) -> [Self; 4] {
            let [r0, r1, r2, r3] = [v[0].0, v[1].0, v[2].0, v[3].0];
            // SAFETY: SSE is part of x86-64.
            unsafe {
                // (r0[0] r1[0] r0[1] r1[1]), (r2[0] r3[0] r2[1] r3[1]), and the upper halves.
                let (a, b) = (_mm_unpacklo_ps(r0, r1), _mm_unpacklo_ps(r2, r3));
                let (c, d) = (_mm_unpackhi_ps(r0, r1), _mm_unpackhi_ps(r2, r3));
                [
                    F32x4(_mm_movelh_ps(a, b)),
                    F32x4(_mm_movehl_ps(b, a)),
                    F32x4(_mm_movelh_ps(c, d)),
                    F32x4(_mm_movehl_ps(d, c)),
                ]
            }
        }
    }

    impl Four<f64> for F64x4 {
        type Token = Avx;
        #[inline(always)]
        fn token() -> Option<Avx> {
            std::arch::is_x86_feature_detected!("avx2").then_some(Avx(()))
        }
        #[inline(always)]
        fn splat(_: Avx, v: f64) -> Self {
            debug_assert!(std::arch::is_x86_feature_detected!("avx"));
            // SAFETY: the token proves that the processor runs AVX.
            F64x4(unsafe { _mm256_set1_pd(v) })
        }
        #[inline(always)]
        fn load(_: Avx, a: &[f64; 4]) -> Self {
            debug_assert!(std::arch::is_x86_feature_detected!("avx"));
            // SAFETY: the token proves AVX; `a` holds four f64 (an unaligned load).
            F64x4(unsafe { _mm256_loadu_pd(a.as_ptr()) })
        }
        #[inline(always)]
        fn to_array(self) -> [f64; 4] {
            let mut a = [0.0; 4];
            // SAFETY: an F64x4 exists only where the processor runs AVX; `a` has room for
            // four f64 (an unaligned store).
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        fn any_lt(self, o: Self) -> bool {
            // SAFETY: an F64x4 exists only where the processor runs AVX. (Ordered, quiet:
            // false with a NaN, as `<`.)
            unsafe { _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(self.0, o.0)) != 0 }
        }
        #[inline(always)]
        fn transpose(_: Avx, v: [Self; 4]) -> [Self; 4] {
            let [r0, r1, r2, r3] = [v[0].0, v[1].0, v[2].0, v[3].0];
            // SAFETY: an F64x4 exists only where the processor runs AVX.
            unsafe {
                // (r0[0] r1[0] r0[2] r1[2]), (r0[1] r1[1] r0[3] r1[3]), and of r2, r3; then
                // each result's halves from the low or the high halves of two of these.
                let (a, b) = (_mm256_unpacklo_pd(r0, r1), _mm256_unpackhi_pd(r0, r1));
                let (c, d) = (_mm256_unpacklo_pd(r2, r3), _mm256_unpackhi_pd(r2, r3));
                [
                    F64x4(_mm256_permute2f128_pd::<0x20>(a, c)),
                    F64x4(_mm256_permute2f128_pd::<0x20>(b, d)),
                    F64x4(_mm256_permute2f128_pd::<0x31>(a, c)),
                    F64x4(_mm256_permute2f128_pd::<0x31>(b, d)),
                ]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each lane of `a * b + c - b` in the four-lane type `$four` has the bits of the same
    /// scalar operations in `$r`.
    macro_rules! lane_by_lane {
        ($r:ty, $four:ty) => {{
            let Some(t) = <$four as Four<$r>>::token() else {
                eprintln!(
                    "skipped: {} needs what this processor lacks",
                    stringify!($four)
                );
                return;
            };
            let mut rng = crate::test_rng::uniform(7);
            for _ in 0..1000 {
                let a: [$r; 4] = std::array::from_fn(|_| (rng() * 1e3) as $r);
                let b: [$r; 4] = std::array::from_fn(|_| (rng() * 1e-3) as $r);
                let c = rng() as $r;
                let (va, vb) = (<$four>::load(t, &a), <$four>::load(t, &b));
                let got = (va * vb + <$four>::splat(t, c) - vb).to_array();
                for k in 0..4 {
                    let want = a[k] * b[k] + c - b[k];
                    assert_eq!(got[k].to_bits(), want.to_bits());
                }
                // The comparison, with NaNs and equal lanes among the values.
                let mut d = a;
                d[(c * 4.0) as usize % 4] = <$r>::NAN;
                let e: [$r; 4] = std::array::from_fn(|k| if k % 2 == 0 { d[k] } else { b[k] });
                for (x, y) in [(d, e), (e, d), (d, d), (b, a)] {
                    let want = (0..4).any(|k| x[k] < y[k]);
                    let got = <$four>::load(t, &x).any_lt(<$four>::load(t, &y));
                    assert_eq!(got, want, "{x:?} < {y:?}");
                }
                // The transpose: lane k of result q is lane q of input k.
                let m: [[$r; 4]; 4] = [a, b, d, e];
                let got = <$four>::transpose(t, m.map(|r| <$four>::load(t, &r)));
                for q in 0..4 {
                    let lanes = got[q].to_array();
                    for k in 0..4 {
                        assert_eq!(lanes[k].to_bits(), m[k][q].to_bits(), "transpose {q} {k}");
                    }
                }
            }
        }};
    }

    #[test]
    fn four_lanes_are_the_scalar_operations() {
        lane_by_lane!(f64, Lanes4<f64>);
        lane_by_lane!(f32, Lanes4<f32>);
        #[cfg(target_arch = "x86_64")]
        {
            lane_by_lane!(f32, F32x4);
            lane_by_lane!(f64, F64x4);
        }
    }
}
