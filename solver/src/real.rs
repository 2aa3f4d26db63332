//! The solver's precision: one generic parameter, so f32 and f64 share one code path.

use std::fmt::Debug;

use crate::four::Four;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A floating-point type the solver can run in (`f64` now, `f32` from the same code).
pub trait Real:
    Copy
    + Send
    + Sync
    + Default
    + Debug
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + 'static
{
    /// Four lanes of this precision as one vector value ([`crate::four`]).
    type Four: Four<Self>;
    /// Name written to `run.json`.
    const NAME: &'static str;
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// Machine epsilon (the gap between 1 and the next number), as f64.
    const EPSILON: f64;
    /// Conversion from `f64` (rounding for `f32`).
    fn of(v: f64) -> Self;
    /// Conversion to `f64`.
    fn f64(self) -> f64;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Absolute value.
    fn abs(self) -> Self;
    /// Bytes of one value.
    const BYTES: usize;
    /// The fraction of a nodal field's largest magnitude below which its values are set to
    /// zero each step ([`crate::step::tail`]); 0 for none.
    const TAIL: f64;
    /// The largest magnitude among the finite `values` (0 where none is, or for none).
    fn largest_finite_magnitude(values: &[Self]) -> Self;
    /// Appends the value's bits, little-endian (checkpoints round-trip exactly).
    fn put_bits(self, out: &mut Vec<u8>);
    /// The value of exactly [`Real::BYTES`] little-endian bytes (`None` for another length).
    fn from_bits(b: &[u8]) -> Option<Self>;
    /// +1, -1 or 0 (0 for 0, unlike `f64::signum`).
    fn sign(self) -> Self {
        if self > Self::ZERO {
            Self::ONE
        } else if self < Self::ZERO {
            -Self::ONE
        } else {
            Self::ZERO
        }
    }
    /// Smaller of two values.
    fn min(self, o: Self) -> Self {
        if o < self {
            o
        } else {
            self
        }
    }
    /// Larger of two values.
    fn max(self, o: Self) -> Self {
        if o > self {
            o
        } else {
            self
        }
    }
}

macro_rules! real {
    ($t:ty, $bits:ty, $name:expr, $four:ty, $tail:expr) => {
        impl Real for $t {
            type Four = $four;
            const TAIL: f64 = $tail;
            const NAME: &'static str = $name;
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const EPSILON: f64 = <$t>::EPSILON as f64;
            const BYTES: usize = std::mem::size_of::<$t>();
            fn largest_finite_magnitude(values: &[Self]) -> Self {
                // A magnitude's bits (the sign's cleared) order as the magnitudes do, the
                // infinities' and NaNs' above every finite one's: an integer maximum, which
                // the compiler makes vector operations (a float maximum skipping NaNs, it
                // left a compare and branch per value).
                const SIGN: $bits = 1 << (<$bits>::BITS - 1);
                let infinite = <$t>::INFINITY.to_bits();
                let m = values.iter().fold(0, |m: $bits, x| {
                    let b = x.to_bits() & !SIGN;
                    m.max(if b < infinite { b } else { 0 })
                });
                <$t>::from_bits(m)
            }
            fn put_bits(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_bits().to_le_bytes());
            }
            fn from_bits(b: &[u8]) -> Option<Self> {
                Some(<$t>::from_bits(<$bits>::from_le_bytes(b.try_into().ok()?)))
            }
            #[inline(always)]
            fn of(v: f64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
        }
    };
}
/// Double precision keeps every nodal value (and so the bits of before): its products reach
/// the subnormal range only some 300 orders of magnitude down, which no case has shown.
const F64_TAIL: f64 = 0.0;
/// Single precision cuts nodal values below 2⁻⁴⁰ (about 9e-13) of the field's largest, 2¹⁶
/// below its own resolution (2⁻²⁴): a wave front's numerical precursor, whose products of two
/// such values otherwise fall below f32's smallest normal number (1.2e-38) and run each
/// operation through the processor's slow subnormal path (docs/design.md §9: a two-phase f32
/// column ran 1.6× slower than f64).
const F32_TAIL: f64 = 1.0 / (1u64 << 40) as f64;
#[cfg(target_arch = "x86_64")]
real!(f64, u64, "f64", crate::four::F64x4, F64_TAIL);
#[cfg(not(target_arch = "x86_64"))]
real!(f64, u64, "f64", crate::four::Lanes4<f64>, F64_TAIL);
#[cfg(target_arch = "x86_64")]
real!(f32, u32, "f32", crate::four::F32x4, F32_TAIL);
#[cfg(not(target_arch = "x86_64"))]
real!(f32, u32, "f32", crate::four::Lanes4<f32>, F32_TAIL);

/// A 3-vector.
pub type V3<R> = [R; 3];

#[cfg(test)]
mod tests {
    use super::Real;
    use proptest::prelude::*;

    /// The largest finite magnitude, value by value as a float maximum.
    fn reference<R: Real>(values: &[R]) -> R {
        values
            .iter()
            .map(|x| x.abs())
            .filter(|a| a.f64().is_finite())
            .fold(R::ZERO, |m, a| if a > m { a } else { m })
    }

    /// Values of every kind the bits order has to place: both zeros, subnormals, the
    /// extremes, the infinities and NaNs of either sign.
    fn special<R: Real>() -> Vec<R> {
        [
            0.0,
            -0.0,
            1e-320,
            -1e-310,
            1e-45,
            -3e-39,
            f64::MAX,
            -f64::MAX,
            3.4e38,
            -3.4e38,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            -f64::NAN,
        ]
        .into_iter()
        .map(R::of)
        .collect()
    }

    #[test]
    fn largest_finite_magnitude_skips_infinities_and_nans() {
        fn check<R: Real>() {
            let s = special::<R>();
            assert_eq!(R::largest_finite_magnitude(&[]).f64(), 0.0);
            for i in 0..s.len() {
                for j in 0..s.len() {
                    let v = [s[i], s[j], R::of(-2.5)];
                    let (got, want) = (R::largest_finite_magnitude(&v), reference(&v));
                    assert_eq!(got.f64().to_bits(), want.f64().to_bits(), "{v:?}");
                }
            }
        }
        check::<f64>();
        check::<f32>();
    }

    proptest! {
        #[test]
        fn largest_finite_magnitude_is_the_float_maximum(
            bits in proptest::collection::vec(any::<u64>(), 0..40)
        ) {
            // Any bits: every finite value, subnormal, infinity and NaN pattern.
            let wide: Vec<f64> = bits.iter().map(|&b| f64::from_bits(b)).collect();
            let narrow: Vec<f32> = bits.iter().map(|&b| f32::from_bits(b as u32)).collect();
            prop_assert_eq!(
                f64::largest_finite_magnitude(&wide).to_bits(),
                reference(&wide).to_bits()
            );
            prop_assert_eq!(
                f32::largest_finite_magnitude(&narrow).to_bits(),
                reference(&narrow).to_bits()
            );
        }
    }
}
