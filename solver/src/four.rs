//! Lanes of one precision as one value ([`Lanes`]), the type the point passes' physics is
//! written in once for every width, and four lanes as one vector value ([`Four`]), written out
//! where the compiler's own vectorizer does badly: the per-point bodies of the scatters hold one lane per node of a
//! tetrahedron, and left to the compiler they were mostly shuffles and stack traffic
//! (docs/design.md §9). Each operation is the lane-wise IEEE operation (no fused
//! multiply-add), so code written with [`Four`] gives the bits of the same code written lane by
//! lane.
//!
//! On x86-64, f64 takes one 256-bit AVX register ([`F64x4`]) and f32 one 128-bit SSE register
//! ([`F32x4`]); elsewhere both take a plain array ([`Lanes4`], a [`Plain`] of four), which the
//! compiler vectorizes as it can. An [`F64x4`] is made only
//! from an [`Avx`] token, which exists only where the processor runs AVX2, so its operations
//! are safe to call; they compile to single instructions only where inlined into code compiled
//! with AVX (the passes' AVX2 copies, [`crate::parallel::avx2`]). Each precision names its type
//! as [`crate::real::Real::Four`]; this file imports nothing of the crate, so that the
//! precision, on the ground floor, needs nothing above it.

use std::ops::{Add, Div, Mul, Sub};

/// Lanes of `R` as one value, each operation the lane-wise IEEE one: what the point passes'
/// physics is written in, once, whatever the lanes hold (one point or one node each) and
/// however many there are. A [`Four`] in the passes' four-lane copies; a [`Plain`] array of
/// `W` in the portable copies and the stress pass's general batches (one lane: the scalar
/// loop). The same code over any of them gives each lane the bits of the same code written
/// for one value.
pub trait Lanes<R: Copy>:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// What proves that the processor runs this type's instructions.
    type Token: Copy + Send + Sync;
    /// All lanes `v`.
    fn splat(t: Self::Token, v: R) -> Self;
}

/// Four lanes of `R` as one value.
pub trait Four<R: Copy>: Lanes<R> {
    /// The token, where the processor runs this type's instructions.
    fn token() -> Option<Self::Token>;
    /// The lanes of `a`.
    fn load(t: Self::Token, a: &[R; 4]) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> [R; 4];
    /// Whether some lane is less than the same lane of `o` (an ordered comparison: false
    /// where either is NaN, as `<` on the scalars).
    fn any_lt(self, o: Self) -> bool;
    /// Lanes `0..live` of `self` and the others of `old` (values moved, not computed): four
    /// points' new values where only the first `live` are the element's, the rest stored back
    /// as they were loaded, so that one whole-vector store leaves them unchanged. `live` is a
    /// constant at every call (1 to 4), which folds the choice away.
    fn first_of(self, old: Self, live: usize) -> Self;
    /// The four vectors' lanes transposed: lane k of vector q of the result is lane q of
    /// vector k (values moved, not computed).
    #[inline(always)]
    fn transpose(t: Self::Token, v: [Self; 4]) -> [Self; 4] {
        let a: [[R; 4]; 4] = std::array::from_fn(|q| v[q].to_array());
        std::array::from_fn(|q| Self::load(t, &std::array::from_fn(|k| a[k][q])))
    }
    /// Four points' 3-vectors (one point's values after another, as the point arrays hold
    /// them) one vector per component: lane q of vector a is `p[q][a]` (values moved).
    #[inline(always)]
    fn load_points3(t: Self::Token, p: &[[R; 3]; 4]) -> [Self; 3] {
        std::array::from_fn(|a| Self::load(t, &std::array::from_fn(|q| p[q][a])))
    }
    /// The inverse of [`Four::load_points3`]: `p[q][a]` becomes lane q of `v[a]`.
    #[inline(always)]
    fn store_points3(v: [Self; 3], p: &mut [[R; 3]; 4]) {
        let a: [[R; 4]; 3] = std::array::from_fn(|c| v[c].to_array());
        for (q, pq) in p.iter_mut().enumerate() {
            *pq = std::array::from_fn(|c| a[c][q]);
        }
    }
    /// Four points' six values (a stress: xx yy zz xy yz zx) one vector per value: lane q of
    /// vector c is `p[q][c]` (values moved).
    #[inline(always)]
    fn load_points6(t: Self::Token, p: &[[R; 6]; 4]) -> [Self; 6] {
        std::array::from_fn(|c| Self::load(t, &std::array::from_fn(|q| p[q][c])))
    }
    /// The inverse of [`Four::load_points6`]: `p[q][c]` becomes lane q of `v[c]`.
    #[inline(always)]
    fn store_points6(v: [Self; 6], p: &mut [[R; 6]; 4]) {
        let a: [[R; 4]; 6] = std::array::from_fn(|c| v[c].to_array());
        for (q, pq) in p.iter_mut().enumerate() {
            *pq = std::array::from_fn(|c| a[c][q]);
        }
    }
    /// Two vectors' lanes interleaved, lane q of `a` then of `b`: `p` becomes (a0 b0 a1 b1
    /// a2 b2 a3 b3) (values moved).
    #[inline(always)]
    fn store_pairs(a: Self, b: Self, p: &mut [R; 8]) {
        let (a, b) = (a.to_array(), b.to_array());
        for q in 0..4 {
            (p[2 * q], p[2 * q + 1]) = (a[q], b[q]);
        }
    }
}

/// `W` lanes as a plain array: each operation lane by lane, which the compiler vectorizes as it
/// can (the portable copies' lanes; one lane is the scalar loop).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plain<R, const W: usize>(pub [R; W]);

/// Four lanes as a plain array (f32, and f64 off x86-64).
pub type Lanes4<R> = Plain<R, 4>;

macro_rules! plain_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<R: Copy + std::ops::$tr<Output = R>, const W: usize> $tr for Plain<R, W> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Plain(std::array::from_fn(|k| self.0[k] $op o.0[k]))
            }
        }
    };
}
plain_op!(Add, add, +);
plain_op!(Sub, sub, -);
plain_op!(Mul, mul, *);
plain_op!(Div, div, /);

impl<R, const W: usize> Lanes<R> for Plain<R, W>
where
    R: Copy + Add<Output = R> + Sub<Output = R> + Mul<Output = R>,
{
    type Token = ();
    #[inline(always)]
    fn splat(_: (), v: R) -> Self {
        Plain([v; W])
    }
}

impl<R> Four<R> for Lanes4<R>
where
    R: Copy + Add<Output = R> + Sub<Output = R> + Mul<Output = R> + PartialOrd,
{
    #[inline(always)]
    fn token() -> Option<()> {
        Some(())
    }
    #[inline(always)]
    fn load(_: (), a: &[R; 4]) -> Self {
        Plain(*a)
    }
    #[inline(always)]
    fn to_array(self) -> [R; 4] {
        self.0
    }
    #[inline(always)]
    fn any_lt(self, o: Self) -> bool {
        (0..4).any(|k| self.0[k] < o.0[k])
    }
    #[inline(always)]
    fn first_of(self, old: Self, live: usize) -> Self {
        Plain(std::array::from_fn(|k| {
            if k < live {
                self.0[k]
            } else {
                old.0[k]
            }
        }))
    }
}

#[cfg(target_arch = "x86_64")]
pub use x86::{Avx, F32x4, F64x4, Sse};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{Four, Lanes};
    use std::arch::x86_64::{
        __m128, __m128d, __m256d, _mm256_add_pd, _mm256_blend_pd, _mm256_castpd128_pd256,
        _mm256_castpd256_pd128, _mm256_cmp_pd, _mm256_extractf128_pd, _mm256_insertf128_pd,
        _mm256_loadu_pd, _mm256_movemask_pd, _mm256_mul_pd, _mm256_permute2f128_pd,
        _mm256_permute_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd, _mm256_unpackhi_pd,
        _mm256_unpacklo_pd, _mm_add_ps, _mm_castpd_ps, _mm_castps_pd, _mm_cmplt_ps, _mm_load_sd,
        _mm_loadu_pd, _mm_loadu_ps, _mm_move_ss, _mm_movehl_ps, _mm_movelh_ps, _mm_movemask_ps,
        _mm_mul_ps, _mm_set1_ps, _mm_shuffle_ps, _mm_store_sd, _mm_storeu_pd, _mm_storeu_ps,
        _mm_sub_ps, _mm_unpackhi_ps, _mm_unpacklo_ps, _CMP_LT_OQ,
    };

    /// `_mm_shuffle_ps`'s selector: lanes 0 and 1 from the first operand's lanes `a0`, `a1`,
    /// lanes 2 and 3 from the second's `b2`, `b3`.
    const fn pick(a0: i32, a1: i32, b2: i32, b3: i32) -> i32 {
        a0 | a1 << 2 | b2 << 4 | b3 << 6
    }
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

    impl Lanes<f32> for F32x4 {
        type Token = Sse;
        #[inline(always)]
        fn splat(_: Sse, v: f32) -> Self {
            // SAFETY: SSE is part of x86-64.
            F32x4(unsafe { _mm_set1_ps(v) })
        }
    }

    impl Four<f32> for F32x4 {
        #[inline(always)]
        fn token() -> Option<Sse> {
            Some(Sse(()))
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
        fn first_of(self, old: Self, live: usize) -> Self {
            let (n, o) = (self.0, old.0);
            // SAFETY: SSE is part of x86-64.
            F32x4(unsafe {
                match live {
                    // (n0 o1 o2 o3): lane 0 moved in.
                    1 => _mm_move_ss(o, n),
                    // (n0 n1 o2 o3).
                    2 => _mm_shuffle_ps::<{ pick(0, 1, 2, 3) }>(n, o),
                    // (n2 n2 o3 o3), then (n0 n1 n2 o3).
                    3 => {
                        let t = _mm_shuffle_ps::<{ pick(2, 2, 3, 3) }>(n, o);
                        _mm_shuffle_ps::<{ pick(0, 1, 0, 2) }>(n, t)
                    }
                    _ => n,
                }
            })
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
        #[inline(always)]
        fn load_points3(_: Sse, p: &[[f32; 3]; 4]) -> [Self; 3] {
            let m = p.as_ptr().cast::<f32>();
            // SAFETY: SSE is part of x86-64; `p` is 12 consecutive f32, read as three
            // unaligned fours: (x0 y0 z0 x1), (y1 z1 x2 y2), (z2 x3 y3 z3).
            unsafe {
                let (a, b, c) = (
                    _mm_loadu_ps(m),
                    _mm_loadu_ps(m.add(4)),
                    _mm_loadu_ps(m.add(8)),
                );
                // Two of each component per shuffle, then the two pairs into one.
                let x02 = _mm_shuffle_ps::<{ pick(2, 0, 1, 0) }>(b, c);
                let x = _mm_shuffle_ps::<{ pick(0, 3, 0, 2) }>(a, x02);
                let y01 = _mm_shuffle_ps::<{ pick(1, 0, 0, 0) }>(a, b);
                let y23 = _mm_shuffle_ps::<{ pick(3, 0, 2, 0) }>(b, c);
                let y = _mm_shuffle_ps::<{ pick(0, 2, 0, 2) }>(y01, y23);
                let z01 = _mm_shuffle_ps::<{ pick(2, 0, 1, 0) }>(a, b);
                let z23 = _mm_shuffle_ps::<{ pick(0, 0, 3, 0) }>(c, c);
                let z = _mm_shuffle_ps::<{ pick(0, 2, 0, 2) }>(z01, z23);
                [F32x4(x), F32x4(y), F32x4(z)]
            }
        }
        #[inline(always)]
        fn store_points3(v: [Self; 3], p: &mut [[f32; 3]; 4]) {
            let [x, y, z] = [v[0].0, v[1].0, v[2].0];
            let m = p.as_mut_ptr().cast::<f32>();
            // SAFETY: SSE is part of x86-64; `p` is 12 consecutive f32, written as three
            // unaligned fours (the inverse of `load_points3`'s shuffles).
            unsafe {
                let pair = |u: __m128, w: __m128| _mm_shuffle_ps::<{ pick(0, 2, 0, 2) }>(u, w);
                let a = pair(
                    _mm_shuffle_ps::<{ pick(0, 0, 0, 0) }>(x, y),
                    _mm_shuffle_ps::<{ pick(0, 0, 1, 0) }>(z, x),
                );
                let b = pair(
                    _mm_shuffle_ps::<{ pick(1, 0, 1, 0) }>(y, z),
                    _mm_shuffle_ps::<{ pick(2, 0, 2, 0) }>(x, y),
                );
                let c = pair(
                    _mm_shuffle_ps::<{ pick(2, 0, 3, 0) }>(z, x),
                    _mm_shuffle_ps::<{ pick(3, 0, 3, 0) }>(y, z),
                );
                _mm_storeu_ps(m, a);
                _mm_storeu_ps(m.add(4), b);
                _mm_storeu_ps(m.add(8), c);
            }
        }
        #[inline(always)]
        fn load_points6(t: Sse, p: &[[f32; 6]; 4]) -> [Self; 6] {
            // SAFETY: SSE is part of x86-64 (SSE2 for the 64-bit loads); each row is six
            // consecutive f32, read as an unaligned four and an unaligned two.
            unsafe {
                let lo: [Self; 4] = std::array::from_fn(|q| F32x4(_mm_loadu_ps(p[q].as_ptr())));
                let hi: [__m128; 4] = std::array::from_fn(|q| {
                    _mm_castpd_ps(_mm_load_sd(p[q].as_ptr().add(4).cast::<f64>()))
                });
                let [c0, c1, c2, c3] = Self::transpose(t, lo);
                // (s4 s5) of points 0 and 1, of 2 and 3; then each value's four.
                let (h01, h23) = (_mm_movelh_ps(hi[0], hi[1]), _mm_movelh_ps(hi[2], hi[3]));
                let c4 = _mm_shuffle_ps::<{ pick(0, 2, 0, 2) }>(h01, h23);
                let c5 = _mm_shuffle_ps::<{ pick(1, 3, 1, 3) }>(h01, h23);
                [c0, c1, c2, c3, F32x4(c4), F32x4(c5)]
            }
        }
        #[inline(always)]
        fn store_points6(v: [Self; 6], p: &mut [[f32; 6]; 4]) {
            let rows = Self::transpose(Sse(()), [v[0], v[1], v[2], v[3]]);
            // SAFETY: SSE is part of x86-64 (SSE2 for the 64-bit stores); each row is six
            // consecutive f32, written as an unaligned four and an unaligned two.
            unsafe {
                // (s4_0 s5_0 s4_1 s5_1), (s4_2 s5_2 s4_3 s5_3).
                let h01 = _mm_unpacklo_ps(v[4].0, v[5].0);
                let h23 = _mm_unpackhi_ps(v[4].0, v[5].0);
                let hi = [h01, _mm_movehl_ps(h01, h01), h23, _mm_movehl_ps(h23, h23)];
                for q in 0..4 {
                    let r = p[q].as_mut_ptr();
                    _mm_storeu_ps(r, rows[q].0);
                    _mm_store_sd(r.add(4).cast::<f64>(), _mm_castps_pd(hi[q]));
                }
            }
        }
        #[inline(always)]
        fn store_pairs(a: Self, b: Self, p: &mut [f32; 8]) {
            // SAFETY: SSE is part of x86-64; `p` holds eight f32 (two unaligned stores of
            // (a0 b0 a1 b1) and (a2 b2 a3 b3)).
            unsafe {
                _mm_storeu_ps(p.as_mut_ptr(), _mm_unpacklo_ps(a.0, b.0));
                _mm_storeu_ps(p.as_mut_ptr().add(4), _mm_unpackhi_ps(a.0, b.0));
            }
        }
    }

    impl Lanes<f64> for F64x4 {
        type Token = Avx;
        #[inline(always)]
        fn splat(_: Avx, v: f64) -> Self {
            debug_assert!(std::arch::is_x86_feature_detected!("avx"));
            // SAFETY: the token proves that the processor runs AVX.
            F64x4(unsafe { _mm256_set1_pd(v) })
        }
    }

    impl Four<f64> for F64x4 {
        #[inline(always)]
        fn token() -> Option<Avx> {
            std::arch::is_x86_feature_detected!("avx2").then_some(Avx(()))
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
        fn first_of(self, old: Self, live: usize) -> Self {
            let (n, o) = (self.0, old.0);
            // SAFETY: an F64x4 exists only where the processor runs AVX. (The selector's bit k
            // takes lane k from the second operand.)
            F64x4(unsafe {
                match live {
                    1 => _mm256_blend_pd::<0b0001>(o, n),
                    2 => _mm256_blend_pd::<0b0011>(o, n),
                    3 => _mm256_blend_pd::<0b0111>(o, n),
                    _ => n,
                }
            })
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
        #[inline(always)]
        fn load_points3(_: Avx, p: &[[f64; 3]; 4]) -> [Self; 3] {
            debug_assert!(std::arch::is_x86_feature_detected!("avx"));
            let m = p.as_ptr().cast::<f64>();
            // SAFETY: the token proves AVX; `p` is 12 consecutive f64, read as three unaligned
            // fours: (x0 y0 z0 x1), (y1 z1 x2 y2), (z2 x3 y3 z3).
            unsafe {
                let (a, b, c) = (
                    _mm256_loadu_pd(m),
                    _mm256_loadu_pd(m.add(4)),
                    _mm256_loadu_pd(m.add(8)),
                );
                // (x0 y0 y3 z3) and (z0 x1 z2 x3): the outer and the inner halves.
                let outer = _mm256_permute2f128_pd::<0x30>(a, c);
                let inner = _mm256_permute2f128_pd::<0x21>(a, c);
                let x = _mm256_blend_pd::<0b0100>(_mm256_blend_pd::<0b1010>(outer, inner), b);
                // (y1 y0 y3 y2), each pair then swapped.
                let y = _mm256_permute_pd::<0b0101>(_mm256_blend_pd::<0b1001>(outer, b));
                let z = _mm256_blend_pd::<0b1000>(_mm256_blend_pd::<0b0010>(inner, b), outer);
                [F64x4(x), F64x4(y), F64x4(z)]
            }
        }
        #[inline(always)]
        fn store_points3(v: [Self; 3], p: &mut [[f64; 3]; 4]) {
            let [x, y, z] = [v[0].0, v[1].0, v[2].0];
            let m = p.as_mut_ptr().cast::<f64>();
            // SAFETY: an F64x4 exists only where the processor runs AVX; `p` is 12
            // consecutive f64, written as three unaligned fours (the inverse of
            // `load_points3`).
            unsafe {
                let swapped = _mm256_permute_pd::<0b0101>(y);
                let outer = _mm256_blend_pd::<0b1000>(_mm256_blend_pd::<0b0110>(x, swapped), z);
                let inner = _mm256_blend_pd::<0b1010>(z, x);
                let b = _mm256_blend_pd::<0b0100>(_mm256_blend_pd::<0b0010>(swapped, z), x);
                _mm256_storeu_pd(m, _mm256_permute2f128_pd::<0x20>(outer, inner));
                _mm256_storeu_pd(m.add(4), b);
                _mm256_storeu_pd(m.add(8), _mm256_permute2f128_pd::<0x31>(inner, outer));
            }
        }
        #[inline(always)]
        fn load_points6(t: Avx, p: &[[f64; 6]; 4]) -> [Self; 6] {
            debug_assert!(std::arch::is_x86_feature_detected!("avx"));
            // SAFETY: the token proves AVX; each row is six consecutive f64, read as an
            // unaligned four and an unaligned two.
            unsafe {
                let lo: [Self; 4] = std::array::from_fn(|q| F64x4(_mm256_loadu_pd(p[q].as_ptr())));
                let hi: [__m128d; 4] = std::array::from_fn(|q| _mm_loadu_pd(p[q].as_ptr().add(4)));
                let [c0, c1, c2, c3] = Self::transpose(t, lo);
                // (s4 s5) of points 0 and 2, of 1 and 3; then each value's four.
                let h02 = _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(hi[0]), hi[2]);
                let h13 = _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(hi[1]), hi[3]);
                let c4 = F64x4(_mm256_unpacklo_pd(h02, h13));
                let c5 = F64x4(_mm256_unpackhi_pd(h02, h13));
                [c0, c1, c2, c3, c4, c5]
            }
        }
        #[inline(always)]
        fn store_points6(v: [Self; 6], p: &mut [[f64; 6]; 4]) {
            let rows = Self::transpose(Avx(()), [v[0], v[1], v[2], v[3]]);
            // SAFETY: an F64x4 exists only where the processor runs AVX; each row is six
            // consecutive f64, written as an unaligned four and an unaligned two.
            unsafe {
                // (s4_0 s5_0 s4_2 s5_2), (s4_1 s5_1 s4_3 s5_3).
                let h02 = _mm256_unpacklo_pd(v[4].0, v[5].0);
                let h13 = _mm256_unpackhi_pd(v[4].0, v[5].0);
                let hi = [
                    _mm256_castpd256_pd128(h02),
                    _mm256_castpd256_pd128(h13),
                    _mm256_extractf128_pd::<1>(h02),
                    _mm256_extractf128_pd::<1>(h13),
                ];
                for q in 0..4 {
                    let r = p[q].as_mut_ptr();
                    _mm256_storeu_pd(r, rows[q].0);
                    _mm_storeu_pd(r.add(4), hi[q]);
                }
            }
        }
        #[inline(always)]
        fn store_pairs(a: Self, b: Self, p: &mut [f64; 8]) {
            // SAFETY: an F64x4 exists only where the processor runs AVX; `p` holds eight f64
            // (two unaligned stores).
            unsafe {
                // (a0 b0 a2 b2) and (a1 b1 a3 b3); then their low halves and their high ones.
                let lo = _mm256_unpacklo_pd(a.0, b.0);
                let hi = _mm256_unpackhi_pd(a.0, b.0);
                let m = p.as_mut_ptr();
                _mm256_storeu_pd(m, _mm256_permute2f128_pd::<0x20>(lo, hi));
                _mm256_storeu_pd(m.add(4), _mm256_permute2f128_pd::<0x31>(lo, hi));
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
                // Points' values in and out of lanes: lane q of vector c is point q's value c.
                let p3: [[$r; 3]; 4] = std::array::from_fn(|q| [a[q], b[q], d[q]]);
                let v3 = <$four>::load_points3(t, &p3);
                let mut back3 = [[0.0; 3]; 4];
                <$four>::store_points3(v3, &mut back3);
                let p6: [[$r; 6]; 4] =
                    std::array::from_fn(|q| [a[q], b[q], d[q], e[q], -a[q], c * b[q]]);
                let v6 = <$four>::load_points6(t, &p6);
                let mut back6 = [[0.0; 6]; 4];
                <$four>::store_points6(v6, &mut back6);
                for q in 0..4 {
                    for c in 0..3 {
                        assert_eq!(v3[c].to_array()[q].to_bits(), p3[q][c].to_bits());
                        assert_eq!(back3[q][c].to_bits(), p3[q][c].to_bits());
                    }
                    for c in 0..6 {
                        assert_eq!(v6[c].to_array()[q].to_bits(), p6[q][c].to_bits());
                        assert_eq!(back6[q][c].to_bits(), p6[q][c].to_bits());
                    }
                }
                // The first lanes of one vector, the others of another.
                for live in 1..=4 {
                    let got = <$four>::load(t, &a).first_of(<$four>::load(t, &d), live);
                    for (k, g) in got.to_array().iter().enumerate() {
                        let want = if k < live { a[k] } else { d[k] };
                        assert_eq!(g.to_bits(), want.to_bits(), "first {live} of lane {k}");
                    }
                }
                // Two vectors' lanes interleaved.
                let mut pairs = [0.0; 8];
                <$four>::store_pairs(<$four>::load(t, &a), <$four>::load(t, &d), &mut pairs);
                for q in 0..4 {
                    assert_eq!(pairs[2 * q].to_bits(), a[q].to_bits(), "pairs {q}");
                    assert_eq!(pairs[2 * q + 1].to_bits(), d[q].to_bits(), "pairs {q}");
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
