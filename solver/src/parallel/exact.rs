//! Exact sums of f64 values: a fixed-point accumulator wide enough for every finite double, so
//! that a sum does not depend on the order of its terms, nor on how they are split between
//! threads or ranks. Partial accumulators add up limb by limb as integers (associative), which
//! MPI does with its plain integer sum: one small all-reduce per total, whatever the number of
//! ranks or blocks, instead of gathering every block's partial sum to add them in one order.
//!
//! The total is rounded once, to nearest (ties to even), so it is the correctly rounded sum of
//! the terms: for two terms, exactly IEEE `a + b`.

/// Bits per limb: limbs hold values below 2^32 once normalised, so 2^31 accumulators (or
/// terms) can be added into an `i64` limb before it could overflow.
const LIMB_BITS: u32 = 32;

/// Bit 0 of the accumulator is 2^-1074, the smallest subnormal.
const BIAS: i32 = 1074;

/// Limbs: 1074 + 1024 bits of the doubles' range, 53 of the mantissa's reach, and headroom
/// for the carries of 2^31 terms at the top of the range (rounded up to whole limbs).
pub const LIMBS: usize = 69;

/// Integers per accumulator: the limbs, then the counts of NaN, +∞ and -∞ terms.
pub const WIDTH: usize = LIMBS + 3;

/// An exact sum of f64 values as integers ([`WIDTH`] of them, summed elementwise to merge).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExactSum {
    words: [i64; WIDTH],
}

impl Default for ExactSum {
    fn default() -> Self {
        ExactSum { words: [0; WIDTH] }
    }
}

impl ExactSum {
    /// Adds `x` exactly. NaN and infinite terms are counted, and make the total NaN or ±∞ as
    /// IEEE addition would.
    pub fn add(&mut self, x: f64) {
        if !x.is_finite() {
            let k = if x.is_nan() {
                0
            } else if x > 0.0 {
                1
            } else {
                2
            };
            self.words[LIMBS + k] += 1;
            return;
        }
        if x == 0.0 {
            return;
        }
        let bits = x.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as i32;
        let fraction = bits & ((1 << 52) - 1);
        // x = m · 2^(e - 1074) with m below 2^53 and e ≥ 0.
        let (m, e) = if exponent == 0 {
            (fraction, 0)
        } else {
            (fraction | (1 << 52), exponent - 1)
        };
        let at = e as u32;
        let limb = (at / LIMB_BITS) as usize;
        let wide = u128::from(m) << (at % LIMB_BITS);
        let sign = if x < 0.0 { -1 } else { 1 };
        // The top exponent puts bits up to 2^2098, limb 65 of 69.
        debug_assert!(limb + 2 < LIMBS);
        for k in 0..3 {
            let part = ((wide >> (LIMB_BITS * k as u32)) & 0xffff_ffff) as i64;
            self.words[limb + k] += sign * part;
        }
    }

    /// The accumulator whose integers are `words` (as [`ExactSum::words_mut`] gives them,
    /// or their elementwise sum over several accumulators).
    pub fn from_words(words: [i64; WIDTH]) -> Self {
        ExactSum { words }
    }

    /// The integers to add elementwise across ranks (normalised first, so that up to 2^31
    /// accumulators add without overflow).
    pub fn words_mut(&mut self) -> &mut [i64; WIDTH] {
        self.normalise();
        &mut self.words
    }

    /// Carries every limb's excess into the next one: limbs below the top in `0..2^32`, the
    /// top limb carrying the sign.
    fn normalise(&mut self) {
        for i in 0..LIMBS - 1 {
            let carry = self.words[i] >> LIMB_BITS;
            self.words[i] -= carry << LIMB_BITS;
            self.words[i + 1] += carry;
        }
    }

    /// The sum, rounded to the nearest double (ties to even; a zero sum is +0); NaN when a term was NaN or
    /// both infinities occurred, ±∞ when one did or the sum is beyond the doubles.
    pub fn value(&self) -> f64 {
        let [nan, pos, neg] = [
            self.words[LIMBS],
            self.words[LIMBS + 1],
            self.words[LIMBS + 2],
        ];
        if nan > 0 || (pos > 0 && neg > 0) {
            return f64::NAN;
        }
        if pos > 0 {
            return f64::INFINITY;
        }
        if neg > 0 {
            return f64::NEG_INFINITY;
        }
        let mut s = *self;
        s.normalise();
        let negative = s.words[LIMBS - 1] < 0;
        if negative {
            // The magnitude: every limb negated, then normalised again.
            for w in &mut s.words[..LIMBS] {
                *w = -*w;
            }
            s.normalise();
        }
        let limbs = &s.words[..LIMBS];
        let Some(top) = limbs.iter().rposition(|&w| w != 0) else {
            return 0.0;
        };
        // The top three limbs (at least 65 significant bits), the rest folded into a sticky
        // bit: one rounding of that to 53 bits is the rounding of the whole.
        let low = top.saturating_sub(2);
        let mut head: u128 = 0;
        for i in (low..=top).rev() {
            head = (head << LIMB_BITS) | limbs[i] as u128;
        }
        let sticky = limbs[..low].iter().any(|&w| w != 0);
        let shift = LIMB_BITS as i32 * low as i32 - BIAS;
        let magnitude = round_scaled(head, sticky, shift);
        if negative {
            -magnitude
        } else {
            magnitude
        }
    }
}

/// `(head + sticky·ε) · 2^shift` rounded once to the nearest double, ties to even (`head`
/// nonzero, below 2^96; ε a nonzero amount below head's last bit).
fn round_scaled(head: u128, sticky: bool, shift: i32) -> f64 {
    let bits = 128 - head.leading_zeros() as i32;
    // The value's binary exponent: 2^(top - 1) ≤ value < 2^top.
    let top = bits + shift;
    // Mantissa bits the result keeps: 53, fewer in the subnormal range (lowest bit 2^-1074).
    let keep = 53.min(top + BIAS).max(0);
    let drop = bits - keep;
    if drop <= 0 {
        // Exact: at most 53 bits (the sticky cannot be set, as head has 65 bits or more
        // whenever a lower limb is nonzero).
        return scale(head as f64, shift);
    }
    let kept = head >> drop;
    let rest = head & ((1u128 << drop) - 1);
    let half = 1u128 << (drop - 1);
    let up = rest > half || (rest == half && (sticky || kept & 1 == 1));
    let rounded = kept + u128::from(up);
    scale(rounded as f64, shift + drop)
}

/// `x · 2^k` for an integer-valued `x` of at most 54 bits: exact, or ±∞ beyond the range.
fn scale(x: f64, k: i32) -> f64 {
    let mut x = x;
    let mut k = k;
    // Steps the factor stays a normal double for; the result is exact unless it overflows
    // (the rounding above already put it on the grid of the subnormals where it falls there).
    while k > 1000 {
        x *= 2f64.powi(1000);
        k -= 1000;
    }
    while k < -1000 {
        x *= 2f64.powi(-1000);
        k += 1000;
    }
    x * 2f64.powi(k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn exact(xs: &[f64]) -> f64 {
        let mut s = ExactSum::default();
        for &x in xs {
            s.add(x);
        }
        s.value()
    }

    #[test]
    fn sums_that_floating_point_loses_are_kept() {
        assert_eq!(exact(&[1e20, 1.0, -1e20]), 1.0);
        // The doubles nearest 0.1, 0.2, 0.3 and 0.6 add up to exactly 2^-55 (Python's
        // fractions agree); left to right in floating point they give 2^-53.
        assert_eq!(exact(&[0.1, 0.2, 0.3, -0.6]), 2f64.powi(-55));
        assert_eq!(0.1f64 + 0.2 + 0.3 - 0.6, 2f64.powi(-53));
        assert_eq!(exact(&[]), 0.0);
        assert_eq!(exact(&[-3.5]), -3.5);
        assert_eq!(exact(&[f64::MAX, f64::MAX]), f64::INFINITY);
        assert_eq!(exact(&[f64::MAX, f64::MAX, -f64::MAX]), f64::MAX);
        assert_eq!(exact(&[5e-324, 5e-324]), 1e-323);
        assert!(exact(&[1.0, f64::NAN]).is_nan());
        assert!(exact(&[f64::INFINITY, f64::NEG_INFINITY]).is_nan());
        assert_eq!(exact(&[f64::NEG_INFINITY, 1.0]), f64::NEG_INFINITY);
    }

    #[test]
    fn ties_round_to_even() {
        // 1 + 2^-53 is halfway between 1 and its successor: ties to 1 (even).
        assert_eq!(exact(&[1.0, 2f64.powi(-53)]), 1.0);
        // ... and just above halfway rounds up.
        assert_eq!(
            exact(&[1.0, 2f64.powi(-53), 2f64.powi(-200)]),
            1.0 + f64::EPSILON
        );
        // The successor of 1 plus half an ulp ties to the even 1 + 2ε.
        assert_eq!(
            exact(&[1.0 + f64::EPSILON, 2f64.powi(-53)]),
            1.0 + 2.0 * f64::EPSILON
        );
    }

    fn finite() -> impl Strategy<Value = f64> {
        prop_oneof![
            -1e6f64..1e6,
            // Any finite double, up to ±MAX (sums may overflow to ±∞, as IEEE's do).
            any::<f64>().prop_filter("finite", |x| x.is_finite()),
            (-1e-300f64..1e-300),
            // Subnormals: exponent field 0.
            (any::<bool>(), 1u64..(1 << 52)).prop_map(|(neg, m)| {
                let x = f64::from_bits(m);
                if neg {
                    -x
                } else {
                    x
                }
            }),
            // Near the top of the range.
            (0.5f64..1.0).prop_map(|f| f * f64::MAX),
        ]
    }

    proptest! {
        #[test]
        fn two_terms_give_ieee_addition(a in finite(), b in finite()) {
            // Bit for bit, but for the sign of a zero sum (always +0 here).
            let want = a + b;
            let want = if want == 0.0 { 0.0 } else { want };
            prop_assert_eq!(exact(&[a, b]).to_bits(), want.to_bits());
        }

        #[test]
        fn order_and_splitting_do_not_change_the_sum(
            xs in proptest::collection::vec(finite(), 0..60),
            cut in 0usize..60,
            seed in any::<u64>(),
        ) {
            let whole = exact(&xs);
            let mut shuffled = xs.clone();
            let mut s = seed | 1;
            for i in (1..shuffled.len()).rev() {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                shuffled.swap(i, (s % (i as u64 + 1)) as usize);
            }
            prop_assert_eq!(exact(&shuffled).to_bits(), whole.to_bits());
            // Two accumulators, merged as ranks are.
            let cut = cut.min(xs.len());
            let (mut a, mut b) = (ExactSum::default(), ExactSum::default());
            xs[..cut].iter().for_each(|&x| a.add(x));
            xs[cut..].iter().for_each(|&x| b.add(x));
            let (wa, wb) = (*a.words_mut(), *b.words_mut());
            let mut merged = ExactSum::default();
            for (m, (x, y)) in merged.words.iter_mut().zip(wa.iter().zip(&wb)) {
                *m = x + y;
            }
            prop_assert_eq!(merged.value().to_bits(), whole.to_bits());
        }

        #[test]
        fn a_sum_and_its_negation_cancel(xs in proptest::collection::vec(finite(), 1..30)) {
            let mut both = xs.clone();
            both.extend(xs.iter().map(|x| -x));
            prop_assert_eq!(exact(&both), 0.0);
            let s = exact(&xs);
            let n = exact(&xs.iter().map(|x| -x).collect::<Vec<_>>());
            prop_assert!(s == -n && (s == 0.0 || s.to_bits() == (-n).to_bits()));
        }
    }
}
